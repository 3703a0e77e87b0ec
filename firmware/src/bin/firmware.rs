//! The firmware: an RTIC 2 application. At power-up it reads the configuration image (flash
//! sector 11), runs every boot check of the core's controller on it, and drives the image's
//! default plan; or, if anything is wrong, keeps the amplifier disabled at 0 V and says why on
//! the command port (`# refused …`) and in the log.
//!
//! Tasks, highest priority first:
//! - `tick` (SysTick, at the settings' `tick_hz`): the block of ADC codes since the last tick
//!   through the image's front end (the core's `acquire`), then one tick of the core's board
//!   (the controller, its DAC frame on SPI1, the enable line); wakes `job` when a job waits;
//! - `rx` (USART2): bytes into request lines, queued to `command`; `adc` (DMA2 stream 0,
//!   silicon): each full buffer of ADC codes added to the tick's block; `adc` and
//!   `adc_overrun` (the ADC's interrupt): a DMA transfer error or an ADC overrun re-armed, the
//!   stall said to the block (the core's reader recovers or faults);
//! - `command` and `job` (software, lowest): each request answered on USART2 by the core's
//!   board; the long work (a new plan's checks, a boot, a trim's solve, tracking's slope)
//!   runs here, preempted by the tick;
//! - `idle`: the telemetry stream (`stream <hz>`): a record taken when one is due, under the
//!   locks of what the tick left (nothing added to the tick), framed and sent on USART1.
//!
//! The link build (`link`, QEMU, for `host-sim run --firmware`): no SysTick; `link_samples`
//! (USART3, host-sim's bell) adds each tick's samples frame to the block and pends the tick;
//! `link_reply` (software, lowest, in place of `job`) runs the tick's job, then sends the
//! tick's output back (`de_resonator_firmware::link`).
//!
//! What the board decides (the boot and its fallbacks, the replies, when the amplifier is on)
//! is the core's `board`, tested on the host; this file wires it to the peripherals.
#![no_std]
#![no_main]

use de_resonator_firmware as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [EXTI0])]
mod app {
    use core::fmt::Write as _;
    use core::mem::MaybeUninit;

    use rtic::mutex_prelude::*;

    use de_resonator::acquire::{Block, FrontEnd, Reader, BUFFER_CODES};
    use de_resonator::board::port::{Extras, TickClock};
    use de_resonator::board::runner::{self, Follow, Logged, Ticker};
    use de_resonator::board::watchdog::CheckIn;
    use de_resonator::board::FlashKeeper;
    use de_resonator::board::{self, Line, Lines, ReplyLine};
    #[cfg(feature = "link")]
    use de_resonator::wire::link::{Booted, Kind, Observed};
    use de_resonator::wire::stream::{Telemetry, FRAME_BYTES};
    #[cfg(not(feature = "link"))]
    use de_resonator::Decimal;
    use de_resonator::{Controller, Dac8551, Event, Inputs, OutputStage};
    #[cfg(not(feature = "qemu"))]
    use de_resonator_firmware::analog::Acquisition;
    #[cfg(not(feature = "qemu"))]
    use de_resonator_firmware::analog::Parts;
    use de_resonator_firmware::chip::{self, Chip, StagePin, StageSpi};
    use de_resonator_firmware::link::{LinkIn, LinkOut, TickDone, REPLIES};
    // The stand-ins QEMU's builds take for what it does not emulate (`qemu`), by name.
    #[cfg(feature = "qemu")]
    use de_resonator_firmware::qemu::{self, analog::Acquisition, dog::Dog, stream::StreamPort};
    use de_resonator_firmware::runtime::{self, ResetCause};
    #[cfg(feature = "model-sensor")]
    use de_resonator_firmware::sensor::ModelSensor as Sensors;
    #[cfg(not(feature = "model-sensor"))]
    use de_resonator_firmware::sensor::NoSensor as Sensors;
    use de_resonator_firmware::sensor::Sensor;
    use de_resonator_firmware::storage::SettingsFlash;
    #[cfg(not(feature = "qemu"))]
    use de_resonator_firmware::stream::StreamPort;
    use de_resonator_firmware::switches::TickSwitches;
    #[cfg(not(feature = "qemu"))]
    use de_resonator_firmware::watchdog::Dog;
    use de_resonator_firmware::watchdog::{self, Watchdog as _};
    use de_resonator_firmware::{config, stack, storage};
    use embedded_hal_nb::serial::Read as _;
    use rtic_sync::channel::{Receiver, Sender, TrySendError};
    use rtic_sync::make_channel;
    use stm32f4xx_hal::pac::USART2;
    use stm32f4xx_hal::serial::RxListen as _;
    use stm32f4xx_hal::serial::{Rx, Tx};

