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

/// Which requests the server takes: those that carry the page's token (made at dash's start,
/// printed in its URL: whoever holds the URL may switch the high voltage on, and no one
/// else), addressed to it by a name it is served as (on loopback: a site that points its own
/// name at 127.0.0.1, DNS rebinding, is refused), from its own page.
pub struct Guard {
    /// `Host` values taken (`None`: served beyond loopback, where any name may reach it).
    pub hosts: Option<Vec<String>>,
    /// The token every request carries: in the URL's query (`?token=`), the cookie the page
    /// gets with it, or an `Authorization: Token …` header (for a tool).
    token: String,
    /// The cookie's name, the port in it: two dash instances on one host keep their own.
    cookie: String,
}

/// Why a request is refused: its HTTP status and the words.
pub struct Refusal {
    pub status: u16,
    pub why: String,
}

impl Guard {
    /// For a server at `address` with `token`: on loopback, only its loopback names and the
    /// names `also` (a reverse proxy's).
    pub fn for_address(address: std::net::SocketAddr, token: String, also: &[String]) -> Self {
        let port = address.port();
        let hosts = address.ip().is_loopback().then(|| {
            let mut hosts = vec![
                address.to_string(),
                format!("127.0.0.1:{port}"),
                format!("localhost:{port}"),
                format!("[::1]:{port}"),
            ];
            hosts.extend(also.iter().cloned());
            hosts
        });
        Guard {
            hosts,
            token,
            cookie: format!("dash_token_{port}"),
        }
    }

    /// The `Set-Cookie` value that keeps the token for the page's own requests (not sent to
    /// another site's, nor readable by a script).
    fn set_cookie(&self) -> String {
        format!(
            "{}={}; Path=/; HttpOnly; SameSite=Strict",
            self.cookie, self.token
        )
    }

    /// The token `request` carries, and whether it came in the URL (the cookie then set).
    fn token_of<'r>(&self, request: &'r Request) -> Option<(&'r str, bool)> {
        let query = request.url().split_once('?').map_or("", |(_, q)| q);
        if let Some(t) = query.split('&').find_map(|kv| kv.strip_prefix("token=")) {
            return Some((t, true));
        }
        for h in request.headers() {
            if h.field.equiv("Authorization") {
                let value = h.value.as_str();
                let t = value
                    .strip_prefix("Token ")
                    .or_else(|| value.strip_prefix("Bearer "));
                if let Some(t) = t {
                    return Some((t.trim(), false));
                }
            }
            if h.field.equiv("Cookie") {
                let found = h.value.as_str().split(';').find_map(|c| {
                    let (name, value) = c.trim().split_once('=')?;
                    (name == self.cookie).then_some(value)
                });
                if let Some(t) = found {
                    return Some((t, false));
                }
            }
        }
        None
    }

    /// Why `request` is refused, if it is; else whether its token came in the URL.
    fn check(&self, request: &Request, acts: bool) -> Result<bool, Refusal> {
        let refuse = |status, why: String| Err(Refusal { status, why });
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
                return refuse(403, format!("not served as `{host}`: open {}", hosts[0]));
            }
        }
        if let Some(origin) = header("Origin") {
            // Its own page, over plain HTTP or behind a reverse proxy's TLS.
            if origin != format!("http://{host}") && origin != format!("https://{host}") {
                return refuse(403, format!("a page of {origin} may not use this one"));
            }
        }
        let from_url = match self.token_of(request) {
            Some((token, from_url)) if same(token, &self.token) => from_url,
            Some(_) => {
                return refuse(
                    401,
                    "a wrong token: open the URL dash printed as it started (its token \
                     changes at every start)"
                        .into(),
                )
            }
            None => {
                return refuse(
                    401,
                    "no token: open the URL dash printed as it started (it carries \
                     `?token=…`)"
                        .into(),
                )
            }
        };
        if acts && header(ACT_HEADER).is_none() {
            return refuse(
                403,
                format!("a request that acts carries {ACT_HEADER} (the page's own)"),
            );
        }
        Ok(from_url)
    }
}

/// Whether two tokens are the same, in a time that does not say how much of one matched.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |differ, (x, y)| differ | (x ^ y))
            == 0
}

/// A new random token: 128 bits from the system's random source, in hex.
pub fn new_token() -> Result<String, String> {
    let mut bytes = [0u8; 16];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut bytes))
        .map_err(|e| format!("cannot make the page's token from /dev/urandom: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
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
    let from_url = match guard.check(&request, method == Method::Post) {
        Ok(from_url) => from_url,
        Err(Refusal { status, why }) => {
            let _ = request.respond(json_response(status, &json!({ "error": why })));
            return;
        }
    };
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
                // The board out of reach: the request could not be sent (dash reconnects).
                Err(why) if why == super::board::NOT_CONNECTED => {
                    json_response(503, &json!({"error": why}))
                }
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
    // The token that came in the URL kept as the page's cookie for its own requests.
    let response = if from_url {
        response.with_header(header("Set-Cookie", &guard.set_cookie()))
    } else {
        response
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
