//! Controller settings in TOML: the keys of the core's `Setting` list (one list for scenes,
//! settings files and the command port), numbers, `Settings::for_target`'s defaults for the
//! keys left out.

use std::path::Path;

use de_resonator::{Setting, Settings};

/// `table` (a scene's `[controller]`, or a settings file: `section` names it in errors) as
/// `Settings`; `target_hz` from the table, else `target_hz`, else an error.
pub fn from_table(
    table: &toml::Table,
    section: &str,
    target_hz: Option<f32>,
) -> Result<Settings, String> {
    let number = |key: &str, value: &toml::Value| match value {
        toml::Value::Float(x) => Ok(*x as f32),
        toml::Value::Integer(n) => Ok(*n as f32),
        other => Err(format!(
            "{section} {key} must be a number, not a {}",
            other.type_str()
        )),
    };
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
        settings.set(setting, number(key, value)?);
    }
    Ok(settings)
}

/// A settings file: flat keys, as a scene's `[controller]` table.
pub fn load(path: &Path, target_hz: Option<f32>) -> Result<Settings, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read settings file {}: {e}", path.display()))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e| format!("settings file {}: {e}", path.display()))?;
    from_table(
        &table,
        &format!("settings file {}:", path.display()),
        target_hz,
    )
}