    /// Request lines queued from the receive interrupt to the command task.
    const QUEUE: usize = 4;
    /// The echo's bytes waiting for the command task (a pasted line's, a backspace's three).
    const ECHO_BYTES: usize = 128;

    #[shared]
    struct Shared {
        /// `None`: nothing is driven (no usable image, or the boot refused). A static of
        /// init's, where the boot builds the controller (3.6 KB: not a resource moved out of
        /// `init`'s frame; its one copy on the stack is the boot's, `Checked::build_in`).
        controller: &'static mut Option<Controller>,
        /// The longest tick so far, core cycles.
        tick_cycles_max: u32,
        /// QEMU builds: the independent clock (TIM2, µs) at the last tick's start, with that
        /// tick's count since power-up.
        last_tick: TickClock,
        /// Whether the output stage is off (DAC powered down, enable low), as the tick left it.
        output_off: bool,
        /// Set by the heartbeat task (the low-priority tasks are not stuck), cleared by the tick.
        checked_in: bool,
        /// The ADC's codes since the last tick: filled by `adc` (silicon) or the tick's
        /// stand-in (QEMU), taken by the tick.
        block: Block,
        /// The last tick: its number since boot and its readings, in units (`status` and
        /// the telemetry stream's records).
        latest: Latest,
        /// The telemetry stream's rate and count (`stream <hz>`), its records taken by `idle`
        /// (by `link_reply` in the link build).
        telemetry: Telemetry,
        /// The telemetry stream's port (`None`: the clock in use gives no divider for it).
        stream_port: Option<StreamPort>,
        /// The fault the tick saw latch, until the command task writes it to the fault log.
        logged: Option<Logged>,
        /// Silicon's ADC, timer and DMA (none with no channel fitted, none under QEMU): the
        /// DMA's and the ADC's interrupts serve it.
        acquisition: Option<Acquisition>,
    }

    /// What the command task is given: a request line (from `rx`), or a wake-up for the
    /// fault the tick left in `logged` (flash work, outside the tick; should the queue be
    /// full, the task finds it at its next line).
    pub enum Work {
        /// A request, and what ends its reply on this connection (`Lines::reply_end`).
        Line(Line, &'static str),
        /// Echo bytes are waiting (`echo_in`): send them.
        Echo,
        Log,
    }

    /// What the tick leaves for the tasks below it.
    #[derive(Clone, Copy)]
    pub struct Latest {
        /// Ticks done since boot: the last one's number is one less (none yet: 0).
        ticks: u32,
        readings: Inputs,
        /// The acquisition's stalls recovered from (the reader's count).
        stalls_recovered: u32,
    }

