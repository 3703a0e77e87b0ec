//! The wire formats, one definition for both ends: the command port's line protocol
//! ([`protocol`]: requests, the board's replies, status; [`reply`]: a reply as a client reads
//! it), the telemetry stream's framed records
//! ([`stream`]) and host-sim's link to the firmware in the loop ([`link`]). The board serves
//! them; host-sim's console, dash and loop read them. Nothing here knows the board.

pub mod link;
pub mod protocol;
pub mod reply;
pub mod stream;
