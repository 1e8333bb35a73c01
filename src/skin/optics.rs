//! Per-wavelength optics of the two skin layers from the four parameters (DJ2006 eqs. 6-8; docs/model.md, sections
//! Absorption to Layers).

use serde::{Deserialize, Serialize};

use super::chromophores::*;
use super::params::{ParamSpec, SkinParams, HEMOGLOBIN};
use super::scattering::ScatteringShape;
use crate::layer::Layer;

/// Index of refraction of all skin, "a constant index of refraction of 1.4 throughout the skin" (DJ2006; docs/model.md,
/// section Parameters).
pub const SKIN_IOR: f64 = 1.4;

/// Model choices that are not accuracy settings nor physiology (the epidermis thickness is a parameter:
/// [`super::params::EPIDERMIS_THICKNESS`]). The defaults are those of docs/model.md (Absorption, Layers).
///
/// Read from JSON or a Python dict (`evaluate(model=...)`), an option left out keeps its default and an unknown name
/// is an error that lists the known ones.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkinModel {
    /// `K_em` of DJ2006 eq. 3 in mm^-1 (default [`K_EM_PER_MM`]; 6.6e11 is the literal printed value, see
    /// docs/model.md, Absorption).
    pub eumelanin_k_per_mm: f64,
    /// Dermis thickness, mm; `f64::INFINITY` (the default) is a semi-infinite dermis (docs/model.md, section Layers).
    /// In JSON an infinite thickness is the string "inf".
    #[serde(with = "finite_or_inf")]
    pub dermis_thickness_mm: f64,
    /// Radius of the dermal blood vessels the blood is confined to, mm, for the packaging correction
    /// ([`vessel_packaging_factor`]); 0 (the default, DJ2006's eq. 7) spreads the blood evenly through the dermis.
    /// At most [`MAX_VESSEL_RADIUS_MM`]. Absent from JSON when 0 (docs/model.md, Vessel packaging).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub blood_vessel_radius_mm: f64,
    /// The eumelanin spectrum's shape ([`EumelaninShape`]); DJ2006's eq. 3 by default. An option for issue 39's
    /// study; absent from JSON when the default.
    #[serde(default, skip_serializing_if = "EumelaninShape::is_default")]
    pub eumelanin_shape: EumelaninShape,
    /// The reduced-scattering spectrum's shape of both layers ([`ScatteringShape`]); DJ2006's eq. 8 by default. An
    /// option for issue 39's study; absent from JSON when the default.
    #[serde(default, skip_serializing_if = "ScatteringShape::is_default")]
    pub scattering_shape: ScatteringShape,
    /// β-carotene in the epidermis, µmol/L ([`sigma_a_carotene_per_mm`]), added to its absorption; 0 (the default,
    /// DJ2006) has none. At most [`MAX_CAROTENE_UMOL_PER_L`]. An option for issue 39's study; absent from JSON when 0
    /// (docs/model.md, Epidermal carotene).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub epidermal_carotene_umol_per_l: f64,
    /// The absorption spectrum of the dermis's blood ([`BloodSpectrum`]); DJ2006's (haemoglobin in solution) by
    /// default. An option for issue 39's study; absent from JSON when the default (docs/model.md, Whole-blood
    /// spectrum).
    #[serde(default, skip_serializing_if = "BloodSpectrum::is_default")]
    pub blood_spectrum: BloodSpectrum,
    /// Whole-blood volume fraction of the epidermis layer, `C_he` of Donner et al. 2008's epidermis (also Jimenez et
    /// al. 2010): blood of the dermis's oxygenation and spectrum in place of as much bloodless tissue. 0 (the
    /// default, DJ2006) has none. Range and meaning: [`EPIDERMAL_HEMOGLOBIN`] (`fit_spectrum` can fit it). Absent from
    /// JSON when 0 (docs/model.md, Epidermal blood).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub epidermal_hemoglobin: f64,
}

/// [`SkinModel::epidermal_hemoglobin`] described once: its name (the model option's JSON key and the name
/// `fit_spectrum` frees it by), symbol, meaning and range, the dermis's own bound ([`HEMOGLOBIN`]'s, 0.1).
pub const EPIDERMAL_HEMOGLOBIN: ParamSpec = ParamSpec {
    name: "epidermal_hemoglobin",
    symbol: "C_he",
    label: "Epidermal Blood",
    description: "whole-blood volume fraction of the epidermis",
    effect: "blood of the dermis's oxygenation above the dermis: its Soret and Q bands seen through less melanin",
    unit: "",
    min: 0.0,
    max: HEMOGLOBIN.max,
    default: Some(0.0),
    source: "Donner, Weyrich, d'Eon, Ramamoorthi & Rusinkiewicz 2008 (epidermis C_he); Jimenez et al. 2010; \
             docs/model.md, Epidermal blood",
};

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// Serde for a length that may be infinite: a number, or the string "inf" (JSON has no infinity).
mod finite_or_inf {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_infinite() && *v > 0.0 {
            s.serialize_str("inf")
        } else {
            s.serialize_f64(*v)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Value {
            Number(f64),
            Text(String),
        }
        match Value::deserialize(d)? {
            Value::Number(v) => Ok(v),
            Value::Text(t) if t == "inf" => Ok(f64::INFINITY),
            Value::Text(t) => Err(serde::de::Error::custom(format!("expected a number or \"inf\", got {t:?}"))),
        }
    }
}

