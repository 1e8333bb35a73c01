//! The four physiological parameters of Donner & Jensen 2006 (DJ2006 parameter table; docs/model.md, section
//! Parameters) and the named presets.

use serde::{Deserialize, Serialize};

use crate::error::{check_range, SkinError};

/// One parameter of the model, defined once: its name (the Python keyword, CLI flag stem with `-` for `_`, map
/// channel), DJ2006's symbol, a UI label, its meaning, unit and allowed range, and the source. [`SkinParams::new`]
/// validates with it; the CLI's help, Python's `parameters()` / `parameter_ranges()` and the Blender add-on's sliders
/// and tooltips are derived from it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamSpec {
    /// The parameter's name: Python keyword, `SkinParams` field, parameter-map channel; the CLI flag is `--` and the
    /// name with `-` for `_`.
    pub name: &'static str,
    /// DJ2006's symbol, ASCII-spelled (`beta_m` for the Greek letter).
    pub symbol: &'static str,
    /// A short title for user interfaces.
    pub label: &'static str,
    /// What the parameter is (a noun phrase, lower case).
    pub description: &'static str,
    /// What changing it does to the skin, in words, with the presets' context.
    pub effect: &'static str,
    /// The unit; empty for a dimensionless fraction, share or scale.
    pub unit: &'static str,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// The value when the parameter is not given; None for one that must be given (by value or by a preset).
    pub default: Option<f64>,
    /// Where the meaning and the range come from.
    pub source: &'static str,
}

impl ParamSpec {
    /// `(min, max)`.
    pub const fn range(&self) -> (f64, f64) {
        (self.min, self.max)
    }

    /// `value` if finite and in range, else an error naming the parameter, its meaning and its range.
    pub fn check(&self, value: f64) -> Result<f64, SkinError> {
        check_range(self.name, self.description, value, self.min, self.max)
    }

    /// The meaning with symbol and range, one line: "melanin volume fraction of the epidermis, C_m, 0..0.5" (the
    /// CLI's help; the add-on's tooltips add the effect).
    pub fn summary(&self) -> String {
        let unit = if self.unit.is_empty() { String::new() } else { format!(" {}", self.unit) };
        format!("{}, {}, {}..{}{unit}", self.description, self.symbol, self.min, self.max)
    }
}

/// The source of the four parameters of DJ2006.
const DJ2006_PARAMETERS: &str = "Donner & Jensen 2006, parameter table; docs/model.md, section Parameters";

/// `C_m`: the melanin volume fraction of the epidermis.
pub const MELANIN: ParamSpec = ParamSpec {
    name: "melanin",
    symbol: "C_m",
    label: "Melanin",
    description: "melanin volume fraction of the epidermis",
    effect: "from fair (0.005, the caucasian preset) to very dark (0.5, the african preset) skin",
    unit: "",
    min: 0.0,
    max: 0.5,
    default: None,
    source: DJ2006_PARAMETERS,
};

/// `beta_m`: the eumelanin share of the melanin (1 - beta_m is pheomelanin).
pub const MELANIN_BLEND: ParamSpec = ParamSpec {
    name: "melanin_blend",
    symbol: "beta_m",
    label: "Melanin Blend",
    description: "eumelanin share of the melanin (the rest is pheomelanin)",
    effect: "0 is all red-yellow pheomelanin, 1 all brown-black eumelanin",
    unit: "",
    min: 0.0,
    max: 1.0,
    default: None,
    source: DJ2006_PARAMETERS,
};

/// `C_h`: the whole-blood volume fraction of the dermis. DJ2006 gives 0.001..0.1; 0 is accepted (no blood).
pub const HEMOGLOBIN: ParamSpec = ParamSpec {
    name: "hemoglobin",
    symbol: "C_h",
    label: "Haemoglobin",
    description: "whole-blood volume fraction of the dermis",
    effect: "more blood gives redder skin",
    unit: "",
    min: 0.0,
    max: 0.1,
    default: None,
    source: "Donner & Jensen 2006, parameter table (0.001..0.1; 0, no blood, is accepted too); docs/model.md, \
             section Parameters",
};

/// `rho_s`: the oiliness, which scales the Torrance-Sparrow surface lobe.
pub const OILINESS: ParamSpec = ParamSpec {
    name: "oiliness",
    symbol: "rho_s",
    label: "Oiliness",
    description: "scale of the surface's specular lobe (the oil layer)",
    effect: "0 is a surface without highlight, 1 the full oil layer's (in Blender: Specular IOR Level and Roughness)",
    unit: "",
    min: 0.0,
    max: 1.0,
    default: None,
    source: DJ2006_PARAMETERS,
};

/// Every parameter, in the order of [`SkinParams`]' fields (and of the parameter-map channels). Parameters with a
/// default can be added as rows.
pub const PARAMS: [ParamSpec; 4] = [MELANIN, MELANIN_BLEND, HEMOGLOBIN, OILINESS];

/// The spec of the parameter called `name`.
pub fn param_spec(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

/// Validated skin parameters. Construct with [`SkinParams::new`] or [`SkinParams::preset`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SkinParams {
    /// [`MELANIN`].
    pub melanin: f64,
    /// [`MELANIN_BLEND`].
    pub melanin_blend: f64,
    /// [`HEMOGLOBIN`].
    pub hemoglobin: f64,
    /// [`OILINESS`].
    pub oiliness: f64,
}

impl SkinParams {
    /// Validate the four parameters against [`PARAMS`]; the error names the first parameter out of range and its range.
    pub fn new(melanin: f64, melanin_blend: f64, hemoglobin: f64, oiliness: f64) -> Result<Self, SkinError> {
        Ok(SkinParams {
            melanin: MELANIN.check(melanin)?,
            melanin_blend: MELANIN_BLEND.check(melanin_blend)?,
            hemoglobin: HEMOGLOBIN.check(hemoglobin)?,
            oiliness: OILINESS.check(oiliness)?,
        })
    }

    /// The values in [`PARAMS`] order.
    pub fn values(&self) -> [f64; 4] {
        [self.melanin, self.melanin_blend, self.hemoglobin, self.oiliness]
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
    fn specs_name_the_fields_in_order_and_bound_validation() {
        // The serialised field names of SkinParams, in declaration order, are the spec names.
        let json = serde_json::to_string(&PRESETS[0].params).unwrap();
        let mut at = 0;
        for spec in PARAMS {
            let found = json[at..].find(&format!("\"{}\":", spec.name)).expect(spec.name);
            at += found + 1;
        }
        // Each spec's max is accepted and the next double above it rejected by SkinParams::new.
        let mid = [0.1, 0.5, 0.01, 0.3];
        for (i, spec) in PARAMS.iter().enumerate() {
            let mut v = mid;
            v[i] = spec.max;
            assert!(SkinParams::new(v[0], v[1], v[2], v[3]).is_ok(), "{}", spec.name);
            v[i] = f64::from_bits(spec.max.to_bits() + 1);
            let e = SkinParams::new(v[0], v[1], v[2], v[3]).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{} must be in", spec.name)), "{e}");
        }
        assert_eq!(param_spec("hemoglobin").map(|s| s.max), Some(0.1));
        // values() is in PARAMS order: each value is the field of that name.
        let q = SkinParams::new(0.1, 0.2, 0.03, 0.4).unwrap();
        let fields = serde_json::to_value(q).unwrap();
        for (spec, value) in PARAMS.iter().zip(q.values()) {
            assert_eq!(fields[spec.name].as_f64(), Some(value), "{}", spec.name);
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
