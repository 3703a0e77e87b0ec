//! Device files: TOML, SI units, flat keys named as the fields of `DeviceParams`; every key
//! optional, defaulting to the reference device of model.md §9. Unknown keys are an error.
//! An optional `[tolerance]` table gives the batch (model.md §10): each key a device key,
//! its value a relative ± fraction (`shear_modulus = 0.10`) or an absolute range
//! `[low, high]` in SI units (`breakdown_field = [35e6, 200e6]`).

use std::collections::BTreeMap;
use std::path::Path;

use de_resonator::model::tolerance::{DeviceBox, Spread};
use de_resonator::{DeviceParams, Field, REFERENCE_DEVICE};
use toml::Spanned;

/// What a device file left out and what in it no real membrane has: said on stderr, never an
/// error (the model's own checks refuse what it cannot use).
#[derive(Debug, Default, PartialEq)]
pub struct Notes {
    /// Keys not given: the reference device's values were taken (`jlim` aside).
    pub defaulted: Vec<Field>,
    /// `jlim` not given: the material is neo-Hookean.
    pub neo_hookean: bool,
    /// Values outside the range any real membrane has, each said with its unit and range.
    pub implausible: Vec<String>,
}

/// The range any real DE membrane and its bars have, per field, in SI, and the unit: wider
/// than any device built (VHB, silicones, acrylics, thin films), so a value outside it is a
/// unit slip (mm for m) or a typo, not a design.
fn plausible(field: Field) -> Option<(f64, f64, &'static str)> {
    Some(match field {
        Field::ShearModulus => (1e3, 1e7, "Pa"),
        Field::Jlim => (2.0, 1e4, ""),
        Field::RelativePermittivity => (1.0, 100.0, ""),
        Field::Density => (300.0, 5000.0, "kg/m³"),
        Field::BreakdownField => (1e6, 2e9, "V/m"),
        Field::Thickness => (1e-6, 5e-3, "m"),
        Field::LengthActive | Field::LengthPassive | Field::Width => (1e-4, 1.0, "m"),
        Field::BarMass => (0.0, 1.0, "kg"),
        Field::Prestretch1 | Field::Prestretch2 => (1.0, 10.0, ""),
        Field::Damping => return None,
    })
}

/// Parse a device file's text: its keys are `Field::ALL`'s (the core's one list), each a
/// number; an absent key takes the reference device's value, except `jlim` (absent:
/// neo-Hookean). Errors are one line: `line N: what is wrong`.
pub fn parse(text: &str) -> Result<DeviceParams<f64>, String> {
    parse_noting(text).map(|(params, _)| params)
}

/// A device file's text for `params`, what [`parse`] reads back: every key, a line each,
/// `jlim` left out for a neo-Hookean membrane (for scenes and tests that write a device).
pub fn text(params: &DeviceParams<f64>) -> String {
    Field::ALL
        .into_iter()
        .filter(|&field| !(field == Field::Jlim && params.jlim.is_none()))
        .map(|field| format!("{} = {:e}\n", field.key(), params.get(field)))
        .collect()
}

/// [`parse`], and what the file left out or holds that no real membrane has.
pub fn parse_noting(text: &str) -> Result<(DeviceParams<f64>, Notes), String> {
    parse_box_noting(text).map(|(b, notes)| (b.nominal, notes))
}

/// The device and its `[tolerance]` table: the batch of devices the file declares (the
/// nominal device alone without one).
pub fn parse_box(text: &str) -> Result<DeviceBox, String> {
    parse_box_noting(text).map(|(b, _)| b)
}

/// [`parse_box`], and what the file left out or holds that no real membrane has.
pub fn parse_box_noting(text: &str) -> Result<(DeviceBox, Notes), String> {
    let line_of = |at: usize| text.get(..at).unwrap_or(text).matches('\n').count() + 1;
    let file: BTreeMap<Spanned<String>, Spanned<toml::Value>> =
        toml::from_str(text).map_err(|e| {
            let message = e.message().trim().replace('\n', " ");
            match e.span() {
                Some(span) => format!("line {}: {message}", line_of(span.start)),
                None => message,
            }
        })?;
    let tolerance = file.iter().find(|(key, _)| key.get_ref() == TOLERANCE);
    let given: Vec<Entry> = file
        .iter()
        .filter(|(key, _)| key.get_ref() != TOLERANCE)
        .map(|(key, value)| {
            let number = match value.get_ref() {
                toml::Value::Float(x) => Ok(*x),
                toml::Value::Integer(n) => Ok(*n as f64),
                other => Err(other.type_str()),
            };
            (
                key.get_ref().as_str(),
                number,
                Some(line_of(key.span().start)),
            )
        })
        .collect();
    let (nominal, notes) = build(&given)?;
    let b = match tolerance {
        None => DeviceBox::exact(nominal),
        Some((key, value)) => {
            let toml::Value::Table(table) = value.get_ref() else {
                return Err(format!(
                    "line {}: `{TOLERANCE}` is a table: [{TOLERANCE}] and then a line a key",
                    line_of(key.span().start)
                ));
            };
            let spreads: Vec<(String, Result<Spread, String>)> = table
                .iter()
                .map(|(k, v)| (k.clone(), spread_of(v)))
                .collect();
            let at = format!("line {}: ", line_of(value.span().start));
            with_tolerances(nominal, &spreads).map_err(|e| format!("{at}{e}"))?
        }
    };
    Ok((b, notes))
}

