//! The dashboard's board side: one command-port session shared by the pages' requests and the
//! status poll (one request at a time, in order), the telemetry stream read into batches for
//! the pages, a recording kept on request, and what a page is told as it opens (`hello`).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use de_resonator::wire::reply::Reply;
use de_resonator::wire::stream::{Record, VERSION};
use de_resonator::Fault;
use serde::Serialize;
use serde_json::{json, Value};

use super::DashArgs;
use crate::cmd::record::{self, Counts};
use crate::command_port::{control, fields, gone, Session};
use crate::telemetry::{self, Source};

/// Requests and replies kept for a page that opens later.
const LOG_KEPT: usize = 200;
/// Events queued for a page before it is counted as too slow (its records dropped).
const PAGE_QUEUE: usize = 4096;
/// How often the stream's records go to the pages in one event.
const BATCH: Duration = Duration::from_millis(20);
/// How long the first request waits for a start-up line (a board already running says none).
const STARTUP_WAIT: Duration = Duration::from_secs(2);
/// The points of the tuning curve drawn.
const CURVE_POINTS: usize = 200;
/// The board's own lines kept for a page that opens later.
const NOTICES_KEPT: usize = 200;
/// The most records a recording keeps (16 min at 1 kHz): past them it stops, said.
const RECORDING_MAX: usize = 1_000_000;
/// The most fault entries read back for the page.
const FAULTS_SHOWN: usize = 8;

/// The columns of a record as the page gets it (a row: an array in this order).
pub const COLUMNS: [&str; 15] = [
    "sequence",
    "tick",
    "volts",
    "amplifier_volts",
    "max_volts",
    "stretch",
    "sensed_stretch",
    "sensed_sigma",
    "current_amps",
    "natural_hz",
    "quality_factor",
    "bias_volts",
    "phase",
    "fault",
    "enable",
];

/// One record for the page, in [`COLUMNS`]' order (NaN and nothing as `null`).
#[derive(Serialize)]
struct Row(
    u32,
    u32,
    f32,
    Option<f32>,
    f32,
    Option<f32>,
    Option<f32>,
    Option<f32>,
    Option<f32>,
    Option<f32>,
    Option<f32>,
    f32,
    &'static str,
    &'static str,
    u8,
);

impl Row {
    fn of(r: &Record) -> Self {
        Row(
            r.sequence,
            r.tick,
            r.volts,
            r.inputs.amplifier_volts,
            r.max_volts,
            r.inputs.stretch,
            r.sensed.map(|s| s.0),
            r.sensed.map(|s| s.1),
            r.inputs.current_amps,
            r.resonance.map(|t| t.0),
            r.resonance.map(|t| t.1),
            r.bias_volts,
            r.phase.map_or("none", |p| p.name()),
            r.fault.and_then(Fault::key_of).unwrap_or(""),
            u8::from(r.enabled),
        )
    }
}

/// The pages' event queues: each event goes to every open page.
#[derive(Default)]
struct Hub {
    pages: Mutex<Vec<SyncSender<Arc<str>>>>,
    /// Records a page could not take (its queue full).
    dropped: AtomicU64,
}

