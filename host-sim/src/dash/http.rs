//! The dashboard's page side: its assets (built into the binary), the board's requests from
//! the page, the recording, and the events each open page receives (server-sent events).

use std::io::{Read, Write};
use std::sync::Arc;
use std::time::Duration;

use serde_json::{json, Value};
use tiny_http::{Header, Method, Request, Response};

use super::board::Shared;

/// The page and what it loads: path, content type, bytes.
const ASSETS: [(&str, &str, &[u8]); 6] = [
    (
        "/",
        "text/html; charset=utf-8",
        include_bytes!("../../assets/dash/index.html"),
    ),
    (
        "/dash.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/dash/dash.js"),
    ),
    (
        "/dash.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/dash/dash.css"),
    ),
    (
        "/uPlot.iife.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../assets/uplot/uPlot.iife.min.js"),
    ),
    (
        "/uPlot.min.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/uplot/uPlot.min.css"),
    ),
    (
        "/uPlot-LICENSE.txt",
        "text/plain; charset=utf-8",
        include_bytes!("../../assets/uplot/LICENSE"),
    ),
];

/// The longest request body taken (a command line is far shorter).
const MAX_BODY: u64 = 4096;

/// The header every request that acts must carry: a page of another site cannot send it
/// without the browser asking this server first (a CORS preflight it never allows), so a
/// site open in the operator's browser cannot `start` the board.
pub const ACT_HEADER: &str = "X-Dash-Request";

/// Which requests the server takes: those addressed to it by a name it is served as (a site
/// that points its own name at 127.0.0.1, DNS rebinding, is refused), from its own page.
pub struct Guard {
    /// `Host` values taken (`None`: served beyond loopback, where any name may reach it).
    pub hosts: Option<Vec<String>>,
}

impl Guard {
    /// For a server at `address`: on loopback, only its loopback names.
    pub fn for_address(address: std::net::SocketAddr) -> Self {
        let port = address.port();
        let hosts = address.ip().is_loopback().then(|| {
            vec![
                format!("127.0.0.1:{port}"),
                format!("localhost:{port}"),
                format!("[::1]:{port}"),
            ]
        });
        Guard { hosts }
    }

    /// Why `request` is refused, if it is.
    fn refuses(&self, request: &Request, acts: bool) -> Option<String> {
        let header = |name: &'static str| {
            request
                .headers()
                .iter()
                .find(|h| h.field.equiv(name))
                .map(|h| h.value.as_str().to_string())
        };
        let host = header("Host").unwrap_or_default();
        if let Some(hosts) = &self.hosts {
            if !hosts.iter().any(|h| h.eq_ignore_ascii_case(&host)) {
                return Some(format!("not served as `{host}`: open {}", hosts[0]));
            }
        }
        if let Some(origin) = header("Origin") {
            if origin != format!("http://{host}") {
                return Some(format!("a page of {origin} may not use this one"));
            }
        }
        if acts && header(ACT_HEADER).is_none() {
            return Some(format!(
                "a request that acts carries {ACT_HEADER} (the page's own)"
            ));
        }
        None
    }
}

fn header(name: &str, value: &str) -> Header {
    Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn json_response(status: u16, value: &Value) -> Response<std::io::Cursor<Vec<u8>>> {
    Response::from_data(value.to_string().into_bytes())
        .with_status_code(status)
        .with_header(header("Content-Type", "application/json"))
        .with_header(header("Cache-Control", "no-store"))
}

/// Answer one request from a page (on its own thread: the events' stream lasts the page's
/// life).
pub fn handle(mut request: Request, shared: &Arc<Shared>, guard: &Guard) {
    let path = request.url().split('?').next().unwrap_or("").to_string();
    let method = request.method().clone();
    if let Some(why) = guard.refuses(&request, method == Method::Post) {
        let _ = request.respond(json_response(403, &json!({ "error": why })));
        return;
    }
    let response = match (method, path.as_str()) {
        (Method::Get, "/api/events") => return events(request, shared),
        (Method::Get, "/api/state") => json_response(200, &shared.state()),
        (Method::Post, "/api/command") => {
            let mut body = String::new();
            let read = request.as_reader().take(MAX_BODY).read_to_string(&mut body);
            match read
                .map_err(|e| e.to_string())
                .and_then(|_| shared.command(&body))
            {
                Ok(reply) => json_response(200, &reply),
                Err(why) => json_response(400, &json!({"error": why})),
            }
        }
        (Method::Post, "/api/record/start") => match shared.record_start() {
            Ok(v) => json_response(200, &v),
            Err(why) => json_response(409, &json!({"error": why})),
        },
        (Method::Post, "/api/record/stop") => match shared.record_stop() {
            Ok(v) => json_response(200, &v),
            Err(why) => json_response(409, &json!({"error": why})),
        },
        (Method::Get, "/api/recording.csv") => match shared.recording_csv() {
            Some(bytes) => Response::from_data(bytes)
                .with_header(header("Content-Type", "text/csv; charset=utf-8"))
                .with_header(header(
                    "Content-Disposition",
                    "attachment; filename=\"dash-recording.csv\"",
                )),
            None => json_response(404, &json!({"error": "no recording yet"})),
        },
        (Method::Get, path) => match ASSETS.iter().find(|(p, _, _)| *p == path) {
            Some((_, kind, bytes)) => {
                Response::from_data(bytes.to_vec()).with_header(header("Content-Type", kind))
            }
            None => json_response(404, &json!({"error": format!("no page at {path}")})),
        },
        (method, path) => json_response(
            405,
            &json!({"error": format!("{method} {path} is not something this page takes")}),
        ),
    };
    let _ = request.respond(response);
}

/// A page's events: the hello, then everything published, until the page goes away.
fn events(request: Request, shared: &Arc<Shared>) {
    let (hello, queue) = shared.subscribe();
    let mut out = request.into_writer();
    let head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
                Connection: close\r\n\r\n";
    let first = format!("{head}event: hello\ndata: {hello}\n\n");
    if out
        .write_all(first.as_bytes())
        .and_then(|()| out.flush())
        .is_err()
    {
        return;
    }
    loop {
        let event = match queue.recv_timeout(Duration::from_secs(5)) {
            Ok(event) => event,
            // A comment line now and then: a page gone is found by the write.
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => ": quiet\n\n".into(),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return,
        };
        // What is queued already goes in the same write.
        let mut text = String::from(&*event);
        while let Ok(more) = queue.try_recv() {
            text.push_str(&more);
        }
        if out
            .write_all(text.as_bytes())
            .and_then(|()| out.flush())
            .is_err()
        {
            return;
        }
    }
}
