//! A reply line of the command port as a client reads it (host-sim's console, dash and the
//! virtual board's tests): `ok …` with its `key=value` pairs, or `err <code> <message>`. The
//! board writes its replies with [`super::protocol`]; this is the other end.

use super::protocol::ErrorCode;

/// A reply line as a client reads it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reply<'a> {
    /// `ok …`: what follows.
    Ok(&'a str),
    Err {
        code: ErrorCode,
        message: &'a str,
    },
}

impl<'a> Reply<'a> {
    /// Read a reply line (without its `\n`); `None` if it is not one.
    pub fn parse(line: &'a str) -> Option<Self> {
        let line = line.trim_end_matches('\r');
        if line == "ok" {
            return Some(Reply::Ok(""));
        }
        if let Some(rest) = line.strip_prefix("ok ") {
            return Some(Reply::Ok(rest));
        }
        let rest = line.strip_prefix("err ")?;
        let (number, message) = rest.split_once(' ').unwrap_or((rest, ""));
        let code = ErrorCode::from_number(number.parse().ok()?)?;
        Some(Reply::Err { code, message })
    }

    /// The value of `key=` in an `ok` reply of key=value pairs (`fault=` takes the rest of
    /// the line: it is always last).
    pub fn field(&self, key: &str) -> Option<&'a str> {
        self.pairs().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// The `key=value` pairs of an `ok` reply, in order (`fault=` takes the rest of the
    /// line); none for an `err`.
    pub fn pairs(&self) -> impl Iterator<Item = (&'a str, &'a str)> {
        let mut rest = match *self {
            Reply::Ok(text) => text,
            Reply::Err { .. } => "",
        };
        core::iter::from_fn(move || loop {
            if rest.is_empty() {
                return None;
            }
            let (pair, after) = if rest.starts_with("fault=") {
                (rest, "")
            } else {
                rest.split_once(' ').unwrap_or((rest, ""))
            };
            rest = after;
            if let Some(kv) = pair.split_once('=') {
                return Some(kv);
            }
        })
    }
}