/// The `[tolerance]` table's name in device files and scenes' `[device]`.
pub const TOLERANCE: &str = "tolerance";

/// A tolerance's TOML value: a number is a relative ± fraction, `[low, high]` a range.
fn spread_of(value: &toml::Value) -> Result<Spread, String> {
    let number = |v: &toml::Value| match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(n) => Some(*n as f64),
        _ => None,
    };
    if let Some(x) = number(value) {
        return Ok(Spread::Relative(x));
    }
    if let toml::Value::Array(ends) = value {
        if let [low, high] = ends.as_slice() {
            if let (Some(low), Some(high)) = (number(low), number(high)) {
                return Ok(Spread::Range { low, high });
            }
        }
    }
    Err(format!(
        "a tolerance is a fraction (0.1 for ±10%) or a range [low, high], not a {}",
        value.type_str()
    ))
}

/// The batch about `nominal` with each `(key, spread)`: keys are device keys, each once.
pub fn with_tolerances(
    nominal: DeviceParams<f64>,
    spreads: &[(String, Result<Spread, String>)],
) -> Result<DeviceBox, String> {
    let mut b = DeviceBox::exact(nominal);
    for (key, spread) in spreads {
        let field = Field::from_key(key).ok_or_else(|| {
            format!("[{TOLERANCE}]: unknown field `{key}`, expected a device key")
        })?;
        let spread = spread
            .clone()
            .map_err(|e| format!("[{TOLERANCE}] `{key}`: {e}"))?;
        b = b
            .with(field, spread)
            .map_err(|e| format!("[{TOLERANCE}]: {e}"))?;
    }
    b.check().map_err(|e| format!("[{TOLERANCE}]: {e}"))?;
    Ok(b)
}

/// A key, its value (or the TOML type it has instead of a number) and its line.
type Entry<'a> = (&'a str, Result<f64, &'static str>, Option<usize>);

/// A device from its keys and values (the device file's, in SI units; the Python package's
/// keyword arguments), on the rules of [`parse`]: an absent key takes the reference device's
/// value, an absent `jlim` makes it neo-Hookean.
pub fn from_keys(keys: &[(&str, f64)]) -> Result<(DeviceParams<f64>, Notes), String> {
    let given: Vec<Entry> = keys.iter().map(|&(k, v)| (k, Ok(v), None)).collect();
    build(&given)
}

/// [`parse_noting`]'s and [`from_keys`]'s work: each key, its value and the line it is on
/// (for the error).
fn build(entries: &[Entry]) -> Result<(DeviceParams<f64>, Notes), String> {
    let mut params = DeviceParams {
        jlim: None,
        ..REFERENCE_DEVICE
    };
    let mut given = Vec::new();
    for &(key, number, line) in entries {
        let at = line.map_or(String::new(), |line| format!("line {line}: "));
        let field = Field::from_key(key).ok_or_else(|| {
            let keys: Vec<String> = Field::ALL
                .iter()
                .map(|f| format!("`{}`", f.key()))
                .collect();
            format!(
                "{at}unknown field `{key}`, expected one of {}",
                keys.join(", ")
            )
        })?;
        let number = number
            .map_err(|kind| format!("{at}`{}` must be a number, not a {kind}", field.key()))?;
        if given.contains(&field) {
            return Err(format!("{at}`{key}` is given twice"));
        }
        params.set(field, number);
        if field == Field::Jlim {
            // Written out, jlim is the Gent limit, whatever its value (0 is refused later).
            params.jlim = Some(number);
        }
        given.push(field);
    }
    let mut notes = Notes {
        neo_hookean: !given.contains(&Field::Jlim),
        ..Notes::default()
    };
    for field in Field::ALL {
        if !given.contains(&field) {
            if field != Field::Jlim {
                notes.defaulted.push(field);
            }
            continue;
        }
        let value = params.get(field);
        if let Some((low, high, unit)) = plausible(field) {
            if value.is_finite() && !(low..=high).contains(&value) {
                let unit = if unit.is_empty() {
                    String::new()
                } else {
                    format!(" {unit}")
                };
                // Short, exact numbers: 1e-6 rather than 0.000001.
                let said = |x: f64| {
                    if x != 0.0 && !(1e-3..1e4).contains(&x.abs()) {
                        format!("{x:e}")
                    } else {
                        format!("{x}")
                    }
                };
                notes.implausible.push(format!(
                    "`{}` = {}{unit} is outside what any real membrane has ({}{unit} .. \
                     {}{unit}; the file is read in SI units)",
                    field.key(),
                    said(value),
                    said(low),
                    said(high)
                ));
            }
        }
    }
    Ok((params, notes))
}