impl Hub {
    /// Send `data` as event `kind` to every page; a page gone is forgotten, one too slow has
    /// its `records` counted as dropped.
    fn publish(&self, kind: &str, data: &dyn std::fmt::Display, records: u64) {
        let event: Arc<str> = format!("event: {kind}\ndata: {data}\n\n").into();
        let mut pages = lock(&self.pages);
        pages.retain(|page| match page.try_send(event.clone()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.dropped.fetch_add(records, Ordering::Relaxed);
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }
}

/// A mutex's guard, also after a thread panicked holding it (the data is still whole).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Milliseconds since the Unix epoch, for the page's log.
fn now_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// A recording made from the page: the header as `console --record` writes it, the records.
struct Recording {
    header: Vec<String>,
    records: Vec<Record>,
    from: Counts,
}

/// One request for the board, and where its reply goes.
struct Job {
    request: String,
    reply: mpsc::Sender<Result<String, String>>,
}

/// The board's command port: one thread asks every request in the order they came (the
/// pages' and the poll's): a STOP clicked after a start reaches the board after it.
#[derive(Clone)]
struct Port(mpsc::Sender<Job>);

/// What a request is told while no connection to the board is open.
pub const NOT_CONNECTED: &str = "the board is not connected (lost; dash reconnects)";

impl Port {
    fn start(mut session: Session) -> Self {
        let (tx, rx) = mpsc::channel::<Job>();
        std::thread::spawn(move || {
            for job in rx {
                let _ = job.reply.send(session.ask(&job.request));
            }
        });
        Port(tx)
    }

    /// Ask `request` after every request before it; its reply.
    fn ask(&self, request: &str) -> Result<String, String> {
        let (tx, rx) = mpsc::channel();
        let job = Job {
            request: request.to_string(),
            reply: tx,
        };
        let gone = || "the board closed the connection".to_string();
        self.0.send(job).map_err(|_| gone())?;
        rx.recv().map_err(|_| gone())?
    }
}

/// The connection to the board as the pages are told it (event `board`).
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "state", rename_all = "snake_case")]
enum Link {
    /// Connected, the board answering.
    Up,
    /// Connected, but the last request went unanswered: its state is unknown.
    Silent { why: String },
    /// The connection is gone; dash tries again every `retry_seconds` (attempt `attempt`).
    Lost {
        why: String,
        since_ms: u64,
        attempt: u32,
        retry_seconds: f64,
    },
}

/// Who may change the board (event `control`): this dash's connection, or another one of
/// `serve`'s (a board's one port is always this one's).
#[derive(Clone, Debug, Serialize)]
struct Control {
    controls: bool,
    /// The connection that controls, when it is another.
    controller: Option<String>,
}

/// The longest wait between two attempts to reach a lost board.
const RETRY_MAX: Duration = Duration::from_secs(4);
/// The first wait after the board is lost.
const RETRY_FIRST: Duration = Duration::from_millis(250);

/// Everything the dashboard's threads share.
pub struct Shared {
    /// The board's command port while connected.
    port: Mutex<Option<Port>>,
    /// Where the board is, for reconnecting.
    board: crate::command_port::PortArgs,
    hub: Hub,
    /// What a page is told first: the board, its device's curve, its settings.
    hello: Mutex<Value>,
    log: Mutex<VecDeque<Value>>,
    status: Mutex<Value>,
    faults: Mutex<Value>,
    link_state: Mutex<Link>,
    control: Mutex<Control>,
    /// This dash took control: its stream is asked again (another connection's leaving
    /// stopped it).
    restart_stream: AtomicBool,
    /// Lines the board said on its own over the present connection.
    heard: AtomicU64,
    /// Which connection is the present one: a line an earlier one's reader still hands on
    /// is dropped.
    generation: AtomicU64,
    /// The newest `NOTICES_KEPT` lines the board said on its own.
    notices: Mutex<VecDeque<String>>,
    counts: Mutex<Counts>,
    recording: Mutex<Option<Recording>>,
    last_recording: Mutex<Option<Vec<u8>>>,
    requests: AtomicU64,
    /// Times the board was lost.
    losses: AtomicU64,
    stop: AtomicBool,
    stream: Option<Source>,
    stream_request: String,
    /// The `stream <hz>` reply (null without a stream).
    stream_reply: Mutex<Option<String>>,
    tick_hz: Mutex<f64>,
}

impl Shared {
    /// Connect to the board, wait for its start-up line (a board that starts as a client
    /// connects says it first), and learn what it runs. The first connection must succeed:
    /// a wrong port is said at once, not retried.
    pub fn connect(args: &DashArgs) -> Result<Arc<Self>, String> {
        let shared = Arc::new(Shared {
            port: Mutex::new(None),
            board: args.board.clone(),
            hub: Hub::default(),
            hello: Mutex::new(Value::Null),
            log: Mutex::new(VecDeque::new()),
            status: Mutex::new(Value::Null),
            faults: Mutex::new(Value::Null),
            link_state: Mutex::new(Link::Up),
            control: Mutex::new(Control {
                controls: true,
                controller: None,
            }),
            restart_stream: AtomicBool::new(false),
            heard: AtomicU64::new(0),
            generation: AtomicU64::new(0),
            notices: Mutex::new(VecDeque::new()),
            counts: Mutex::new(Counts::default()),
            recording: Mutex::new(None),
            last_recording: Mutex::new(None),
            requests: AtomicU64::new(0),
            losses: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            stream: args.stream.source(),
            stream_request: format!("stream {}", args.stream_hz),
            stream_reply: Mutex::new(None),
            tick_hz: Mutex::new(f64::NAN),
        });
        shared.open_board()?;
        Ok(shared)
    }

