//! The link's frames (`wire::link`): what one side writes the other reads back, a corrupted
//! or cut frame is refused with its reason, and no bytes panic the parser.

use de_resonator::wire::link::{
    self, Booted, Kind, LinkError, Observed, HEADER, MAX_FRAME, MAX_PAYLOAD,
};
use de_resonator::{Event, EventKind, FailureMode, Fault, Phase};
use proptest::prelude::*;

fn samples_frame(tick: u32, codes: &[u16]) -> Vec<u8> {
    let mut out = vec![0; MAX_FRAME];
    let n = link::write_frame(&mut out, (Kind::Samples, 0), tick, |p| {
        link::write_codes(codes, p)
    })
    .unwrap();
    out.truncate(n);
    out
}

#[test]
fn a_frame_is_its_header_payload_and_the_ieee_crc_of_both() {
    let frame = samples_frame(7, &[0x0102, 0xFFFF]);
    assert_eq!(frame.len(), 10 + 4 + 4);
    assert_eq!(&frame[..4], b"DL\x01\x00");
    assert_eq!(&frame[4..8], &7u32.to_le_bytes());
    assert_eq!(&frame[8..10], &4u16.to_le_bytes());
    assert_eq!(&frame[10..14], &[0x02, 0x01, 0xFF, 0xFF]);
    // CRC-32 (IEEE 802.3) by its definition, bit by bit, independently of the core's table.
    let mut crc = !0u32;
    for &b in &frame[..14] {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    assert_eq!(&frame[14..], &(!crc).to_le_bytes());
}

#[test]
fn a_frame_reads_back_and_a_corrupted_one_is_refused_with_its_reason() {
    let codes: Vec<u16> = (0..30).map(|i| 4095 - 100 * i).collect();
    let good = samples_frame(3, &codes);
    assert_eq!(link::frame_bytes(&good[..HEADER]), Ok(good.len()));
    let (h, payload) = link::parse(&good).unwrap();
    assert_eq!(
        (h.kind, h.flags, h.tick, h.payload_bytes),
        (Kind::Samples, 0, 3, 60)
    );
    assert_eq!(link::codes(payload).collect::<Vec<_>>(), codes);

    let mut bad = good.clone();
    bad[20] ^= 0x10;
    assert!(matches!(link::parse(&bad), Err(LinkError::BadCrc { .. })));
    let mut magic = good.clone();
    magic[0] = b'X';
    assert_eq!(link::parse(&magic), Err(LinkError::NoMagic));
    let cut = &good[..good.len() - 1];
    assert!(matches!(link::parse(cut), Err(LinkError::Size { .. })));
    assert!(matches!(
        link::parse(&good[..4]),
        Err(LinkError::Size { .. })
    ));
}

#[test]
fn a_length_over_the_limit_or_an_unknown_kind_is_refused_at_the_header() {
    let mut over = samples_frame(0, &[]);
    over[8..10].copy_from_slice(&((MAX_PAYLOAD + 1) as u16).to_le_bytes());
    assert_eq!(
        link::frame_bytes(&over),
        Err(LinkError::TooLong((MAX_PAYLOAD + 1) as u16))
    );
    let mut kind = samples_frame(0, &[]);
    kind[2] = 9;
    assert_eq!(link::frame_bytes(&kind), Err(LinkError::UnknownKind(9)));
}

#[test]
fn codes_that_do_not_fit_the_buffer_are_an_error_not_a_cut() {
    let mut out = [0u8; 20];
    let r = link::write_frame(&mut out, (Kind::Samples, 0), 0, |p| {
        link::write_codes(&[1; 4], p)
    });
    assert!(matches!(r, Err(LinkError::Size { needed: 8, .. })), "{r:?}");
}

#[test]
fn a_ticks_output_reads_back_with_the_events_words() {
    let event = Event::Trimmed {
        bias_volts: 3012.25,
        measured_hz: 43.98765,
        shear_modulus: 41234.5,
        next_bias_volts: 3020.0,
        resolution: Some(120.0),
        quality: Some(de_resonator::estimate::ring::RingQuality {
            quality_factor: 150.5,
            high: 175.25,
        }),
    };
    let observed = Observed {
        dac_code: 51234,
        dac_on: true,
        enable: true,
        said: Some(event.kind()),
        said_values: event.values(),
        phase: Some(Phase::Solving),
        bias_volts: 3012.25,
        target_hz: 44.5,
        ac_phase_step: Some(0x1234_5678),
        tracked_hz: f32::NAN,
        quality_factor: 180.5,
        sensed_stretch: 3.01,
        sensed_sigma: 1e-4,
    };
    let mut out = vec![0; MAX_FRAME];
    let n = link::write_frame(&mut out, (Kind::Output, 0), 99, |p| {
        observed.write(Some(&event), p)
    })
    .unwrap();
    let (h, payload) = link::parse(&out[..n]).unwrap();
    assert_eq!((h.kind, h.tick), (Kind::Output, 99));
    let (back, words) = Observed::read(payload).unwrap();
    assert!(back.tracked_hz.is_nan());
    // The event's numbers, as it was made, named in order.
    assert_eq!(back.said, Some(EventKind::Trimmed));
    assert_eq!(
        back.said_values,
        [3012.25, 43.98765, 41234.5, 3020.0, 120.0, 150.5, 175.25]
    );
    assert_eq!(
        EventKind::Trimmed.value_names(),
        [
            "bias_volts",
            "measured_hz",
            "shear_modulus_pa",
            "next_bias_volts",
            "resolution",
            "quality_factor",
            "quality_high"
        ]
    );
    assert_eq!(
        Observed {
            tracked_hz: 0.0,
            ..back
        },
        Observed {
            tracked_hz: 0.0,
            ..observed
        }
    );
    assert_eq!(
        std::str::from_utf8(words).unwrap(),
        "trim: 43.9877 Hz measured at 3012.2 V (resolution 120), Q 150 (at most 175), μ \
         estimated 41.23 kPa, next bias 3020.0 V"
    );
}

#[test]
fn a_fault_sends_the_faults_words_and_a_refused_boot_its_reason() {
    let fault = Fault::SensorStuck {
        samples: 200,
        value: 3.0,
    };
    let observed = Observed::of(0, false, false, None, Some(&Event::Fault(fault)));
    assert_eq!(
        (observed.said, observed.phase),
        (Some(EventKind::Fault), None)
    );
    let mut out = [0u8; 200];
    let n = observed
        .write(Some(&Event::Fault(fault)), &mut out)
        .unwrap();
    let (_, words) = Observed::read(&out[..n]).unwrap();
    assert_eq!(std::str::from_utf8(words).unwrap(), fault.to_string());
    assert_eq!(
        Observed::of(0, false, false, None, Some(&Event::Fault(Fault::Bus))).said,
        Some(EventKind::BusFault)
    );

    let booted = Booted {
        driving: false,
        bias_volts: f32::NAN,
        max_volts: 4000.0,
        limit: Some((FailureMode::Emi, 3.5)),
    };
    let n = booted.write("image: bad CRC", &mut out).unwrap();
    let (back, words) = Booted::read(&out[..n]).unwrap();
    assert_eq!(
        (back.driving, back.max_volts, back.limit),
        (false, 4000.0, booted.limit)
    );
    assert_eq!(words, b"image: bad CRC");
}

#[test]
fn words_longer_than_the_room_are_cut_at_a_character() {
    let observed = Observed::of(0, false, false, None, None);
    let mut out = [0u8; link::OBSERVED_BYTES + 5];
    let event = Event::Trimmed {
        bias_volts: 1.0,
        measured_hz: 1.0,
        shear_modulus: 1.0,
        next_bias_volts: 1.0,
        resolution: None,
        quality: None,
    };
    let n = observed.write(Some(&event), &mut out).unwrap();
    assert_eq!(&out[link::OBSERVED_BYTES..n], b"trim:");
    assert!(Observed::read(&out[..10]).is_err());
}

#[test]
fn a_record_byte_no_field_can_hold_is_refused() {
    let observed = Observed::of(0, false, false, None, None);
    let mut out = [0u8; link::OBSERVED_BYTES];
    observed.write(None, &mut out).unwrap();
    // What was said (byte 3) and the phase (byte 4), each given a value no variant has.
    for offset in [3, 4] {
        let mut bad = out;
        bad[offset] = 8;
        assert_eq!(
            Observed::read(&bad).map(|_| ()),
            Err(LinkError::BadField { offset, value: 8 })
        );
    }
}

proptest! {
    /// No bytes panic the parser; any one bit flipped in a frame is refused (CRC-32 finds
    /// every single-bit error; a flip in the header's length is a size the bytes do not have).
    #[test]
    fn any_bytes_parse_without_a_panic_and_no_flipped_bit_passes(
        bytes in proptest::collection::vec(any::<u8>(), 0..1100),
        codes in proptest::collection::vec(any::<u16>(), 0..40),
        bit in 0usize..1000,
    ) {
        let _ = link::parse(&bytes);
        let _ = link::frame_bytes(&bytes);
        let frame = samples_frame(5, &codes);
        prop_assert!(link::parse(&frame).is_ok());
        let mut flipped = frame.clone();
        let bit = bit % (8 * flipped.len());
        flipped[bit / 8] ^= 1 << (bit % 8);
        prop_assert!(link::parse(&flipped).is_err());
    }
}