/// Read and parse a device file; errors name the file. What it left out (the reference
/// device's values taken, neo-Hookean without `jlim`) is noted on stderr, and a value no
/// real membrane has is warned of (for a device the model accepts: a refused one is said
/// by its refusal).
pub fn load(path: &Path) -> Result<DeviceParams<f64>, String> {
    load_box(path).map(|b| b.nominal)
}

/// [`load`] with the file's `[tolerance]` table: the batch it declares.
pub fn load_box(path: &Path) -> Result<DeviceBox, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read device file {}: {e}", path.display()))?;
    let (b, notes) =
        parse_box_noting(&text).map_err(|e| format!("device file {}: {e}", path.display()))?;
    let name = path.display();
    // A device the model refuses is said by its refusal alone (one line).
    if de_resonator::Device::new(b.nominal).is_err() {
        return Ok(b);
    }
    if !notes.defaulted.is_empty() {
        let keys: Vec<&str> = notes.defaulted.iter().map(|f| f.key()).collect();
        eprintln!(
            "note: device file {name}: not given, the reference device's values taken: {}",
            keys.join(", ")
        );
    }
    if notes.neo_hookean {
        eprintln!("note: device file {name}: no `jlim`: the material is neo-Hookean");
    }
    for warning in &notes.implausible {
        eprintln!("warning: device file {name}: {warning}");
    }
    Ok(b)
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

    /// What `text` writes, `parse` reads back exactly: a Gent device and a neo-Hookean one.
    #[test]
    fn text_reads_back_as_the_device() {
        let gent = DeviceParams {
            shear_modulus: 51_234.567_891,
            prestretch_1: 1.0 / 3.0,
            ..REFERENCE_DEVICE
        };
        let neo = DeviceParams { jlim: None, ..gent };
        for params in [gent, neo] {
            assert_eq!(parse(&text(&params)).unwrap(), params);
        }
        assert!(!text(&neo).contains("jlim"));
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

    /// Issue 29, 7: what the file leaves out is noted, and values no membrane has (metres
    /// for millimetres, a breakdown field of 1 V/m) are warned of, with the unit.
    #[test]
    fn left_out_keys_and_absurd_values_are_noted() {
        let (_, notes) = parse_noting("thickness = 50\nbreakdown_field = 1\n").unwrap();
        assert!(notes.neo_hookean);
        assert_eq!(notes.defaulted.len(), Field::ALL.len() - 3);
        assert!(!notes.defaulted.contains(&Field::Thickness));
        assert_eq!(notes.implausible.len(), 2, "{:?}", notes.implausible);
        assert!(notes.implausible[0].starts_with("`breakdown_field` = 1 V/m"));
        assert!(notes.implausible[1].starts_with("`thickness` = 50 m is outside"));
        // The shipped devices are all plausible, and the reference file leaves nothing out.
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../devices");
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let text = std::fs::read_to_string(&path).unwrap();
            let (_, notes) = parse_noting(&text).unwrap();
            assert!(
                notes.implausible.is_empty(),
                "{}: {notes:?}",
                path.display()
            );
        }
        let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("../devices/reference.toml");
        let (_, notes) = parse_noting(&std::fs::read_to_string(reference).unwrap()).unwrap();
        assert_eq!(notes, Notes::default());
    }

    #[test]
    fn nested_tables_are_not_device_keys() {
        assert!(parse("[device]\nthickness = 1e-3\n").is_err());
    }

    /// A `[tolerance]` table: fractions and ranges, as the box's ends.
    #[test]
    fn the_tolerance_table_is_the_batch() {
        let b = parse_box(
            "jlim = 120\n[tolerance]\nshear_modulus = 0.1\nbreakdown_field = [35e6, 200e6]\n",
        )
        .unwrap();
        assert_eq!(b.nominal.shear_modulus, 45e3);
        assert_eq!(b.low.shear_modulus, 40.5e3);
        assert!((b.high.shear_modulus - 49.5e3).abs() < 1e-9);
        assert_eq!(
            (b.low.breakdown_field, b.high.breakdown_field),
            (35e6, 200e6)
        );
        assert_eq!(b.low.thickness, b.high.thickness);
        // No table: the nominal device alone, as before.
        assert!(parse_box("jlim = 120\n").unwrap().is_exact());
    }

    /// Each way a tolerance is wrong, said with its line and key.
    #[test]
    fn bad_tolerances_are_refused_with_their_line() {
        for (text, says) in [
            (
                "[tolerance]\nshear_modulos = 0.1\n",
                "unknown field `shear_modulos`",
            ),
            ("[tolerance]\nshear_modulus = 1.5\n", "fraction in [0, 1)"),
            ("[tolerance]\nshear_modulus = \"ten\"\n", "not a string"),
            ("[tolerance]\nbreakdown_field = [2e8, 1e8]\n", "low ≤ high"),
            (
                "[tolerance]\nbreakdown_field = [1e6, 2e6]\n",
                "does not hold the device's own",
            ),
            ("[tolerance]\njlim = 0.1\n", "neo-Hookean"),
            ("tolerance = 0.1\n", "is a table"),
        ] {
            let e = parse_box(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
            assert!(e.starts_with("line "), "{text}: {e}");
        }
    }
}
