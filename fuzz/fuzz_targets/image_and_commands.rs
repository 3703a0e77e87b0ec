//! Any bytes as a configuration image (first byte `I`), as the telemetry stream a receiver
//! reads (first byte `S`) or as command-port lines (otherwise): reading never panics; an image
//! that reads boots or is refused with a typed fault, never a panic; a record the receiver
//! takes is written back to the same bytes; a line parses or gets a typed error, and a number
//! it parses is finite.
#![no_main]

use de_resonator::board::commands::{self, Command, FaultsAsk};
use de_resonator::image::Image;
use de_resonator::wire::protocol;
use de_resonator::wire::stream::{Receiver, Record};
use de_resonator::Controller;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Some(rest) = data.strip_prefix(b"I") {
        let Ok(image) = Image::parse(rest) else {
            return;
        };
        let Ok(amplifier) = image.amplifier.amplifier() else {
            return;
        };
        if let Ok((mut c, boot)) =
            Controller::start(image.params, image.table, amplifier, image.settings)
        {
            assert!(boot.max_volts <= amplifier.max_volts());
            let out = c.tick(de_resonator::Inputs::NONE);
            assert!(out.volts <= boot.max_volts);
        }
        return;
    }
    if let Some(rest) = data.strip_prefix(b"S") {
        let mut receiver = Receiver::default();
        for &b in rest {
            if let Some(Ok(record)) = receiver.push(b) {
                let again = Record::from_bytes(&record.to_bytes());
                assert_eq!(again.map(|r| r.to_bytes()), Ok(record.to_bytes()));
            }
        }
        return;
    }
    for line in data.split(|&b| b == b'\n') {
        match commands::parse(line) {
            Ok(Command::Target { hz }) => assert!(hz.is_finite()),
            Ok(Command::Ac { volts, hz }) => assert!(volts.is_finite() && hz.is_finite()),
            Ok(Command::Set(_, value)) => assert!(value.is_finite()),
            Ok(Command::Stream(Some(hz))) => assert!(hz.is_finite()),
            Ok(Command::Faults(FaultsAsk::One(n))) => assert!(n >= 1),
            _ => {}
        }
        if let Ok(text) = core::str::from_utf8(line) {
            if let Some(x) = protocol::parse_number(text) {
                assert!(x.is_finite());
            }
        }
    }
});
