//! Device files: TOML, SI units, flat keys named as the fields of `DeviceParams`; every key
//! optional, defaulting to the reference device of MODEL.md §9. Unknown keys are an error.

use std::path::Path;

use de_resonator::{DeviceParams, REFERENCE_DEVICE};
use serde::Deserialize;

/// The file's keys; an absent key takes the reference device's value.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct DeviceFile {
    shear_modulus: Option<f64>,
    jlim: Option<f64>,
    relative_permittivity: Option<f64>,
    density: Option<f64>,
    breakdown_field: Option<f64>,
    thickness: Option<f64>,
    length_active: Option<f64>,
    length_passive: Option<f64>,
    width: Option<f64>,
    bar_mass: Option<f64>,
    prestretch_1: Option<f64>,
    prestretch_2: Option<f64>,
    damping: Option<f64>,
}

/// Parse a device file's text. Errors are one line: `line N: what is wrong`.
pub fn parse(text: &str) -> Result<DeviceParams<f64>, String> {
    let file: DeviceFile = toml::from_str(text).map_err(|e| {
        let message = e.message().trim().replace('\n', " ");
        match e.span() {
            Some(span) => {
                let before = text.get(..span.start).unwrap_or(text);
                let line = before.matches('\n').count() + 1;
                format!("line {line}: {message}")
            }
            None => message,
        }
    })?;
    let r = REFERENCE_DEVICE;
    Ok(DeviceParams {
        shear_modulus: file.shear_modulus.unwrap_or(r.shear_modulus),
        // Absent means neo-Hookean (Jlim = ∞), not the reference's 120.
        jlim: file.jlim,
        relative_permittivity: file
            .relative_permittivity
            .unwrap_or(r.relative_permittivity),
        density: file.density.unwrap_or(r.density),
        breakdown_field: file.breakdown_field.unwrap_or(r.breakdown_field),
        thickness: file.thickness.unwrap_or(r.thickness),
        length_active: file.length_active.unwrap_or(r.length_active),
        length_passive: file.length_passive.unwrap_or(r.length_passive),
        width: file.width.unwrap_or(r.width),
        bar_mass: file.bar_mass.unwrap_or(r.bar_mass),
        prestretch_1: file.prestretch_1.unwrap_or(r.prestretch_1),
        prestretch_2: file.prestretch_2.unwrap_or(r.prestretch_2),
        damping: file.damping.unwrap_or(r.damping),
    })
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
