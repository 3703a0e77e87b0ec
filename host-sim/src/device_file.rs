//! Device files: TOML, SI units, flat keys named as the fields of `DeviceParams`; every key
//! optional, defaulting to the reference device of model.md §9. Unknown keys are an error.

use std::collections::BTreeMap;
use std::path::Path;

use de_resonator::{DeviceParams, Field, REFERENCE_DEVICE};
use toml::Spanned;

/// Parse a device file's text: its keys are `Field::ALL`'s (the core's one list), each a
/// number; an absent key takes the reference device's value, except `jlim` (absent:
/// neo-Hookean). Errors are one line: `line N: what is wrong`.
pub fn parse(text: &str) -> Result<DeviceParams<f64>, String> {
    let line_of = |at: usize| text.get(..at).unwrap_or(text).matches('\n').count() + 1;
    let file: BTreeMap<Spanned<String>, Spanned<toml::Value>> =
        toml::from_str(text).map_err(|e| {
            let message = e.message().trim().replace('\n', " ");
            match e.span() {
                Some(span) => format!("line {}: {message}", line_of(span.start)),
                None => message,
            }
        })?;
    let mut params = DeviceParams {
        jlim: None,
        ..REFERENCE_DEVICE
    };
    for (key, value) in &file {
        let line = line_of(key.span().start);
        let field = Field::from_key(key.get_ref()).ok_or_else(|| {
            let keys: Vec<String> = Field::ALL
                .iter()
                .map(|f| format!("`{}`", f.key()))
                .collect();
            format!(
                "line {line}: unknown field `{}`, expected one of {}",
                key.get_ref(),
                keys.join(", ")
            )
        })?;
        let number = match value.get_ref() {
            toml::Value::Float(x) => *x,
            toml::Value::Integer(n) => *n as f64,
            other => {
                return Err(format!(
                    "line {line}: `{}` must be a number, not a {}",
                    field.key(),
                    other.type_str()
                ))
            }
        };
        params.set(field, number);
        if field == Field::Jlim {
            // Written out, jlim is the Gent limit, whatever its value (0 is refused later).
            params.jlim = Some(number);
        }
    }
    Ok(params)
}

/// Read and parse a device file; errors name the file.
pub fn load(path: &Path) -> Result<DeviceParams<f64>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read device file {}: {e}", path.display()))?;
    parse(&text).map_err(|e| format!("device file {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_file_is_the_reference_device_but_neo_hookean() {
        let p = parse("").unwrap();
        assert_eq!(
            p,
            DeviceParams {
                jlim: None,
                ..REFERENCE_DEVICE
            }
        );
    }

    #[test]
    fn the_shipped_reference_file_is_the_built_in_device() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../devices/reference.toml");
        assert_eq!(load(&path).unwrap(), REFERENCE_DEVICE);
    }

    #[test]
    fn keys_override_the_reference() {
        let p = parse("jlim = 120\nprestretch_1 = 3.0\nbar_mass = 0.0\n").unwrap();
        assert_eq!(p.prestretch_1, 3.0);
        assert_eq!(p.bar_mass, 0.0);
        assert_eq!(p.jlim, Some(120.0));
        assert_eq!(p.width, REFERENCE_DEVICE.width);
    }

    #[test]
    fn integers_are_accepted_for_floats() {
        assert_eq!(parse("shear_modulus = 45000").unwrap().shear_modulus, 45e3);
    }

    #[test]
    fn unknown_key_is_an_error_naming_it_and_its_line() {
        let e = parse("thickness = 1e-3\nshear_modulos = 4e4\n").unwrap_err();
        assert!(e.contains("shear_modulos"), "{e}");
        assert!(e.starts_with("line 2:"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn wrong_type_is_an_error() {
        let e = parse("thickness = \"thin\"\n").unwrap_err();
        assert!(e.starts_with("line 1:"), "{e}");
    }

    #[test]
    fn nested_tables_are_not_device_keys() {
        assert!(parse("[device]\nthickness = 1e-3\n").is_err());
    }
}