    #[local]
    struct Local {
        stage: OutputStage<StageSpi, StagePin>,
        sensor: Sensors,
        /// The image's analog front end (none fitted without an image), ready for the tick.
        reader: Reader,
        serial_rx: Rx<USART2>,
        lines: Lines,
        /// A line that found the queue full, kept until the command task makes room.
        held: Option<(Line, &'static str)>,
        /// What a person at a terminal sees as they type: the receiver's bytes to echo, sent
        /// by the command task (before the reply of the line they belong to).
        echo_in: heapless::spsc::Producer<'static, u8, ECHO_BYTES>,
        echo_out: heapless::spsc::Consumer<'static, u8, ECHO_BYTES>,
        to_command: Sender<'static, Work, QUEUE>,
        /// The tick's end of the command task's queue: a fault to log.
        to_log: Sender<'static, Work, QUEUE>,
        from_rx: Receiver<'static, Work, QUEUE>,
        tx: Tx<USART2>,
        /// The core's board: the image, the settings, the refusal, the command port's answers.
        board: board::Board<'static, FlashKeeper<SettingsFlash>>,
        /// Idle without `wfi` (QEMU runs that measure the tick rate).
        busy_idle: bool,
        /// QEMU's test switches in the tick (none on silicon).
        switches: TickSwitches,
        dog: Dog,
        /// The low-priority tasks' check-ins, counted in ticks (when the dog is fed).
        check_in: CheckIn,
        /// The link build: host-sim's samples in (a pipe, rung on USART3), the tick's output
        /// out (a pipe).
        #[cfg(feature = "link")]
        link_in: LinkIn,
        #[cfg(feature = "link")]
        link_out: LinkOut,
        /// The link build: each tick's outcome to the reply task.
        #[cfg(feature = "link")]
        to_reply: Sender<'static, TickDone, REPLIES>,
        #[cfg(feature = "link")]
        from_tick: Receiver<'static, TickDone, REPLIES>,
    }

    // The slot uninitialized (in .bss, not a 3 KB `None` copied from flash to `.data`).
    #[init(local = [
        echo_bytes: heapless::spsc::Queue<u8, ECHO_BYTES> = heapless::spsc::Queue::new(),
        slot: MaybeUninit<Option<Controller>> = MaybeUninit::uninit(),
        buffers: [[u16; BUFFER_CODES]; 3] = [[0; BUFFER_CODES]; 3],
        frames: [[u8; FRAME_BYTES]; 2] = [[0; FRAME_BYTES]; 2],
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        bring_up(cx)
    }