    /// Open the board's command port, wait for its start-up line, start from a clean line,
    /// and learn what it runs (the hello made anew).
    fn open_board(self: &Arc<Self>) -> Result<(), String> {
        *lock(&self.control) = Control {
            controls: true,
            controller: None,
        };
        self.heard.store(0, Ordering::Relaxed);
        let generation = self.generation.fetch_add(1, Ordering::Relaxed) + 1;
        // The reader thread holds the shared state weakly (it does not keep it alive).
        let weak = Arc::downgrade(self);
        let mut session = Session::open(&self.board, move |line| {
            if let Some(shared) = weak.upgrade() {
                if shared.generation.load(Ordering::Relaxed) == generation {
                    shared.heard.fetch_add(1, Ordering::Relaxed);
                    shared.notice(line);
                }
            }
        })?;
        let end = Instant::now() + STARTUP_WAIT;
        while Instant::now() < end && self.heard.load(Ordering::Relaxed) == 0 {
            std::thread::sleep(Duration::from_millis(20));
        }
        // A clean line first: a half line an earlier connection left is refused, not glued.
        session.clean_line()?;
        *lock(&self.port) = Some(Port::start(session));
        self.learn(&self.board.describe())
    }

    /// Ask the board, over the connection open now.
    fn ask(&self, request: &str) -> Result<String, String> {
        let port = lock(&self.port).clone();
        match port {
            Some(port) => port.ask(request),
            None => Err(NOT_CONNECTED.into()),
        }
    }

    /// Ask the board what it runs (`info`, `get`, `help` for each setting) and make the
    /// hello: the device's tuning curve from `info`'s device and `get`'s margin.
    fn learn(&self, board: &str) -> Result<(), String> {
        let info = self.ask_own("info")?;
        let get = self.ask_own("get")?;
        let info_fields = fields(&info);
        let get_fields = fields(&get);
        let tick_hz = get_fields
            .get("tick_hz")
            .or(info_fields.get("tick_hz"))
            .and_then(Value::as_f64)
            .ok_or_else(|| format!("the board's `info` and `get` say no tick rate: `{get}`"))?;
        *lock(&self.tick_hz) = tick_hz;
        let mut settings = Vec::new();
        if let Some(reply) = Reply::parse(&get) {
            for (key, value) in reply.pairs() {
                // Not logged: twenty lines of help would bury the operator's requests.
                let help = self.ask(&format!("help {key}"))?;
                let help = Reply::parse(&help)
                    .and_then(|r| match r {
                        Reply::Ok(text) => Some(text.to_string()),
                        Reply::Err { .. } => None,
                    })
                    .unwrap_or_default();
                settings.push(json!({"key": key, "value": value, "help": help}));
            }
        }
        let (curve, curve_problem) = match tuning_curve(&info_fields, &get_fields) {
            Ok(curve) => (curve, Value::Null),
            Err(why) => (Value::Null, Value::from(why)),
        };
        let device: serde_json::Map<String, Value> = info_fields
            .iter()
            .filter_map(|(k, v)| {
                k.strip_prefix("device.")
                    .map(|k| (k.to_string(), v.clone()))
            })
            .collect();
        *lock(&self.hello) = json!({
            "board": board,
            "info": info,
            "firmware": info_fields.get("firmware"),
            "image_crc": info_fields.get("image_crc"),
            "device": device,
            "tick_hz": tick_hz,
            "settings": settings,
            "curve": curve,
            "curve_problem": curve_problem,
            "columns": COLUMNS,
            "stream": self.stream.as_ref().map(Source::describe),
            "record_layout": VERSION,
        });
        Ok(())
    }

    /// A request of the dashboard's own (logged as such, not counted as a page's).
    fn ask_own(&self, request: &str) -> Result<String, String> {
        self.exchange(request, "dash").map(|(line, _)| line)
    }

