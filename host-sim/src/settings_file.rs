//! Controller settings in TOML: the keys of the core's `Setting` list (one list for scenes,
//! settings files and the command port), numbers, `Settings::for_target`'s defaults for the
//! keys left out; and the board's analog front end (`[front_end]`, the core's
//! `acquire::FrontEnd`).

use std::path::Path;

use de_resonator::acquire::{Channel, ChannelSpec, FrontEnd};
use de_resonator::{Setting, Settings};

/// A TOML number as f32, or an error naming `what`.
fn number(what: &str, value: &toml::Value) -> Result<f32, String> {
    match value {
        toml::Value::Float(x) => Ok(*x as f32),
        toml::Value::Integer(n) => Ok(*n as f32),
        other => Err(format!(
            "{what} must be a number, not a {}",
            other.type_str()
        )),
    }
}

/// `table` (a scene's `[controller]`, or a settings file: `section` names it in errors) as
/// `Settings`; `target_hz` from the table, else `target_hz`, else an error.
pub fn from_table(
    table: &toml::Table,
    section: &str,
    target_hz: Option<f32>,
) -> Result<Settings, String> {
    let number = |key: &str, value: &toml::Value| number(&format!("{section} {key}"), value);
    let target = match (table.get("target_hz"), target_hz) {
        (Some(value), _) => number("target_hz", value)?,
        (None, Some(hz)) => hz,
        (None, None) => return Err(format!("{section} needs target_hz")),
    };
    let mut settings = Settings::for_target(target);
    for (key, value) in table {
        let setting = Setting::from_key(key).ok_or_else(|| {
            let keys: Vec<&str> = Setting::ALL.iter().map(|s| s.key()).collect();
            format!(
                "{section} unknown key `{key}`, expected one of {}",
                keys.join(", ")
            )
        })?;
        let value = number(key, value)?;
        if setting.whole() && value.fract() != 0.0 {
            return Err(format!(
                "{section} `{key}` = {value}: a whole number of {} (a fraction is not rounded)",
                setting.unit()
            ));
        }
        settings.set(setting, value);
    }
    Ok(settings)
}

/// A settings file: flat keys, as a scene's `[controller]` table, and optionally the board's
/// `[front_end]` (none: a board without analog inputs).
pub fn load(path: &Path, target_hz: Option<f32>) -> Result<(Settings, FrontEnd), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read settings file {}: {e}", path.display()))?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e| format!("settings file {}: {e}", path.display()))?;
    let section = format!("settings file {}:", path.display());
    let front_end = match table.remove("front_end") {
        Some(toml::Value::Table(t)) => front_end(&t, &format!("{section} [front_end]"), 0.0)?,
        Some(other) => {
            return Err(format!(
                "{section} front_end must be a table, not a {}",
                other.type_str()
            ))
        }
        None => FrontEnd::NONE,
    };
    Ok((from_table(&table, &section, target_hz)?, front_end))
}

/// The keys of a channel's table in `[front_end]`: the wiring (every one needed), then
/// `noise_codes` (optional).
const CHANNEL_KEYS: [&str; 6] = [
    "input",
    "zero_code",
    "per_count",
    "low",
    "high",
    "noise_codes",
];
/// How many of `CHANNEL_KEYS` a channel needs.
const WIRING_KEYS: usize = 5;

/// A `[front_end]` table: `scan_hz`, and a table per fitted channel (`current`, `amplifier`,
/// `stretch`) with every wiring key of `CHANNEL_KEYS` (a front end is wiring: nothing
/// defaulted) and its RMS noise a conversion, `noise_codes` (`default_noise_codes` if left
/// out). The core checks it when the image is made.
pub fn front_end(
    table: &toml::Table,
    section: &str,
    default_noise_codes: f32,
) -> Result<FrontEnd, String> {
    let mut front_end = FrontEnd::NONE;
    for (key, value) in table {
        if key == "scan_hz" {
            front_end.scan_hz = number(&format!("{section} scan_hz"), value)?;
            continue;
        }
        let Some(k) = Channel::ALL.iter().position(|c| c.name() == key) else {
            let names: Vec<&str> = Channel::ALL.iter().map(|c| c.name()).collect();
            return Err(format!(
                "{section} unknown key `{key}`, expected scan_hz or a channel: {}",
                names.join(", ")
            ));
        };
        let toml::Value::Table(t) = value else {
            return Err(format!(
                "{section} {key} must be a table of {}",
                CHANNEL_KEYS.join(", ")
            ));
        };
        let mut values = [0.0, 0.0, 0.0, 0.0, 0.0, default_noise_codes];
        for (name, v) in t {
            let Some(i) = CHANNEL_KEYS.iter().position(|n| n == name) else {
                return Err(format!(
                    "{section} {key}: unknown key `{name}`, expected {}",
                    CHANNEL_KEYS.join(", ")
                ));
            };
            values[i] = number(&format!("{section} {key}.{name}"), v)?;
        }
        let wiring = CHANNEL_KEYS.get(..WIRING_KEYS).unwrap_or(&CHANNEL_KEYS);
        if let Some(missing) = wiring.iter().find(|n| !t.contains_key(**n)) {
            return Err(format!("{section} {key} needs `{missing}`"));
        }
        let [input, zero_code, per_count, low, high, noise_codes] = values;
        let highest = f32::from(de_resonator::acquire::MAX_INPUT);
        if !((0.0..=highest).contains(&input) && input.fract() == 0.0) {
            return Err(format!(
                "{section} {key}.input must be an ADC input, 0 to {highest}, not {input}"
            ));
        }
        front_end.channels[k] = Some(ChannelSpec {
            input: input as u8,
            zero_code,
            per_count,
            low,
            high,
            noise_codes,
        });
    }
    if !front_end.is_empty() && !table.contains_key("scan_hz") {
        return Err(format!("{section} needs scan_hz (scans a second)"));
    }
    Ok(front_end)
}