    /// `init`'s work, in a frame of its own that is gone before any task runs: RTIC enables
    /// the interrupts inside the frame `init` is inlined into, so a request that arrived
    /// during the boot is served on top of that frame (the boot's 8.7 KB was once under a
    /// `start`'s 17.8 KB: 39.8 KB of RAM in all, docs/firmware.md's stack).
    #[inline(never)]
    fn bring_up(cx: init::Context) -> (Shared, Local) {
        #[cfg(feature = "qemu")]
        qemu::clock::start(&cx.device.TIM2);
        // The link paces the tick at the simulation's speed, not virtual time's: no stand-in
        // watchdog clock to bite between ticks the host has not sent yet.
        #[cfg(all(feature = "qemu", not(feature = "link")))]
        Dog::start_clock(&cx.device.TIM3);
        stack::paint();
        let mut core = cx.core;
        let mut chip = Chip::new(cx.device);
        let mut tx = chip.tx;
        let (dac, enable) = chip::stage_wires(chip.dac, chip.enable);
        let mut stage = OutputStage::new(Dac8551::new(dac), enable);
        // 0 V, DAC powered down, amplifier disabled, until the checks pass.
        let _ = stage.safe();
        #[cfg(feature = "defmt")]
        if let Some(e) = chip.clock_error {
            defmt::warn!("clock: {}; running on the 16 MHz HSI", e);
        }
        let cause = runtime::take_reset_cause();
        if let Some(cause) = cause {
            let _ = runner::write_reset(cause, &mut tx, "\n");
        }
        let controller = cx.local.slot.write(None);
        let (mut board, mut started) = board::Board::boot(
            controller,
            config::image(),
            storage::open(chip.flash),
            cause,
        );
        #[cfg(feature = "defmt")]
        if let Some(warning) = &started.warning {
            defmt::warn!("{=str}", warning.as_str());
        }
        let notice = &mut started.notice;
        let tick_hz = board.tick_hz(controller);
        // The image's front end at the tick rate booted with: `Board::boot` has refused one
        // the board cannot run (its image then gone: none here), so this gives the scans a
        // tick; the acquisition started before the tick (the tick's reader gives the first
        // buffers a few ticks).
        let front_end = board.image().map_or(FrontEnd::NONE, |i| i.front_end);
        let scans_per_tick = match front_end.check(tick_hz) {
            Ok(scans) => scans,
            Err(e) => {
                board.refuse(controller, &e, notice);
                0
            }
        };
        // On the HSI fallback the ADC converts about 4 times slower than the image assumed.
        #[cfg(not(feature = "qemu"))]
        if let Err(e) =
            front_end.check_adc_clock(de_resonator_firmware::analog::adc_clock_hz(&chip.rcc))
        {
            board.refuse(controller, &e, notice);
        }
        #[cfg(not(feature = "qemu"))]
        let acquisition = {
            let analog = chip.analog;
            let parts = Parts {
                adc1: analog.adc1,
                dma: analog.dma,
                tim2: analog.tim2,
                pins: analog.pins,
                buffers: cx.local.buffers,
            };
            let started = Acquisition::start(parts, &mut chip.rcc, &front_end, scans_per_tick);
            if started.is_none() && scans_per_tick > 0 {
                board.refuse(controller, &"the ADC's acquisition did not start", notice);
            }
            started
        };
        #[cfg(feature = "qemu")]
        let acquisition = {
            let _ = (&mut chip.rcc, cx.local.buffers);
            None
        };
        #[cfg(not(feature = "qemu"))]
        let stream_port = chip
            .stream_tx
            .map(|tx| StreamPort::new(chip.stream_dma, tx, cx.local.frames));
        #[cfg(feature = "qemu")]
        let stream_port = {
            let _ = cx.local.frames;
            chip.stream_tx.map(StreamPort::new)
        };
        // The link build's tick is pended by each samples frame, not SysTick's count.
        #[cfg(feature = "link")]
        let _ = &mut core;
        #[cfg(not(feature = "link"))]
        if board.image().is_some()
            && chip::start_tick(&mut core.SYST, chip.core_hz, tick_hz).is_none()
        {
            // The controller's own checks bound tick_hz; this is the timer's 24-bit reach.
            let why = Decimal(tick_hz);
            board.refuse(
                controller,
                &format_args!("tick_hz = {why} is beyond SysTick's reach"),
                notice,
            );
        }
        #[cfg(feature = "defmt")]
        if controller.is_some() {
            defmt::info!("{=str}", notice.as_str());
        } else {
            defmt::error!("{=str}", notice.as_str());
        }
        let _ = started.write_banner(&mut tx, "\n");
        #[cfg(feature = "link")]
        let (link_in, link_out) = {
            let link_in = LinkIn::open(chip.link, front_end);
            let mut out = LinkOut::open();
            let booted = Booted::of(board.booted());
            let refusal = board.refusal().unwrap_or("");
            out.send(Kind::Boot, 0, |p| booted.write(refusal, p));
            (link_in, out)
        };
        let (to_command, from_rx) = make_channel!(Work, QUEUE);
        let to_log = to_command.clone();
        let (echo_in, echo_out) = cx.local.echo_bytes.split();
        if command::spawn().is_err() {
            de_resonator_firmware::exit(104);
        }
        #[cfg(feature = "link")]
        let (to_reply, from_tick) = make_channel!(TickDone, REPLIES);
        #[cfg(feature = "link")]
        if link_reply::spawn().is_err() {
            de_resonator_firmware::exit(104);
        }
        (
            Shared {
                controller,
                tick_cycles_max: 0,
                last_tick: TickClock::default(),
                output_off: true,
                checked_in: true,
                block: Block::EMPTY,
                latest: Latest {
                    ticks: 0,
                    readings: Inputs::NONE,
                    stalls_recovered: 0,
                },
                telemetry: Telemetry::default(),
                stream_port,
                logged: None,
                acquisition,
            },
            Local {
                stage,
                #[cfg(not(feature = "model-sensor"))]
                sensor: Sensors,
                #[cfg(feature = "model-sensor")]
                sensor: Sensors::new(
                    board.image().map(|i| i.params),
                    front_end,
                    scans_per_tick,
                    tick_hz,
                )
                .failing_after(chip::asked("sensor-fails").then_some(2.0 * tick_hz)),
                reader: Reader::new(front_end, scans_per_tick),
                serial_rx: chip.rx,
                lines: Lines::default(),
                held: None,
                echo_in,
                echo_out,
                to_command,
                to_log,
                from_rx,
                tx,
                board,
                busy_idle: chip::asked("busy-idle"),
                switches: TickSwitches::asked(tick_hz),
                dog: Dog::new(chip.iwdg, &chip.dbgmcu),
                check_in: CheckIn::new(tick_hz),
                #[cfg(feature = "link")]
                link_in,
                #[cfg(feature = "link")]
                link_out,
                #[cfg(feature = "link")]
                to_reply,
                #[cfg(feature = "link")]
                from_tick,
            },
        )
    }

