//! The four physiological parameters of Donner & Jensen 2006 (DJ2006 parameter table; docs/model.md, section
//! Parameters) and the named presets.

use serde::{Deserialize, Serialize};

use crate::error::{check_range, SkinError};

/// Allowed range of the melanin volume fraction `C_m` in the epidermis (DJ2006 parameter table; docs/model.md, section
/// Parameters).
pub const MELANIN_RANGE: (f64, f64) = (0.0, 0.5);
/// Allowed range of the eumelanin share `beta_m` (1 - beta_m is pheomelanin).
pub const MELANIN_BLEND_RANGE: (f64, f64) = (0.0, 1.0);
/// Allowed range of the whole-blood volume fraction `C_h` in the dermis. DJ2006 gives 0.001..0.1; 0 is accepted (no blood).
pub const HEMOGLOBIN_RANGE: (f64, f64) = (0.0, 0.1);
/// Allowed range of the oiliness `rho_s` that scales the Torrance-Sparrow surface lobe.
pub const OILINESS_RANGE: (f64, f64) = (0.0, 1.0);

/// Validated skin parameters. Construct with [`SkinParams::new`] or [`SkinParams::preset`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SkinParams {
    /// `C_m`: melanin volume fraction in the epidermis, 0..0.5.
    pub melanin: f64,
    /// `beta_m`: eumelanin share of the melanin, 0..1.
    pub melanin_blend: f64,
    /// `C_h`: whole-blood volume fraction in the dermis, 0..0.1.
    pub hemoglobin: f64,
    /// `rho_s`: oiliness, scales the specular lobe, 0..1.
    pub oiliness: f64,
}

impl SkinParams {
    /// Validate the four parameters; the error names the first parameter out of range and its range.
    pub fn new(melanin: f64, melanin_blend: f64, hemoglobin: f64, oiliness: f64) -> Result<Self, SkinError> {
        Ok(SkinParams {
            melanin: check_range("melanin", "melanin fraction C_m", melanin, MELANIN_RANGE.0, MELANIN_RANGE.1)?,
            melanin_blend: check_range(
                "melanin_blend",
                "eumelanin share beta_m",
                melanin_blend,
                MELANIN_BLEND_RANGE.0,
                MELANIN_BLEND_RANGE.1,
            )?,
            hemoglobin: check_range(
                "hemoglobin",
                "blood fraction C_h",
                hemoglobin,
                HEMOGLOBIN_RANGE.0,
                HEMOGLOBIN_RANGE.1,
            )?,
            oiliness: check_range("oiliness", "oiliness rho_s", oiliness, OILINESS_RANGE.0, OILINESS_RANGE.1)?,
        })
    }

    /// A named preset (case-insensitive); the error lists the known names.
    pub fn preset(name: &str) -> Result<Self, SkinError> {
        PRESETS.iter().find(|p| p.name.eq_ignore_ascii_case(name)).map(|p| p.params).ok_or_else(|| {
            let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
            SkinError::invalid("preset", format!("unknown preset {name:?}; known presets: {}", names.join(", ")))
        })
    }
}

/// A named parameter set with its source.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Preset {
    pub name: &'static str,
    pub description: &'static str,
    pub params: SkinParams,
}

const fn preset(name: &'static str, description: &'static str, c_m: f64, beta_m: f64, c_h: f64, oil: f64) -> Preset {
    Preset {
        name,
        description,
        params: SkinParams { melanin: c_m, melanin_blend: beta_m, hemoglobin: c_h, oiliness: oil },
    }
}

/// The presets. The first three are the skin types of the SIGGRAPH 2006 sketch (Donner & Jensen, teaser caption;
/// docs/model.md, section Parameters).
pub const PRESETS: &[Preset] = &[
    preset("caucasian", "Caucasian skin type, DJ2006 sketch teaser caption", 0.005, 0.7, 0.005, 0.3),
    preset("asian", "Asian skin type, DJ2006 sketch teaser caption", 0.15, 0.0, 0.01, 0.3),
    preset("african", "African skin type, DJ2006 sketch teaser caption", 0.50, 0.7, 0.05, 0.3),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate() {
        for p in PRESETS {
            let q = p.params;
            assert_eq!(SkinParams::new(q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness).unwrap(), q);
        }
    }

    #[test]
    fn out_of_range_names_parameter_and_range() {
        let e = SkinParams::new(0.6, 0.5, 0.01, 0.3).unwrap_err().to_string();
        assert!(e.contains("melanin") && e.contains("[0, 0.5]") && e.contains("0.6"), "{e}");
        let e = SkinParams::new(0.1, 0.5, f64::NAN, 0.3).unwrap_err().to_string();
        assert!(e.contains("hemoglobin") && e.contains("NaN"), "{e}");
        assert!(SkinParams::preset("martian").unwrap_err().to_string().contains("caucasian"));
        assert!(SkinParams::preset("Caucasian").is_ok());
    }
}
