//! The physiological parameters: the four of Donner & Jensen 2006 (DJ2006 parameter table; docs/model.md, section
//! Parameters), the extended physiology beside them (each defaulting to the paper's fixed value; docs/model.md,
//! section Extended physiology), and the named presets.

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

/// The source of the extended physiology's defaults and ranges.
const EXTENDED_SOURCE: &str = "default: the value DJ2006 fixes; range: docs/model.md, section Extended physiology";

/// The epidermis thickness, mm. DJ2006 fix 0.25 mm; in-vivo epidermis over most of the body and face is thinner (about
/// 0.05-0.1 mm by optical coherence tomography, Sandby-Moller, Poulsen & Wulf 2003, Acta Derm. Venereol. 83:410), which
/// is what fits of measured spectra find (docs/measured-skin.md). The range spans both with margin.
pub const EPIDERMIS_THICKNESS: ParamSpec = ParamSpec {
    name: "epidermis_thickness_mm",
    symbol: "d_epi",
    label: "Epidermis Thickness",
    description: "thickness of the epidermis",
    effect: "a thinner epidermis holds less melanin and lets the dermis's blood show: redder, more saturated skin",
    unit: "mm",
    min: 0.01,
    max: 0.5,
    default: Some(0.25),
    source: EXTENDED_SOURCE,
};

/// A scale on the melanin- and blood-free tissue absorption of DJ2006 eq. 5 (Jacques 1998), in both layers. 1 is the
/// paper; fits of measured spectra ask for more blue absorption than eq. 5 gives (docs/measured-skin.md).
pub const BASELINE_ABSORPTION_SCALE: ParamSpec = ParamSpec {
    name: "baseline_absorption_scale",
    symbol: "s_base",
    label: "Baseline Absorption",
    description: "scale on the melanin- and blood-free tissue absorption",
    effect: "above 1 the bloodless tissue absorbs more, mostly in the blue: darker, yellower skin",
    unit: "",
    min: 0.0,
    max: 10.0,
    default: Some(1.0),
    source: EXTENDED_SOURCE,
};

/// `gamma`: the oxygenated share of the dermis's haemoglobin. DJ2006 fix 0.75; venous blood is about 0.7, arterial
/// about 0.97 (docs/model.md, section Extended physiology).
pub const BLOOD_OXYGENATION: ParamSpec = ParamSpec {
    name: "blood_oxygenation",
    symbol: "gamma",
    label: "Blood Oxygenation",
    description: "oxygenated share of the dermis's haemoglobin",
    effect: "1 is bright arterial red, 0 dark venous purple (a bruise, cold or cyanotic skin)",
    unit: "",
    min: 0.0,
    max: 1.0,
    default: Some(0.75),
    source: EXTENDED_SOURCE,
};

/// The number of parameters ([`PARAMS`]).
pub const PARAM_COUNT: usize = 7;

/// Every parameter, in the order of [`SkinParams`]' fields: the paper's four (no default: each must be given, by value
/// or by a preset), then the extended physiology (each with the paper's value as its default).
pub const PARAMS: [ParamSpec; PARAM_COUNT] =
    [MELANIN, MELANIN_BLEND, HEMOGLOBIN, OILINESS, EPIDERMIS_THICKNESS, BASELINE_ABSORPTION_SCALE, BLOOD_OXYGENATION];

/// The paper's four parameters ([`PARAMS`]' first four): the channels every parameter map has.
pub const PAPER_PARAMS: [ParamSpec; 4] = [MELANIN, MELANIN_BLEND, HEMOGLOBIN, OILINESS];

/// The extended physiology ([`PARAMS`] after the paper's four), each with a default.
pub const EXTENDED_PARAMS: [ParamSpec; 3] = [EPIDERMIS_THICKNESS, BASELINE_ABSORPTION_SCALE, BLOOD_OXYGENATION];