impl Default for SkinModel {
    fn default() -> Self {
        SkinModel {
            eumelanin_k_per_mm: K_EM_PER_MM,
            dermis_thickness_mm: f64::INFINITY,
            blood_vessel_radius_mm: 0.0,
            eumelanin_shape: EumelaninShape::Dj2006,
            scattering_shape: ScatteringShape::Dj2006,
            epidermal_carotene_umol_per_l: 0.0,
            blood_spectrum: BloodSpectrum::Dj2006,
            epidermal_hemoglobin: 0.0,
        }
    }
}

/// The bloodless, melanin-free tissue absorption of the parameters, mm^-1: DJ2006 eq. 5 times the baseline scale.
fn sigma_a_tissue_per_mm(p: &SkinParams, wavelength_nm: f64) -> f64 {
    p.baseline_absorption_scale * sigma_a_baseline_per_mm(wavelength_nm)
}

/// `sigma_a_epi(lambda)`, mm^-1: melanin blend plus baseline (DJ2006 eq. 6). No haemoglobin in the DJ2006 epidermis.
pub fn sigma_a_epidermis_per_mm(p: &SkinParams, wavelength_nm: f64, k_em_per_mm: f64) -> f64 {
    sigma_a_epidermis_shaped_per_mm(p, wavelength_nm, k_em_per_mm, EumelaninShape::Dj2006)
}

/// [`sigma_a_epidermis_per_mm`] with the eumelanin spectrum of `shape` ([`SkinModel::eumelanin_shape`]).
pub fn sigma_a_epidermis_shaped_per_mm(
    p: &SkinParams,
    wavelength_nm: f64,
    k_em_per_mm: f64,
    shape: EumelaninShape,
) -> f64 {
    let melanin = p.melanin_blend * sigma_a_eumelanin_shaped_per_mm(wavelength_nm, k_em_per_mm, shape)
        + (1.0 - p.melanin_blend) * sigma_a_pheomelanin_per_mm(wavelength_nm);
    p.melanin * melanin + (1.0 - p.melanin) * sigma_a_tissue_per_mm(p, wavelength_nm)
}

/// `sigma_a_derm(lambda)`, mm^-1: oxygenated/deoxygenated blood blend (gamma = the blood oxygenation) plus baseline
/// (DJ2006 eq. 7), the blood's term (of the model's [`BloodSpectrum`]) times the packaging factor of the model's
/// vessels ([`SkinModel::blood_vessel_radius_mm`]; 1 at 0).
pub fn sigma_a_dermis_per_mm(p: &SkinParams, wavelength_nm: f64, model: &SkinModel) -> f64 {
    p.hemoglobin * sigma_a_packed_blood_per_mm(p, wavelength_nm, model)
        + (1.0 - p.hemoglobin) * sigma_a_tissue_per_mm(p, wavelength_nm)
}

/// The blood's absorption, mm^-1: the oxygenation's blend of the model's [`BloodSpectrum`], times the packaging
/// factor of the model's vessels (1 without them).
fn sigma_a_packed_blood_per_mm(p: &SkinParams, wavelength_nm: f64, model: &SkinModel) -> f64 {
    let (gamma, spectrum) = (p.blood_oxygenation, model.blood_spectrum);
    let blood = gamma * spectrum.oxy_per_mm(wavelength_nm) + (1.0 - gamma) * spectrum.deoxy_per_mm(wavelength_nm);
    blood * vessel_packaging_factor(blood, model.blood_vessel_radius_mm)
}

/// What [`SkinModel::epidermal_hemoglobin`] adds to the epidermis's absorption, mm^-1: `C_he` times blood's absorption
/// less the bloodless tissue's it replaces (0 without it).
fn sigma_a_epidermal_blood_per_mm(p: &SkinParams, wavelength_nm: f64, model: &SkinModel) -> f64 {
    if model.epidermal_hemoglobin == 0.0 {
        return 0.0;
    }
    let blood = sigma_a_packed_blood_per_mm(p, wavelength_nm, model);
    model.epidermal_hemoglobin * (blood - sigma_a_tissue_per_mm(p, wavelength_nm))
}