    /// Silicon sleeps until the next interrupt (an explicit `wfi`: RTIC's default
    /// SLEEPONEXIT idle runs about 40 times slower under QEMU, QEMU-STM32F405.md §3). Under
    /// QEMU's `-icount sleep=off` a `wfi` loses every other SysTick period (measured against
    /// TIM2: BENCHMARKS.md); a QEMU run started with the semihosting argument `busy-idle`
    /// idles busy instead, so that its virtual time is its instruction count, exactly.
    #[idle(shared = [controller, latest, output_off, telemetry, stream_port], local = [busy_idle, frame: [u8; FRAME_BYTES] = [0; FRAME_BYTES]])]
    fn idle(mut cx: idle::Context) -> ! {
        let busy = *cx.local.busy_idle;
        #[cfg(feature = "link")]
        let _ = (&mut cx.shared, cx.local.frame);
        loop {
            // The telemetry stream: a record when one is due (the link build takes its own
            // after each tick's job: `link_reply`).
            #[cfg(not(feature = "link"))]
            stream(
                (&mut cx.shared.telemetry, &mut cx.shared.latest),
                (&mut cx.shared.controller, &mut cx.shared.output_off),
                &mut cx.shared.stream_port,
                cx.local.frame,
            );
            if busy {
                cortex_m::asm::nop();
            } else {
                cortex_m::asm::wfi();
            }
        }
    }

    /// The telemetry stream's record of the last tick done, if one is due: taken under the
    /// locks of what the tick left (its state after its last run, whole; none before the first
    /// tick), then framed outside them and sent on the stream's port, if the board has one.
    fn stream(
        (telemetry, latest): (
            &mut impl rtic::Mutex<T = Telemetry>,
            &mut impl rtic::Mutex<T = Latest>,
        ),
        (controller, output_off): (
            &mut impl rtic::Mutex<T = &'static mut Option<Controller>>,
            &mut impl rtic::Mutex<T = bool>,
        ),
        port: &mut impl rtic::Mutex<T = Option<StreamPort>>,
        frame: &mut [u8; FRAME_BYTES],
    ) {
        // Whether one is due, under the stream's own lock (below the tick's: the tick never
        // waits for a pass with none due); then the record under one lock with the tick's
        // state (a short wait for the tick, the record's, none of its work).
        let Some(last) = latest.lock(|l| l.ticks.checked_sub(1)) else {
            return;
        };
        if !telemetry.lock(|t| t.is_due(last)) {
            return;
        }
        let record = (telemetry, latest, controller, output_off).lock(|t, latest, c, off| {
            let last = latest.ticks.checked_sub(1)?;
            t.record(last, !*off, c.as_ref(), &latest.readings)
        });
        let Some(record) = record else {
            return;
        };
        let n = record.frame(frame);
        port.lock(|port| {
            if let Some(port) = port.as_mut() {
                let _ = port.send(frame.get(..n).unwrap_or(&[]));
            }
        });
    }