/// The parameters that change the material (Base Color and Subsurface Radius): every one of [`PARAMS`] but
/// [`OILINESS`], which only the surface's specular reads. The maps evaluate texels by these.
pub const MATERIAL_PARAMS: [ParamSpec; 6] =
    [MELANIN, MELANIN_BLEND, HEMOGLOBIN, EPIDERMIS_THICKNESS, BASELINE_ABSORPTION_SCALE, BLOOD_OXYGENATION];

/// The extended physiology's defaults (the values DJ2006 fix), in [`EXTENDED_PARAMS`] order.
pub const EXTENDED_DEFAULTS: [f64; 3] =
    [spec_default(EPIDERMIS_THICKNESS), spec_default(BASELINE_ABSORPTION_SCALE), spec_default(BLOOD_OXYGENATION)];

/// The spec of the parameter called `name`.
pub fn param_spec(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

/// Validated skin parameters. Construct with [`SkinParams::new`] (the paper's four, the extended physiology at its
/// defaults), [`SkinParams::from_values`] (all of them) or [`SkinParams::preset`].
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
    /// [`EPIDERMIS_THICKNESS`], mm.
    #[serde(default = "default_epidermis_thickness_mm")]
    pub epidermis_thickness_mm: f64,
    /// [`BASELINE_ABSORPTION_SCALE`].
    #[serde(default = "default_baseline_absorption_scale")]
    pub baseline_absorption_scale: f64,
    /// [`BLOOD_OXYGENATION`].
    #[serde(default = "default_blood_oxygenation")]
    pub blood_oxygenation: f64,
}

const fn spec_default(spec: ParamSpec) -> f64 {
    match spec.default {
        Some(v) => v,
        None => panic!("an extended parameter without a default"),
    }
}

fn default_epidermis_thickness_mm() -> f64 {
    EXTENDED_DEFAULTS[0]
}

fn default_baseline_absorption_scale() -> f64 {
    EXTENDED_DEFAULTS[1]
}

fn default_blood_oxygenation() -> f64 {
    EXTENDED_DEFAULTS[2]
}

impl SkinParams {
    /// The paper's four parameters with the extended physiology at its defaults, unchecked (for tables' nodes and
    /// presets, whose values are in range by construction).
    pub(crate) const fn paper(melanin: f64, melanin_blend: f64, hemoglobin: f64, oiliness: f64) -> Self {
        SkinParams {
            melanin,
            melanin_blend,
            hemoglobin,
            oiliness,
            epidermis_thickness_mm: EXTENDED_DEFAULTS[0],
            baseline_absorption_scale: EXTENDED_DEFAULTS[1],
            blood_oxygenation: EXTENDED_DEFAULTS[2],
        }
    }

    /// Validate the paper's four parameters against [`PARAMS`] (the extended physiology at its defaults); the error
    /// names the first parameter out of range and its range.
    pub fn new(melanin: f64, melanin_blend: f64, hemoglobin: f64, oiliness: f64) -> Result<Self, SkinError> {
        Self::paper(melanin, melanin_blend, hemoglobin, oiliness).validated()
    }

    /// Validate every parameter, in [`PARAMS`] order.
    pub fn from_values(v: [f64; PARAM_COUNT]) -> Result<Self, SkinError> {
        SkinParams {
            melanin: v[0],
            melanin_blend: v[1],
            hemoglobin: v[2],
            oiliness: v[3],
            epidermis_thickness_mm: v[4],
            baseline_absorption_scale: v[5],
            blood_oxygenation: v[6],
        }
        .validated()
    }

    /// Validate every parameter, each given by `value_of` its spec (addressed by name, not by position).
    pub fn from_fn(value_of: impl Fn(&ParamSpec) -> f64) -> Result<Self, SkinError> {
        Self::from_values(PARAMS.map(|spec| value_of(&spec)))
    }

    /// These parameters if each is in its range ([`PARAMS`]), else the error naming the first that is not.
    pub fn validated(self) -> Result<Self, SkinError> {
        for (spec, value) in PARAMS.iter().zip(self.values()) {
            spec.check(value)?;
        }
        Ok(self)
    }