    /// A request to the board and its reply, logged and told to every page.
    fn exchange(&self, request: &str, origin: &str) -> Result<(String, f64), String> {
        let started = Instant::now();
        let line = self.ask(request)?;
        let ms = started.elapsed().as_secs_f64() * 1e3;
        // Refused as not in control: another connection took it (said by name).
        if let Some(Some(who)) = control::of_line(&line) {
            self.set_control(false, Some(who));
        }
        let entry = json!({
            "origin": origin,
            "request": request,
            "reply": line,
            "ok": matches!(Reply::parse(&line), Some(Reply::Ok(_))),
            "ms": ms,
            "at": now_ms(),
        });
        {
            let mut log = lock(&self.log);
            if log.len() == LOG_KEPT {
                log.pop_front();
            }
            log.push_back(entry.clone());
        }
        self.hub.publish("exchange", &entry, 0);
        Ok((line, ms))
    }

    /// A page's request: sent verbatim (one line of printable ASCII), its reply verbatim.
    /// What it changes follows: the settings read again, the stream asked again after a
    /// reset (the board's rate starts at off).
    pub fn command(&self, request: &str) -> Result<Value, String> {
        let request = request.trim_end_matches(['\r', '\n']);
        let most = de_resonator::wire::protocol::MAX_LINE;
        if request.is_empty() || request.len() > most {
            return Err(format!("a request is one line of 1 to {most} characters"));
        }
        if !request.bytes().all(|b| (0x20..0x7f).contains(&b)) {
            return Err(
                "a request is one line of printable ASCII (no line end inside: one request a \
                 time)"
                    .into(),
            );
        }
        self.requests.fetch_add(1, Ordering::Relaxed);
        let (line, ms) = self.exchange(request, "page")?;
        let ok = matches!(Reply::parse(&line), Some(Reply::Ok(_)));
        let verb = request.split_whitespace().next().unwrap_or("");
        // What may change a setting in force (`target` its target, `ac` its drive): the
        // settings read again, so the page never shows a value gone.
        if ok
            && matches!(
                verb,
                "set" | "reset" | "save" | "clear" | "target" | "ac" | "start" | "trim"
            )
        {
            self.refresh_settings();
        }
        if ok && verb == "faults" {
            read_faults(self);
        }
        if ok && verb == "reset" && self.stream.is_some() {
            std::thread::sleep(Duration::from_millis(300));
            self.ask_stream();
        }
        Ok(json!({"request": request, "reply": line, "ok": ok, "fields": fields(&line), "ms": ms}))
    }

    /// `get` again: the settings' values told to the pages (and kept in the hello).
    fn refresh_settings(&self) {
        let Ok(get) = self.ask_own("get") else { return };
        let Some(reply) = Reply::parse(&get) else {
            return;
        };
        let values: serde_json::Map<String, Value> = reply
            .pairs()
            .map(|(k, v)| (k.to_string(), Value::from(v)))
            .collect();
        let mut hello = lock(&self.hello);
        let mut margin_moved = false;
        if let Some(settings) = hello.get_mut("settings").and_then(Value::as_array_mut) {
            for s in settings {
                let value = s["key"].as_str().and_then(|k| values.get(k)).cloned();
                if let Some(value) = value {
                    margin_moved |= s["key"] == "margin" && s["value"] != value;
                    s["value"] = value;
                }
            }
        }
        // A new margin moves the curve's highest bias and the tunable range.
        let curve = margin_moved.then(|| {
            let info = fields(hello["info"].as_str().unwrap_or(""));
            let (curve, problem) = match tuning_curve(&info, &fields(&get)) {
                Ok(curve) => (curve, Value::Null),
                Err(why) => (Value::Null, Value::from(why)),
            };
            hello["curve"] = curve.clone();
            hello["curve_problem"] = problem.clone();
            json!({"curve": curve, "curve_problem": problem})
        });
        drop(hello);
        self.hub.publish("settings", &Value::Object(values), 0);
        if let Some(curve) = curve {
            self.hub.publish("curve", &curve, 0);
        }
    }

    /// `stream <hz>`: the board's stream started (its reply kept for the pages).
    fn ask_stream(&self) {
        let reply = self
            .ask_own(&self.stream_request)
            .unwrap_or_else(|why| format!("(no reply: {why})"));
        *lock(&self.stream_reply) = Some(reply.clone());
        self.hub.publish(
            "stream",
            &json!({"request": self.stream_request, "reply": reply}),
            0,
        );
    }