    /// One controller tick: its code to the DAC, the enable line held, the events logged.
    #[task(binds = SysTick, priority = 3, shared = [controller, tick_cycles_max, last_tick, output_off, checked_in, block, latest, logged], local = [stage, sensor, reader, dog, check_in, switches, to_log, ticker: Ticker = Ticker::new(), #[cfg(feature = "link")] to_reply])]
    fn tick(mut cx: tick::Context) {
        let switches = cx.local.switches;
        if let Some(clock) = switches.start() {
            cx.shared.last_tick.lock(|at| *at = clock);
        }
        let stage = cx.local.stage;
        let sensor = cx.local.sensor;
        let mut block = cx.shared.block.lock(Block::take);
        sensor.fill(&mut block);
        // The core's board tick (`count` counts this call): the block through the front end,
        // the controller's output through the stage, a fault's entry.
        let (ticker, reader) = (cx.local.ticker, cx.local.reader);
        cx.shared.controller.lock(|c| {
            ticker.tick_block(reader, &block, c, stage);
        });
        let done = ticker.last();
        let ticked = done.ticked;
        if let Some(t) = ticked {
            sensor.commanded(t.output.volts);
        }
        let stalls_recovered = reader.recovered();
        cx.shared.latest.lock(|l| {
            *l = Latest {
                ticks: done.tick.wrapping_add(1),
                readings: done.readings,
                stalls_recovered,
            }
        });
        let running = ticked.is_some();
        switches.after(running);
        let checked_in = cx.shared.checked_in.lock(|c| core::mem::replace(c, false));
        let feed = cx.local.check_in.tick(checked_in, running);
        let dog = cx.local.dog;
        if feed.start {
            dog.start(watchdog::TIMEOUT_MS);
        }
        if feed.heartbeat {
            let _ = heartbeat::spawn();
        }
        if feed.feed {
            dog.feed();
        }
        // The link build: the output back to host-sim once the job (if any) is done, as
        // host-sim's loop runs it between ticks.
        #[cfg(feature = "link")]
        let _ = cx.local.to_reply.try_send(TickDone {
            dac: stage.dac().bus().dac,
            enable: stage.enable_line().high,
            event: ticked.and_then(|t| t.output.event),
            job: ticked.is_some_and(|t| t.job_wanted),
        });
        if let Some(t) = ticked {
            #[cfg(not(feature = "link"))]
            if t.job_wanted {
                // Already queued or running: it takes the job when it runs.
                let _ = job::spawn();
            }
            if let Some(event) = t.output.event {
                log(event, t.ticks);
            }
        }
        // A fault into the fault log, written by the command task (flash work).
        if let Some(logged) = done.logged() {
            cx.shared.logged.lock(|l| *l = Some(logged));
            let _ = cx.local.to_log.try_send(Work::Log);
        }
        let off = stage.is_safe();
        cx.shared.output_off.lock(|o| *o = off);
        let cycles = chip::cycles_into_tick();
        cx.shared
            .tick_cycles_max
            .lock(|most| *most = (*most).max(cycles));
    }

    /// The link build: host-sim's samples into the tick's block; each tick's samples pend the
    /// tick.
    #[cfg(feature = "link")]
    #[task(binds = USART3, priority = 2, shared = [block], local = [link_in])]
    fn link_samples(mut cx: link_samples::Context) {
        let block = &mut cx.shared.block;
        if cx.local.link_in.read(&mut |add| block.lock(|b| add(b))) {
            cortex_m::peripheral::SCB::set_pendst();
        }
    }

    /// The link build: each tick's job run (as host-sim's loop runs it, before the next
    /// tick), then the tick's output to host-sim.
    #[cfg(feature = "link")]
    #[task(priority = 1, shared = [controller, latest, output_off, telemetry, stream_port], local = [link_out, from_tick, frame: [u8; FRAME_BYTES] = [0; FRAME_BYTES]])]
    async fn link_reply(mut cx: link_reply::Context) {
        let mut tick = 0u32;
        while let Ok(done) = cx.local.from_tick.recv().await {
            if done.job {
                board::tick::run_job(|f| {
                    cx.shared.controller.lock(|c| {
                        if let Some(c) = c.as_mut() {
                            f(c);
                        }
                    })
                });
            }
            // The stream's record after the tick and its job, as host-sim's loop takes the
            // core's: the same tick whatever host-sim's pace.
            stream(
                (&mut cx.shared.telemetry, &mut cx.shared.latest),
                (&mut cx.shared.controller, &mut cx.shared.output_off),
                &mut cx.shared.stream_port,
                cx.local.frame,
            );
            let ((dac_code, dac_on), enable) = (done.dac, done.enable);
            let event = done.event;
            let observed = cx
                .shared
                .controller
                .lock(|c| Observed::of(dac_code, dac_on, enable, c.as_ref(), event.as_ref()));
            cx.local
                .link_out
                .send(Kind::Output, tick, |p| observed.write(event.as_ref(), p));
            tick = tick.wrapping_add(1);
        }
    }