    /// The values in [`PARAMS`] order.
    pub fn values(&self) -> [f64; PARAM_COUNT] {
        [
            self.melanin,
            self.melanin_blend,
            self.hemoglobin,
            self.oiliness,
            self.epidermis_thickness_mm,
            self.baseline_absorption_scale,
            self.blood_oxygenation,
        ]
    }

    /// The extended physiology's values, in [`EXTENDED_PARAMS`] order.
    pub fn extended_values(&self) -> [f64; 3] {
        [self.epidermis_thickness_mm, self.baseline_absorption_scale, self.blood_oxygenation]
    }

    /// True when every extended parameter has its default: the paper's model.
    pub fn is_paper_model(&self) -> bool {
        self.extended_values() == EXTENDED_DEFAULTS
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
    Preset { name, description, params: SkinParams::paper(c_m, beta_m, c_h, oil) }
}

/// A preset with the epidermis thickness and the baseline absorption scale given too (blood oxygenation and oiliness
/// at the paper's 0.75 and the presets' 0.3).
const fn measured(name: &'static str, description: &'static str, v: [f64; 5]) -> Preset {
    let mut params = SkinParams::paper(v[0], v[1], v[2], 0.3);
    params.epidermis_thickness_mm = v[3];
    params.baseline_absorption_scale = v[4];
    Preset { name, description, params }
}

/// A palette preset: melanin, melanin blend, haemoglobin, epidermis thickness (mm), baseline absorption scale and
/// blood oxygenation as fitted, oiliness the presets' 0.3.
const fn palette(name: &'static str, description: &'static str, v: [f64; 6]) -> Preset {
    let mut params = measured(name, description, [v[0], v[1], v[2], v[3], v[4]]).params;
    params.blood_oxygenation = v[5];
    Preset { name, description, params }
}

/// The presets. The first three are the skin types of the SIGGRAPH 2006 sketch (Donner & Jensen, teaser caption;
/// docs/model.md, section Parameters). The `measured-*` ones are the median fitted parameters (melanin, melanin
/// blend, haemoglobin, epidermis thickness, baseline scale) of the lightest, middle and darkest third by L* of the
/// in-vivo spectra of Xiao et al. 2016 (every 16th of the 4392), fitted with the exact transport, regenerated by
/// `cargo run --release --example measured_skin_report -- --every 16` (docs/measured-skin.md, section Presets).
/// The `ita-*` ones, the palette, are one per ITA° class of the same spectra (very light to dark), the fit of each
/// class's median spectrum (docs/measured-skin.md, section Palette).
pub const PRESETS: &[Preset] = &[
    preset("caucasian", "Caucasian skin type, DJ2006 sketch teaser caption", 0.005, 0.7, 0.005, 0.3),
    preset("asian", "Asian skin type, DJ2006 sketch teaser caption", 0.15, 0.0, 0.01, 0.3),
    preset("african", "African skin type, DJ2006 sketch teaser caption", 0.50, 0.7, 0.05, 0.3),
    measured(
        "measured-light",
        "lightest third of in-vivo spectra (Xiao et al. 2016), median fit; docs/measured-skin.md",
        [0.0606, 0.0, 0.0083, 0.031, 1.75],
    ),
    measured(
        "measured-medium",
        "middle third of in-vivo spectra (Xiao et al. 2016), median fit; docs/measured-skin.md",
        [0.0478, 0.0, 0.0099, 0.053, 1.31],
    ),
    measured(
        "measured-dark",
        "darkest third of in-vivo spectra (Xiao et al. 2016), median fit; docs/measured-skin.md",
        [0.0799, 0.266, 0.0142, 0.064, 1.36],
    ),
    // The palette: one preset per ITA class, the fit of the class's median measured spectrum (docs/measured-skin.md,
    // Palette). Written by `cargo run --release --example palette -- --write`; do not edit by hand.
    // BEGIN palette
    palette(
        "ita-very-light",
        "median of the 66 in-vivo spectra of ITA class very light (> 55°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.0096, 1.000, 0.0043, 0.110, 1.00, 0.75],
    ),
    palette(
        "ita-light",
        "median of the 749 in-vivo spectra of ITA class light (41–55°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.0171, 0.445, 0.0064, 0.110, 1.00, 0.75],
    ),
    palette(
        "ita-intermediate",
        "median of the 1492 in-vivo spectra of ITA class intermediate (28–41°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.0260, 0.313, 0.0082, 0.110, 1.00, 0.75],
    ),
    palette(
        "ita-tan",
        "median of the 1467 in-vivo spectra of ITA class tan (10–28°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.0365, 0.309, 0.0107, 0.110, 1.00, 0.75],
    ),
    palette(
        "ita-brown",
        "median of the 531 in-vivo spectra of ITA class brown (−30–10°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.0490, 0.688, 0.0115, 0.110, 1.00, 0.75],
    ),
    palette(
        "ita-dark",
        "median of the 87 in-vivo spectra of ITA class dark (< −30°) (Xiao et al. 2016); docs/measured-skin.md",
        [0.1154, 1.000, 0.0064, 0.110, 1.00, 0.75],
    ),
    // END palette
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate() {
        // The paper's three come first, on the paper's model.
        let names: Vec<&str> = PRESETS.iter().map(|p| p.name).collect();
        assert_eq!(names[..3], ["caucasian", "asian", "african"]);
        for p in &PRESETS[..3] {
            let q = p.params;
            assert_eq!(SkinParams::new(q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness).unwrap(), q, "{}", p.name);
        }
        for p in &PRESETS[3..] {
            assert_eq!(p.params.validated().unwrap(), p.params, "{}", p.name);
            assert!(!p.params.is_paper_model() && p.params.blood_oxygenation == 0.75, "{}", p.name);
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
        let mid = [0.1, 0.5, 0.01, 0.3, 0.1, 1.0, 0.75];
        for (i, spec) in PARAMS.iter().enumerate() {
            let mut v = mid;
            v[i] = spec.max;
            assert!(SkinParams::from_values(v).is_ok(), "{}", spec.name);
            v[i] = f64::from_bits(spec.max.to_bits() + 1);
            let e = SkinParams::from_values(v).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{} must be in", spec.name)), "{e}");
        }
        // The extended physiology defaults to the paper's values, in JSON too (a sidecar from before it existed).
        let old = r#"{"melanin":0.005,"melanin_blend":0.7,"hemoglobin":0.005,"oiliness":0.3}"#;
        let q: SkinParams = serde_json::from_str(old).unwrap();
        assert!(q.is_paper_model() && q.epidermis_thickness_mm == 0.25 && q.blood_oxygenation == 0.75, "{q:?}");
        assert_eq!(q, SkinParams::preset("caucasian").unwrap());
        assert!(
            PAPER_PARAMS.iter().all(|s| s.default.is_none()) && EXTENDED_PARAMS.iter().all(|s| s.default.is_some()),
            "{:?} / {:?}",
            PAPER_PARAMS.map(|s| s.default),
            EXTENDED_PARAMS.map(|s| s.default)
        );
        assert_eq!(param_spec("hemoglobin").map(|s| s.max), Some(0.1));
        // values() is in PARAMS order: each value is the field of that name.
        let q = SkinParams::from_values([0.1, 0.2, 0.03, 0.4, 0.08, 2.0, 0.9]).unwrap();
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
        assert!(
            SkinParams::preset("martian").unwrap_err().to_string().contains("caucasian"),
            "{}",
            SkinParams::preset("martian").unwrap_err()
        );
        assert!(SkinParams::preset("Caucasian").is_ok(), "{:?}", SkinParams::preset("Caucasian"));
    }
}
