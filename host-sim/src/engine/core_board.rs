//! The core's board on the host ([`CoreBoard`]): the firmware's logic, unchanged, booted from a
//! scene's image, its output stage on the simulated wires, one of the boards a
//! [`Loop`](crate::engine::closed_loop::Loop) runs against the plant.

use de_resonator::acquire::InputError;
use de_resonator::board::port::Extras;
use de_resonator::board::runner::AfterTick;
use de_resonator::board::runner::{self, Follow, Ticker};
use de_resonator::board::{self, Line, Lines, NoKeeper, ReplyLine};
use de_resonator::image::Image;
use de_resonator::wire::link::{Booted, Observed, Words};
use de_resonator::wire::stream::{self, Receiver, Record, Telemetry};
use de_resonator::{Controller, Dac8551, Event, Fault, Inputs, OutputStage};

use crate::engine::bench::{EnableLine, SimulatedDac, Wires};
use crate::engine::loop_board::{LoopBoard, Samples};

/// The core's board tick in host-sim's loops (`Loop::step` for `serve`, [`CoreBoard`] for
/// `run`): the firmware's tick ([`Ticker::tick`]), then its background job at once, as the
/// firmware's low-priority task runs it before the next tick (the next tick applies it).
pub fn core_tick(
    ticker: &mut Ticker,
    slot: &mut Option<Controller>,
    stage: &mut OutputStage<&SimulatedDac, &EnableLine>,
    inputs: Result<Inputs, InputError>,
) -> AfterTick {
    let done = *ticker.tick(inputs, slot, stage);
    if done.ticked.is_some_and(|t| t.job_wanted) {
        board::tick::run_job(|f| {
            if let Some(c) = slot.as_mut() {
                f(c);
            }
        });
    }
    done
}

/// The core's board on the host: booted from the scene's image, its output stage on the
/// simulated wires.
pub struct CoreBoard<'w> {
    slot: Option<Controller>,
    board: board::Board<'w, NoKeeper>,
    /// The last tick's readings, for `status`.
    readings: Inputs,
    /// The acquisition's stalls the reader recovered from (a stalled tick it read), for
    /// `status`, as the firmware counts them.
    stalls_recovered: u32,
    stage: OutputStage<&'w SimulatedDac, &'w EnableLine>,
    ticker: Ticker,
    booted: Booted,
    refusal: Option<String>,
    fault: Option<Fault>,
    wires: &'w Wires,
    /// The stream's state, and its frames through a receiver as a client's wire would take
    /// them.
    telemetry: Telemetry,
    receiver: Receiver,
    records: Vec<Record>,
}

impl<'w> CoreBoard<'w> {
    /// Boot the core's board from `image` (`Loop::image`), as the firmware does from flash.
    pub fn boot(image: &'w [u8], wires: &'w Wires) -> Self {
        let mut stage = OutputStage::new(Dac8551::new(&wires.bus), &wires.enable);
        let _ = stage.safe();
        let mut slot = None;
        let (board, _) = board::Board::boot(&mut slot, Image::parse(image), None::<NoKeeper>, None);
        let booted = Booted::of(board.booted());
        let refusal = board.refusal().map(str::to_string);
        CoreBoard {
            slot,
            board,
            readings: Inputs::NONE,
            stalls_recovered: 0,
            stage,
            ticker: Ticker::new(),
            booted,
            refusal,
            fault: None,
            wires,
            telemetry: Telemetry::default(),
            receiver: Receiver::default(),
            records: Vec::new(),
        }
    }
}

impl LoopBoard for CoreBoard<'_> {
    fn booted(&mut self) -> (Booted, Option<String>) {
        (self.booted, self.refusal.clone())
    }

    fn tick(
        &mut self,
        _: u64,
        inputs: Result<Inputs, InputError>,
        samples: Samples,
        _: &[u16],
    ) -> Result<(Observed, String), String> {
        if let (Samples::Codes { stall: Some(_) }, Ok(_)) = (samples, &inputs) {
            self.stalls_recovered += 1;
        }
        let done = core_tick(&mut self.ticker, &mut self.slot, &mut self.stage, inputs);
        self.readings = done.readings;
        // The stream's record after the tick and its job, as the firmware's idle loop takes it.
        if let Some(record) = self.telemetry.record(
            done.tick,
            !self.stage.is_safe(),
            self.slot.as_ref(),
            &self.readings,
        ) {
            let mut frame = [0u8; stream::FRAME_BYTES];
            let n = record.frame(&mut frame);
            for &byte in &frame[..n] {
                if let Some(Ok(r)) = self.receiver.push(byte) {
                    self.records.push(r);
                }
            }
        }
        let event = done.event();
        self.fault = match event {
            Some(Event::Fault(fault)) => Some(fault),
            _ => None,
        };
        let (code, on) = self.wires.bus.last.get();
        let seen = Observed::of(
            code,
            on,
            self.wires.enable.high.get(),
            self.slot.as_ref(),
            event.as_ref(),
        );
        let words = event.map_or(String::new(), |e| Words(&e).to_string());
        Ok((seen, words))
    }

    fn fault(&self) -> Option<Fault> {
        self.fault
    }

    fn command(&mut self, line: &str) -> Result<String, String> {
        let parsed = command_line(line)?;
        let extras = Extras {
            readings: self.readings,
            stream_port: true,
            stalls_recovered: self.stalls_recovered,
            ..Extras::default()
        };
        let mut reply = ReplyLine::new();
        let then = self
            .board
            .serve(&parsed, &mut &mut self.slot, &extras, &mut reply);
        if runner::follow(then, &mut self.telemetry) == Follow::Reset {
            return Err(format!(
                "`{line}`: a scene cannot script a reset (the run would start again)"
            ));
        }
        Ok(reply.to_string())
    }

    fn records(&mut self) -> Result<(Vec<Record>, Receiver), String> {
        Ok((std::mem::take(&mut self.records), self.receiver.clone()))
    }
}

/// A scripted line as the command port's reader makes it.
pub(crate) fn command_line(line: &str) -> Result<Line, String> {
    let mut lines = Lines::default();
    line.bytes()
        .chain(std::iter::once(b'\n'))
        .filter_map(|b| lines.push(b).line)
        .last()
        .ok_or_else(|| format!("`{line}`: not a command line"))
}
