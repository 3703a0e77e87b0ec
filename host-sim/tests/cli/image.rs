//! `image`: the amplifier's flags, the trim's noise, a scene's power-up, an older image read
//! back.

use super::*;

/// Issue 46: the amplifier's flags are warned of as a device file's values are: a DAC
/// reference of 2500 "V" (millivolts typed as volts) is made, and said to be no DAC's.
#[test]
fn an_amplifier_flag_no_real_stage_has_is_warned_of() {
    let dir = std::env::temp_dir().join(format!("host-sim-amp-warn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.img");
    let done = host_sim(&[
        "image",
        "--dac-reference-volts",
        "2500",
        "--gain",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(done.status.success(), "the image is made: it boots");
    let err = String::from_utf8_lossy(&done.stderr);
    assert!(
        err.contains(
            "warning: `--dac-reference-volts` = 2500 V is outside what any DAC's reference has"
        ),
        "{err}"
    );
    assert!(
        !err.contains("--gain"),
        "1.6 V/V is a gain some stage has: {err}"
    );
    let plain = host_sim(&["image", "--out", out.to_str().unwrap()]);
    assert!(!String::from_utf8_lossy(&plain.stderr).contains("warning"));
}

/// `image` boots what it writes as the board does, with the noise its front end declares: a
/// scene whose ADC (20 codes, declared) leaves the trim's first ring unresolvable is not
/// written (status 2, the refusal's figures); at the shipped 2 codes it is.
#[test]
fn image_refuses_a_trim_its_declared_noise_cannot_resolve() {
    let shipped = include_str!("../../../scenes/sensorless-soft.toml");
    let noisy = DeviceFile::new(
        "noisy-scene.toml",
        &shipped.replace("noise_codes = 2.0", "noise_codes = 20.0"),
    );
    let out = std::env::temp_dir().join(format!("host-sim-cli-{}.img", std::process::id()));
    let out = out.to_str().unwrap();
    let said = refused(&["image", "--scene", noisy.path(), "--out", out]);
    assert!(
        said.contains("too weak to time") && said.contains("before any voltage"),
        "{said}"
    );
    assert!(!std::path::Path::new(out).exists());
    let shipped = DeviceFile::new("shipped-scene.toml", shipped);
    let written = host_sim(&["image", "--scene", shipped.path(), "--out", out]);
    assert_eq!(written.status.code(), Some(0), "{written:?}");
    let _ = std::fs::remove_file(out);
}

/// A scene's image drives at power-up, as `run` and `serve` boot it, unless `--power-up wait`
/// says otherwise (never a flag taken and ignored); the two differ in nothing else that
/// `--check` reads.
#[test]
fn a_scenes_image_takes_the_power_up_asked() {
    let scene = DeviceFile::new(
        "power-up-scene.toml",
        include_str!("../../../scenes/reference.toml"),
    );
    let dir = std::env::temp_dir().join(format!("host-sim-power-up-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut checked = Vec::new();
    for asked in [None, Some("wait"), Some("drive")] {
        let path = dir.join(format!("{}.img", asked.unwrap_or("default")));
        let path = path.to_str().unwrap();
        let mut args = vec!["image", "--scene", scene.path(), "--out", path];
        args.extend(asked.map(|a| ["--power-up", a]).iter().flatten());
        let out = host_sim(&args);
        assert!(out.status.success(), "{out:?}");
        let mut report = json(&["--json", "image", "--check", path]);
        let power_up = report["power_up"].take();
        assert_eq!(power_up, asked.unwrap_or("drive"), "{asked:?}");
        report["file"].take();
        checked.push(report);
    }
    assert_eq!(checked[0], checked[1]);
    assert_eq!(checked[0], checked[2]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `image --check` on an image made before a setting was added (here, one whose
/// `settle_seconds` entry is taken out, as an older host-sim wrote it) names the setting the
/// board boots at its default, in words and in `--json`'s `defaulted`; today's image names
/// none.
#[test]
fn image_check_names_the_settings_an_older_image_lacks() {
    let dir = std::env::temp_dir().join(format!("host-sim-defaulted-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("today.img");
    let out = host_sim(&[
        "image",
        "--target-hz",
        "44",
        "--out",
        path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let today = json(&["--json", "image", "--check", path.to_str().unwrap()]);
    assert_eq!(today["defaulted"], serde_json::json!([]), "{today}");
    // Layout 4 (docs/firmware.md): settings by id from byte 156, 8 bytes each; the count at
    // 6, the length at 8, the CRC-32 last.
    let mut bytes = std::fs::read(&path).unwrap();
    let length = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
    bytes.truncate(length);
    let lacking = de_resonator::Setting::from_key("settle_seconds").unwrap();
    let at = 156 + 8 * usize::from(lacking.id());
    assert_eq!(bytes[at..at + 2], u16::from(lacking.id()).to_le_bytes());
    bytes.drain(at..at + 8);
    let count = u16::from_le_bytes(bytes[6..8].try_into().unwrap()) - 1;
    bytes[6..8].copy_from_slice(&count.to_le_bytes());
    bytes[8..12].copy_from_slice(&((length - 8) as u32).to_le_bytes());
    let body = bytes.len() - 4;
    let crc = de_resonator::bytes::crc32(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
    let older = dir.join("older.img");
    std::fs::write(&older, &bytes).unwrap();
    let read = json(&["--json", "image", "--check", older.to_str().unwrap()]);
    assert_eq!(
        read["defaulted"],
        serde_json::json!(["settle_seconds"]),
        "{read}"
    );
    let text =
        String::from_utf8(host_sim(&["image", "--check", older.to_str().unwrap()]).stdout).unwrap();
    assert!(
        text.contains("boots them at their defaults): settle_seconds"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