    /// Who controls the board now, told to the pages; taking control asks for the stream
    /// again (the connection that left stopped it).
    fn set_control(&self, controls: bool, controller: Option<String>) {
        let control = Control {
            controls,
            controller,
        };
        let before = std::mem::replace(&mut *lock(&self.control), control.clone());
        if controls && !before.controls {
            self.restart_stream.store(true, Ordering::Relaxed);
        }
        self.hub.publish("control", &json!(control), 0);
    }

    /// The connection to the board, told to the pages.
    fn set_link(&self, link: Link) {
        *lock(&self.link_state) = link.clone();
        self.hub.publish("board", &json!(link), 0);
    }

    /// A line of dash's own for the pages' "board said" list (marked as dash's).
    fn dash_says(&self, what: &str) {
        self.hub.publish(
            "notice",
            &json!({"line": format!("# dash: {what}"), "at": now_ms()}),
            0,
        );
    }

    /// A line the board said on its own: kept, and told to the pages.
    fn notice(&self, line: String) {
        if let Some(who) = control::of_line(&line) {
            self.set_control(who.is_none(), who);
        }
        let entry = json!({"line": line, "at": now_ms()});
        let mut notices = lock(&self.notices);
        if notices.len() == NOTICES_KEPT {
            notices.pop_front();
        }
        notices.push_back(line);
        drop(notices);
        self.hub.publish("notice", &entry, 0);
    }

    /// A new page: its queue, and what it is told first.
    pub fn subscribe(&self) -> (Value, Receiver<Arc<str>>) {
        let (tx, rx) = mpsc::sync_channel(PAGE_QUEUE);
        // No event is published while the page's first view is taken and its queue added:
        // none falls between the two.
        let mut pages = lock(&self.hub.pages);
        let hello = self.hello_now();
        pages.push(tx);
        (hello, rx)
    }

    /// What a page is told first: the board, and everything as it stands now.
    fn hello_now(&self) -> Value {
        let mut hello = lock(&self.hello).clone();
        hello["log"] = Value::from(lock(&self.log).iter().cloned().collect::<Vec<_>>());
        hello["notices"] = Value::from(lock(&self.notices).iter().cloned().collect::<Vec<_>>());
        hello["status"] = lock(&self.status).clone();
        hello["faults"] = lock(&self.faults).clone();
        hello["link"] = self.link();
        hello["stream_reply"] = Value::from(lock(&self.stream_reply).clone());
        hello["recording"] = Value::from(lock(&self.recording).is_some());
        hello["board_link"] = json!(*lock(&self.link_state));
        hello["control"] = json!(*lock(&self.control));
        hello
    }

    /// The hello again, for the pages already open (after the board came back: what it runs
    /// may have changed).
    fn hello_again(&self) {
        self.hub.publish("hello", &self.hello_now(), 0);
    }

    /// The link's health: the stream's counts, what the pages could not take.
    fn link(&self) -> Value {
        let c = *lock(&self.counts);
        json!({
            "records": c.records,
            "lost": c.lost,
            "bad_frames": c.bad_frames,
            "dropped_to_pages": self.dropped(),
            "requests": self.requests(),
        })
    }

    /// Start keeping the stream's records, the header asked of the board now.
    pub fn record_start(&self) -> Result<Value, String> {
        if self.stream.is_none() {
            return Err(
                "no telemetry stream: start dash with --stream-port, --stream-tcp or \
                        --stream-unix to record"
                    .into(),
            );
        }
        {
            // Taken at once: a second start finds this one.
            let mut slot = lock(&self.recording);
            if slot.is_some() {
                return Err("a recording is already under way".into());
            }
            *slot = Some(Recording {
                header: Vec::new(),
                records: Vec::new(),
                from: *lock(&self.counts),
            });
        }
        // What runs, asked as the records come (as `console --record` asks it first).
        let mut header = Vec::new();
        for request in ["info", "get", "status"] {
            match self.ask_own(request) {
                Ok(line) => header.push(format!("{request}: {line}")),
                Err(why) => {
                    *lock(&self.recording) = None;
                    return Err(why);
                }
            }
        }
        let stream = lock(&self.stream_reply).clone().unwrap_or_default();
        header.push(format!("{}: {stream}", self.stream_request));
        if let Some(recording) = lock(&self.recording).as_mut() {
            recording.header = header;
        }
        self.hub.publish("recording", &json!({"on": true}), 0);
        Ok(json!({"recording": true}))
    }