    /// A full buffer of ADC codes, or the DMA's transfer error (silicon): its scans, or the
    /// re-armed stall, into the tick's block.
    #[task(binds = DMA2_STREAM0, priority = 2, shared = [block, acquisition])]
    fn adc(cx: adc::Context) {
        serve_acquisition(cx.shared.acquisition, cx.shared.block);
    }

    /// The ADC's overrun (silicon): the acquisition re-armed, the stall into the tick's block.
    #[task(binds = ADC, priority = 2, shared = [block, acquisition])]
    fn adc_overrun(cx: adc_overrun::Context) {
        serve_acquisition(cx.shared.acquisition, cx.shared.block);
    }

    /// Either acquisition interrupt: the acquisition, if any, serves it into the block.
    fn serve_acquisition(
        acquisition: impl rtic::Mutex<T = Option<Acquisition>>,
        block: impl rtic::Mutex<T = Block>,
    ) {
        (acquisition, block).lock(|acquisition, block| {
            if let Some(acquisition) = acquisition.as_mut() {
                acquisition.on_interrupt(block);
            }
        });
    }

    /// QEMU's watchdog stand-in: its own clock, above the tick (a stuck tick starves it too).
    #[cfg(feature = "qemu")]
    #[task(binds = TIM3, priority = 4)]
    fn dog_clock(_cx: dog_clock::Context) {
        qemu::dog::bite_if_starved();
    }

    /// The low-priority tasks' check-in: it runs only when none of them holds the priority.
    #[task(priority = 1, shared = [checked_in])]
    async fn heartbeat(mut cx: heartbeat::Context) {
        cx.shared.checked_in.lock(|c| *c = true);
    }

    fn log(event: Event, ticks: u32) {
        #[cfg(feature = "defmt")]
        match event {
            Event::Fault(fault) => defmt::error!("tick {=u32}: {}, down to 0 V", ticks, fault),
            event => defmt::info!("tick {=u32}: {}", ticks, event),
        }
        let _ = (event, ticks);
    }

    /// Bytes into lines; a full queue holds the line and pauses reception until `command`
    /// makes room (it pends this interrupt). Paused, the byte that may already wait is kept
    /// (`stash`): reading it lowers the interrupt line, which QEMU's USART does not lower when
    /// RXNEIE is cleared; the rest wait in the USART (QEMU), or overrun and garble their line
    /// (silicon), which then gets its `err`.
    #[task(binds = USART2, priority = 2, local = [serial_rx, lines, held, stash: Option<u8> = None, to_command, echo_in])]
    fn rx(cx: rx::Context) {
        let rx = cx.local.serial_rx;
        let echo_in = cx.local.echo_in;
        let lines = cx.local.lines;
        let to_command = cx.local.to_command;
        let held = cx.local.held;
        let stash = cx.local.stash;
        if let Some((line, end)) = held.take() {
            if let Err(TrySendError::Full(Work::Line(line, end))) =
                to_command.try_send(Work::Line(line, end))
            {
                *held = Some((line, end));
                match rx.read() {
                    Ok(byte) if stash.is_none() => *stash = Some(byte),
                    Ok(_) | Err(nb::Error::Other(_)) => lines.lost(),
                    Err(nb::Error::WouldBlock) => {}
                }
                return;
            }
            rx.listen();
        }
        let mut next = stash.take().map(Ok);
        loop {
            match next.take().unwrap_or_else(|| rx.read()) {
                Ok(byte) => {
                    let pushed = lines.push(byte);
                    if pushed.echo != board::Echo::Nothing {
                        // Shown only: past the buffer's room a byte is not shown. The wake-up
                        // may find the queue full: the next line's drains it anyway.
                        pushed.echo.bytes(|b| {
                            let _ = echo_in.enqueue(b);
                        });
                        let _ = to_command.try_send(Work::Echo);
                    }
                    if let Some(line) = pushed.line {
                        let end = lines.reply_end();
                        if let Err(TrySendError::Full(Work::Line(line, end))) =
                            to_command.try_send(Work::Line(line, end))
                        {
                            *held = Some((line, end));
                            rx.unlisten();
                            return;
                        }
                    }
                }
                Err(nb::Error::WouldBlock) => return,
                Err(nb::Error::Other(_)) => lines.lost(),
            }
        }
    }