/// The two layers, top to bottom, at one wavelength: epidermis over dermis, both with index 1.4.
pub fn skin_layers(p: &SkinParams, model: &SkinModel, wavelength_nm: f64) -> [Layer; 2] {
    [
        Layer {
            thickness_mm: p.epidermis_thickness_mm,
            sigma_a_per_mm: sigma_a_epidermis_shaped_per_mm(
                p,
                wavelength_nm,
                model.eumelanin_k_per_mm,
                model.eumelanin_shape,
            ) + sigma_a_carotene_per_mm(wavelength_nm, model.epidermal_carotene_umol_per_l)
                + sigma_a_epidermal_blood_per_mm(p, wavelength_nm, model),
            sigma_s_reduced_per_mm: model.scattering_shape.epidermis_per_mm(wavelength_nm),
            ior: SKIN_IOR,
        },
        Layer {
            thickness_mm: model.dermis_thickness_mm,
            sigma_a_per_mm: sigma_a_dermis_per_mm(p, wavelength_nm, model),
            sigma_s_reduced_per_mm: model.scattering_shape.dermis_per_mm(wavelength_nm),
            ior: SKIN_IOR,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An option's `key` is absent from a default model's JSON (so earlier JSON and cache keys read the same) and
    /// `set`, a model with the option set, round-trips through JSON.
    fn absent_by_default_and_round_trips(key: &str, set: &SkinModel) {
        let text = serde_json::to_string(&SkinModel::default()).unwrap();
        assert!(!text.contains(key), "{text}");
        let text = serde_json::to_string(set).unwrap();
        assert_eq!(serde_json::from_str::<SkinModel>(&text).unwrap(), *set, "{text}");
    }

    #[test]
    fn model_json_round_trip_keeps_infinity() {
        let m = SkinModel::default();
        let text = serde_json::to_string(&m).unwrap();
        assert!(text.contains("\"dermis_thickness_mm\":\"inf\""), "{text}");
        assert_eq!(serde_json::from_str::<SkinModel>(&text).unwrap(), m);
    }

    /// A model read from JSON (`--model`, Python's `model=`) names only the options it changes; an unknown name is an
    /// error that lists the known ones.
    #[test]
    fn model_json_names_only_what_it_changes() {
        let m: SkinModel = serde_json::from_str(r#"{"epidermal_hemoglobin": 0.01}"#).unwrap();
        assert_eq!(m, SkinModel { epidermal_hemoglobin: 0.01, ..SkinModel::default() });
        assert_eq!(serde_json::from_str::<SkinModel>("{}").unwrap(), SkinModel::default());
        let err = serde_json::from_str::<SkinModel>(r#"{"epidermal_blood": 0.01}"#).unwrap_err().to_string();
        assert!(err.contains("epidermal_blood") && err.contains("epidermal_hemoglobin"), "{err}");
    }

    /// The packaging option is absent from a default model's JSON (so earlier JSON and cache keys read the same) and
    /// round-trips when set.
    #[test]
    fn vessel_radius_is_absent_from_json_unless_set() {
        absent_by_default_and_round_trips(
            "blood_vessel_radius_mm",
            &SkinModel { blood_vessel_radius_mm: 0.02, ..SkinModel::default() },
        );
    }

    /// The eumelanin shape is absent from a default model's JSON and round-trips when set.
    #[test]
    fn eumelanin_shape_is_absent_from_json_unless_set() {
        for shape in [EumelaninShape::PowerLaw { exponent: -3.48 }, EumelaninShape::Exponential { k_per_nm: 0.011 }] {
            absent_by_default_and_round_trips(
                "eumelanin_shape",
                &SkinModel { eumelanin_shape: shape, ..SkinModel::default() },
            );
        }
    }

    /// The carotene option is absent from a default model's JSON, round-trips when set, and adds its absorption to
    /// the epidermis alone.
    #[test]
    fn carotene_adds_to_the_epidermis_only() {
        let m = SkinModel { epidermal_carotene_umol_per_l: 3.0, ..SkinModel::default() };
        absent_by_default_and_round_trips("carotene", &m);
        let p = SkinParams::preset("caucasian").unwrap();
        let ([epi0, derm0], [epi1, derm1]) =
            (skin_layers(&p, &SkinModel::default(), 480.0), skin_layers(&p, &m, 480.0));
        assert_eq!(derm0, derm1);
        let added = epi1.sigma_a_per_mm - epi0.sigma_a_per_mm;
        assert!((added - sigma_a_carotene_per_mm(480.0, 3.0)).abs() < 1e-12 && added > 0.0, "{added}");
    }

    /// The blood spectrum is absent from a default model's JSON, round-trips when set, and changes the dermis alone.
    #[test]
    fn blood_spectrum_changes_the_dermis_only() {
        let m = SkinModel { blood_spectrum: BloodSpectrum::WholeBlood2014, ..SkinModel::default() };
        absent_by_default_and_round_trips("blood_spectrum", &m);
        let text = serde_json::to_string(&m).unwrap();
        assert!(text.contains("\"blood_spectrum\":\"whole_blood2014\""), "{text}");
        let p = SkinParams::preset("caucasian").unwrap();
        let ([epi0, derm0], [epi1, derm1]) =
            (skin_layers(&p, &SkinModel::default(), 576.0), skin_layers(&p, &m, 576.0));
        assert_eq!(epi0, epi1);
        let tissue = (1.0 - p.hemoglobin) * sigma_a_tissue_per_mm(&p, 576.0);
        let blood = 0.75 * BloodSpectrum::WholeBlood2014.oxy_per_mm(576.0)
            + 0.25 * BloodSpectrum::WholeBlood2014.deoxy_per_mm(576.0);
        assert!((derm1.sigma_a_per_mm - tissue - p.hemoglobin * blood).abs() < 1e-12);
        assert!(derm1.sigma_a_per_mm < derm0.sigma_a_per_mm);
    }

    /// Epidermal blood is absent from a default model's JSON, round-trips when set, and replaces bloodless tissue of
    /// the epidermis by blood of the dermis's spectrum and oxygenation: the epidermis gains C_he (blood − tissue).
    #[test]
    fn epidermal_blood_replaces_tissue_in_the_epidermis() {
        let m = SkinModel { epidermal_hemoglobin: 0.01, ..SkinModel::default() };
        absent_by_default_and_round_trips("epidermal_hemoglobin", &m);
        let p = SkinParams::preset("caucasian").unwrap();
        for w in [420.0, 576.0, 650.0] {
            let ([epi0, derm0], [epi1, derm1]) = (skin_layers(&p, &SkinModel::default(), w), skin_layers(&p, &m, w));
            assert_eq!(derm0, derm1);
            let blood = 0.75 * sigma_a_oxy_blood_per_mm(w) + 0.25 * sigma_a_deoxy_blood_per_mm(w);
            let added = 0.01 * (blood - sigma_a_tissue_per_mm(&p, w));
            assert!((epi1.sigma_a_per_mm - epi0.sigma_a_per_mm - added).abs() < 1e-12, "{w} nm");
        }
    }

    /// Packaging scales the dermis's blood term alone, by the factor of the blood's own absorption: the epidermis and
    /// the bloodless part of the dermis are unchanged.
    #[test]
    fn packaging_scales_only_the_blood() {
        let p = SkinParams::preset("caucasian").unwrap();
        let packed = SkinModel { blood_vessel_radius_mm: 0.015, ..SkinModel::default() };
        for w in [414.0, 542.0, 560.0, 650.0] {
            let [epi0, derm0] = skin_layers(&p, &SkinModel::default(), w);
            let [epi1, derm1] = skin_layers(&p, &packed, w);
            assert_eq!(epi0, epi1);
            let tissue = (1.0 - p.hemoglobin) * sigma_a_tissue_per_mm(&p, w);
            let blood = 0.75 * sigma_a_oxy_blood_per_mm(w) + 0.25 * sigma_a_deoxy_blood_per_mm(w);
            let factor = (derm1.sigma_a_per_mm - tissue) / (derm0.sigma_a_per_mm - tissue);
            assert!((factor - vessel_packaging_factor(blood, 0.015)).abs() < 1e-12, "{w} nm: {factor}");
            assert!(factor < 1.0 && derm1.sigma_s_reduced_per_mm == derm0.sigma_s_reduced_per_mm);
        }
    }

    /// Independently computed values, Caucasian at 550 nm (docs/model.md, section Reference numbers).
    #[test]
    fn caucasian_550() {
        let p = SkinParams::preset("caucasian").unwrap();
        let [epi, derm] = skin_layers(&p, &SkinModel::default(), 550.0);
        assert!((epi.sigma_a_per_mm - 0.26062).abs() < 3e-4, "{}", epi.sigma_a_per_mm);
        assert!((derm.sigma_a_per_mm - 0.16783).abs() < 3e-4, "{}", derm.sigma_a_per_mm);
        assert!((derm.sigma_s_reduced_per_mm - 3.04113).abs() < 3e-4, "{}", derm.sigma_s_reduced_per_mm);
    }
}