    /// Stop keeping records: the CSV (as `console --record` writes it) kept for download.
    pub fn record_stop(&self) -> Result<Value, String> {
        let Some(recording) = lock(&self.recording).take() else {
            return Err("no recording is under way".into());
        };
        let now = *lock(&self.counts);
        let counts = Counts {
            records: now.records - recording.from.records,
            lost: now.lost - recording.from.lost,
            bad_frames: now.bad_frames - recording.from.bad_frames,
        };
        let mut header = recording.header;
        header.extend(
            lock(&self.notices)
                .iter()
                .map(|n| format!("board said: {n}")),
        );
        let tick_hz = *lock(&self.tick_hz);
        let csv = record::csv(&header, &recording.records, counts, tick_hz)?;
        let bytes = csv.len();
        *lock(&self.last_recording) = Some(csv);
        let said = json!({
            "on": false,
            "full": recording.records.len() >= RECORDING_MAX,
            "records": recording.records.len(),
            "lost": counts.lost,
            "bad_frames": counts.bad_frames,
            "bytes": bytes,
            "url": "/api/recording.csv",
        });
        self.hub.publish("recording", &said, 0);
        Ok(said)
    }

    /// The last recording's CSV.
    pub fn recording_csv(&self) -> Option<Vec<u8>> {
        lock(&self.last_recording).clone()
    }

    pub fn counts(&self) -> Counts {
        *lock(&self.counts)
    }

    pub fn requests(&self) -> u64 {
        self.requests.load(Ordering::Relaxed)
    }

    pub fn dropped(&self) -> u64 {
        self.hub.dropped.load(Ordering::Relaxed)
    }

    /// Why the board is out of reach as dash ends, if it is.
    pub fn stopped(&self) -> Option<String> {
        match &*lock(&self.link_state) {
            Link::Lost { why, .. } => Some(why.clone()),
            Link::Up | Link::Silent { .. } => None,
        }
    }

    /// Times the board was lost (and dash reconnected, or tried to).
    pub fn losses(&self) -> u64 {
        self.losses.load(Ordering::Relaxed)
    }

    /// A snapshot for tools and tests: the link, the last status, the board's connection,
    /// who controls.
    pub fn state(&self) -> Value {
        json!({
            "link": self.link(),
            "status": lock(&self.status).clone(),
            "board": *lock(&self.link_state),
            "control": *lock(&self.control),
            "losses": self.losses(),
        })
    }
}

/// The device's tuning curve from `info`'s `device.*` and `get`'s margin (model.md §5–§6):
/// f against bias to the limit, the margin's highest bias, the tunable range.
fn tuning_curve(
    info: &serde_json::Map<String, Value>,
    get: &serde_json::Map<String, Value>,
) -> Result<Value, String> {
    let keys: Vec<(&str, f64)> = info
        .iter()
        .filter_map(|(k, v)| Some((k.strip_prefix("device.")?, v.as_f64()?)))
        .collect();
    if keys.is_empty() {
        return Err("the board's `info` names no device".into());
    }
    let (params, _) = crate::device_file::from_keys(&keys)?;
    let margin = get
        .get("margin")
        .and_then(Value::as_f64)
        .ok_or("the board's `get` says no margin")?;
    let curve = crate::cmd::curve::one_curve(params, margin, None, CURVE_POINTS);
    if let Some(problem) = &curve.problem {
        return Err(problem.clone());
    }
    let mut value = serde_json::to_value(&curve).map_err(|e| e.to_string())?;
    value["margin"] = Value::from(margin);
    Ok(value)
}

/// The dashboard's thread that keeps the board: polls it, reads its stream, and reconnects
/// when it is lost.
pub struct Workers {
    thread: JoinHandle<()>,
}