    /// The controller under the lock it shares with the tick.
    struct Locked<'a, M>(&'a mut M);

    impl<M: rtic::Mutex<T = &'static mut Option<Controller>>> board::Shared for Locked<'_, M> {
        fn with<R>(&mut self, f: impl FnOnce(&mut Option<Controller>) -> R) -> R {
            self.0.lock(|c| f(c))
        }
    }

    /// Each request answered, one reply line each.
    #[task(priority = 1, shared = [controller, tick_cycles_max, last_tick, output_off, latest, telemetry, logged, stream_port], local = [from_rx, tx, board, echo_out])]
    async fn command(mut cx: command::Context) {
        let mut reply = ReplyLine::new();
        while let Ok(work) = cx.local.from_rx.recv().await {
            // Room in the queue again: a paused receiver resumes.
            rtic::pend(stm32f4xx_hal::pac::Interrupt::USART2);
            // A fault the tick left, into the log (the flash's own policy: no erase while
            // running on the chip, `board::FlashKeeper::erase_stalls`).
            if let Some(logged) = cx.shared.logged.lock(Option::take) {
                let board = &mut *cx.local.board;
                let tick_hz = cx.shared.controller.lock(|c| board.tick_hz(c));
                let done = board.log(&logged, tick_hz);
                #[cfg(feature = "defmt")]
                if let Some(Err(e)) = done {
                    defmt::error!("the fault log: {}", e);
                }
                let _ = done;
            }
            // What was typed, shown before anything else (a line's reply after its echo).
            while let Some(b) = cx.local.echo_out.dequeue() {
                let _ = nb::block!(embedded_hal_nb::serial::Write::write(cx.local.tx, b));
            }
            let (line, end) = match work {
                Work::Line(line, end) => (line, end),
                Work::Echo | Work::Log => continue,
            };
            #[cfg(feature = "defmt")]
            if let Line::Text(bytes) = &line {
                defmt::info!("command: {=[u8]:a}", bytes);
            }
            let extras = Extras {
                // Under QEMU a tick after a `wfi` counts QEMU's wake-up: not cycles (the
                // tick's instructions are counted by `count`).
                #[cfg(feature = "qemu")]
                tick_cycles_max: None,
                #[cfg(not(feature = "qemu"))]
                tick_cycles_max: Some(cx.shared.tick_cycles_max.lock(|most| *most)),
                stack_bytes: stack::used(),
                #[cfg(feature = "qemu")]
                clock: Some(cx.shared.last_tick.lock(|at| *at)),
                #[cfg(not(feature = "qemu"))]
                clock: None,
                readings: cx.shared.latest.lock(|l| l.readings),
                stream_port: cx.shared.stream_port.lock(|p| p.is_some()),
                stalls_recovered: cx.shared.latest.lock(|l| l.stalls_recovered),
            };
            let mut controller = Locked(&mut cx.shared.controller);
            let then = cx
                .local
                .board
                .serve(&line, &mut controller, &extras, &mut reply);
            let _ = write!(cx.local.tx, "{reply}{end}");
            if cx.shared.telemetry.lock(|t| runner::follow(then, t)) == Follow::Reset {
                // The board took the controller out of its slot: the tick turns the output
                // off; then the restart.
                cx.shared.output_off.lock(|o| *o = false);
                for _ in 0..chip::RESET_WAIT_POLLS {
                    if cx.shared.output_off.lock(|o| *o) {
                        break;
                    }
                }
                let _ = nb::block!(embedded_hal_nb::serial::Write::flush(cx.local.tx));
                runtime::reset(ResetCause::Asked);
            }
        }
    }

    /// The tick's background job (a trim's solve, tracking's slope), outside the tick; its
    /// result back at the next tick.
    #[task(priority = 1, shared = [controller])]
    async fn job(mut cx: job::Context) {
        board::tick::run_job(|f| {
            cx.shared.controller.lock(|c| {
                if let Some(c) = c.as_mut() {
                    f(c);
                }
            })
        });
    }
}