/// Start the stream (`stream <hz>`) and the thread that polls the status, reads the stream,
/// and reconnects to a board lost. The first stream must open: a wrong path is said at once.
pub fn start(shared: &Arc<Shared>, args: &DashArgs) -> Result<Workers, String> {
    let first = shared.stream.as_ref().map(Source::open).transpose()?;
    let s = shared.clone();
    let every = Duration::from_secs_f64(args.poll_seconds);
    let thread = std::thread::spawn(move || keep(&s, every, first));
    Ok(Workers { thread })
}

impl Workers {
    /// Stop the thread and the stream; what the board is still doing, in words.
    pub fn finish(self, shared: &Shared) -> String {
        shared.stop.store(true, Ordering::Relaxed);
        let _ = self.thread.join();
        if let Some(why) = shared.stopped() {
            return format!("the board is out of reach ({why}): its state is unknown");
        }
        // The stream stopped only by the connection that controls (another's asks err 8).
        if shared.stream.is_some() && lock(&shared.control).controls {
            let _ = shared.ask_own("stream off");
        }
        crate::cmd::console::leaving(&mut |r| shared.ask(r), false)
    }
}

/// The board kept while dash runs: each connection polled until it is lost, then opened
/// again with a growing wait between attempts, the pages told at every change.
fn keep(shared: &Arc<Shared>, every: Duration, first: Option<Box<dyn std::io::Read + Send>>) {
    let mut stream = Stream {
        first,
        reader: None,
        tried: None,
    };
    while !shared.stop.load(Ordering::Relaxed) {
        let why = poll(shared, every, &mut stream);
        stream.close();
        let Some(why) = why else { return };
        // Lost: nothing the page shows of the board holds any more (who controls included).
        *lock(&shared.port) = None;
        *lock(&shared.status) = Value::Null;
        *lock(&shared.faults) = Value::Null;
        shared.set_control(true, None);
        shared.losses.fetch_add(1, Ordering::Relaxed);
        let since_ms = now_ms();
        let mut wait = RETRY_FIRST;
        let mut attempt = 0;
        let mut last = why;
        loop {
            attempt += 1;
            shared.set_link(Link::Lost {
                why: last.clone(),
                since_ms,
                attempt,
                retry_seconds: wait.as_secs_f64(),
            });
            let until = Instant::now() + wait;
            while Instant::now() < until {
                if shared.stop.load(Ordering::Relaxed) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            match shared.open_board() {
                Ok(()) => break,
                Err(why) => {
                    *lock(&shared.port) = None;
                    last = why;
                    wait = (wait * 2).min(RETRY_MAX);
                }
            }
        }
        shared.dash_says(&format!("the board is back after {attempt} attempts"));
        shared.set_link(Link::Up);
        shared.hello_again();
    }
}

/// The telemetry stream's reader: a thread while the stream is open, opened again (every
/// `STREAM_RETRY`) when it ends or could not open.
struct Stream {
    /// The stream opened as dash started, for the first connection.
    first: Option<Box<dyn std::io::Read + Send>>,
    reader: Option<(JoinHandle<()>, Arc<AtomicBool>)>,
    /// When it was last opened or tried.
    tried: Option<Instant>,
}

/// How long after a stream ended, or could not open, it is tried again.
const STREAM_RETRY: Duration = Duration::from_millis(500);

impl Stream {
    /// The stream read if it is not (dash's own, or after `STREAM_RETRY`), and asked for
    /// (`stream <hz>`) when this dash controls the board.
    fn keep_open(&mut self, shared: &Arc<Shared>) {
        let Some(source) = shared.stream.as_ref() else {
            return;
        };
        if self.reader.as_ref().is_some_and(|(r, _)| !r.is_finished()) {
            return;
        }
        if self.first.is_none() && self.tried.is_some_and(|t| t.elapsed() < STREAM_RETRY) {
            return;
        }
        self.close();
        self.tried = Some(Instant::now());
        let port = match self.first.take().map_or_else(|| source.open(), Ok) {
            Ok(port) => port,
            Err(why) => return shared.dash_says(&why),
        };
        let stop = Arc::new(AtomicBool::new(false));
        let (s, stopping) = (Arc::clone(shared), stop.clone());
        // The counts go on from the streams read before (over the connections before).
        let before = *lock(&shared.counts);
        let reader = std::thread::spawn(move || read_stream(&s, port, &stopping, before));
        self.reader = Some((reader, stop));
        if lock(&shared.control).controls {
            shared.ask_stream();
        }
    }

    /// The reader stopped and awaited.
    fn close(&mut self) {
        if let Some((reader, stop)) = self.reader.take() {
            stop.store(true, Ordering::Relaxed);
            let _ = reader.join();
        }
    }
}

/// Ask `status` every `every`, and the fault log when the fault changes: told to the pages;
/// the stream kept open. Returns why the board was lost, or `None` when dash stops.
fn poll(shared: &Arc<Shared>, every: Duration, stream: &mut Stream) -> Option<String> {
    let mut last_fault: Option<String> = None;
    let mut polls = 0u64;
    while !shared.stop.load(Ordering::Relaxed) {
        stream.keep_open(shared);
        if shared.restart_stream.swap(false, Ordering::Relaxed) && shared.stream.is_some() {
            shared.ask_stream();
        }
        match shared.ask("status") {
            Ok(line) => {
                if !matches!(*lock(&shared.link_state), Link::Up) {
                    shared.set_link(Link::Up);
                }
                let status = json!({"line": line, "fields": fields(&line), "at": now_ms()});
                *lock(&shared.status) = status.clone();
                shared.hub.publish("status", &status, 0);
                let fault = Reply::parse(&line)
                    .and_then(|r| r.field("fault"))
                    .map(String::from);
                // The log read when the fault changes, and now and then (a fault cleared
                // and a new one between two polls).
                if fault != last_fault || polls.is_multiple_of(20) {
                    read_faults(shared);
                    last_fault = fault;
                }
            }
            Err(why) if gone(&why) || why == NOT_CONNECTED => return Some(why),
            // Unanswered: the board's state is unknown until it answers again.
            Err(why) => {
                *lock(&shared.status) = Value::Null;
                shared.set_link(Link::Silent { why });
            }
        }
        polls += 1;
        let link = shared.link();
        shared.hub.publish("link", &link, 0);
        std::thread::sleep(every);
    }
    None
}

/// `faults`, and each entry it lists (the newest few): told to the pages.
fn read_faults(shared: &Shared) {
    let Ok(summary) = shared.ask("faults") else {
        return;
    };
    // `ok faults=N | n cause t=… | …`: the entries' numbers.
    let numbers: Vec<u32> = summary
        .split('|')
        .skip(1)
        .filter_map(|part| part.split_whitespace().next()?.parse().ok())
        .collect();
    let mut entries = Vec::new();
    // `faults` lists the newest first.
    for n in numbers.iter().take(FAULTS_SHOWN) {
        if let Ok(line) = shared.ask(&format!("faults {n}")) {
            entries.push(json!({"line": line, "fields": fields(&line)}));
        }
    }
    let faults = json!({"summary": summary, "entries": entries});
    *lock(&shared.faults) = faults.clone();
    shared.hub.publish("faults", &faults, 0);
}

/// Read the stream into batches for the pages (and the recording).
fn read_stream(
    shared: &Shared,
    port: Box<dyn std::io::Read + Send>,
    stop: &AtomicBool,
    before: Counts,
) {
    let mut pending: Vec<Row> = Vec::new();
    let mut last = Instant::now();
    let result = telemetry::read(port, stop, |new, receiver| {
        pending.extend(new.iter().map(Row::of));
        // The counts and the recording's rows under one lock: a recording's counts are its
        // rows'.
        let mut recording = lock(&shared.recording);
        *lock(&shared.counts) = Counts::of(receiver).after(before);
        if let Some(r) = recording.as_mut() {
            let room = RECORDING_MAX.saturating_sub(r.records.len());
            r.records.extend_from_slice(&new[..new.len().min(room)]);
        }
        drop(recording);
        if !pending.is_empty() && last.elapsed() >= BATCH {
            let n = pending.len() as u64;
            // f32 written as f32 (7449.8784, not 7449.87841796875).
            let rows = serde_json::to_string(&pending).unwrap_or_else(|_| "[]".into());
            shared.hub.publish("records", &rows, n);
            pending.clear();
            last = Instant::now();
        }
    });
    if let Err(why) = result {
        shared.dash_says(&why);
    }
}
