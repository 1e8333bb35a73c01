//! The skin surface's reflection as a model of its own (docs/model.md, "Surface reflection: measured two-lobe
//! model"): the BRDF, its directional albedo and its normal-incidence reflectance, under one of two models.
//!
//! - `paper`: DJ2006's oil layer exactly as [`crate::surface::oil_layer`] computes it, one Torrance-Sparrow lobe scaled by the
//!   oiliness (rho_s = o): dry skin (o = 0) reflects nothing.
//! - `measured`: two Torrance-Sparrow lobes, a broad one (the rough stratum corneum) and a sharp one (where sebum
//!   smooths it), sharing one dielectric Fresnel term at the skin surface's eta = 1.4, with weights that sum to 1, so
//!   the surface reflects like a dielectric at every oiliness and oil only reshapes the highlight:
//!   `f_r = F(i.h; 1.4) sum_k w_k D_k(h) G_k(i, o) / (4 cos_i cos_o)`, Beckmann `D_k`, Smith `G_k` for Beckmann.
//!
//! Angles are in degrees (names end in `_deg`): polar angles from the surface normal in [0, 90), and the outgoing
//! direction's azimuth relative to the incident one (180: the plane of mirror reflection). BRDFs are in sr^-1,
//! albedos and reflectances dimensionless. Its Principled inputs (base lobe + Coat) are
//! [`crate::surface::principled`]'s.

use std::cell::Cell;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;
use std::sync::{Mutex, OnceLock};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::SkinError;
use crate::surface::oil_layer::{
    beckmann_d, fresnel_dielectric, hemispherical_average_par, microfacet_albedo, torrance_sparrow_directional_albedo,
    torrance_sparrow_f_r, torrance_sparrow_unit_albedos, Lobe, ALBEDO_THETA_PANELS, SKIN_SURFACE_IOR,
};

/// Which surface reflection: Python's `surface=` takes the serde names. The default ([`Default`], every front's) is
/// the measured surface: skin reflects like a dielectric whether oily or dry; `paper` reproduces DJ2006's oil layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Hash, Default)]
#[serde(rename_all = "snake_case")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
pub enum SurfaceModel {
    /// Two Beckmann lobes sharing the Fresnel term of the skin surface, weights summing to 1 ([`TWO_LOBE_TABLE`]).
    #[default]
    Measured,
    /// DJ2006's oil layer as `surface` computes it: one lobe scaled by the oiliness.
    Paper,
}

impl SurfaceModel {
    /// The serde name (`surface=` in Python, `--surface` on the command line).
    pub fn name(self) -> &'static str {
        match self {
            SurfaceModel::Measured => "measured",
            SurfaceModel::Paper => "paper",
        }
    }

    /// One line for the fronts' choices (tooltips, help).
    pub fn description(self) -> &'static str {
        match self {
            SurfaceModel::Measured => {
                "measured skin: a broad lobe and a sharp Coat, reflecting like a dielectric (about 2.8 % at normal \
                 incidence) at every oiliness; oil sharpens the Coat and raises its weight"
            }
            SurfaceModel::Paper => {
                "Donner & Jensen 2006's oil layer: one lobe scaled by the oiliness, no reflection on dry skin"
            }
        }
    }

    /// `paper`: what a request's JSON without a surface means (written before the field existed, or by
    /// [`SurfaceModel::is_paper`]'s omission).
    pub fn absent() -> SurfaceModel {
        SurfaceModel::Paper
    }

    /// True for `paper` (serde leaves the field out then, so earlier results and cache keys stay as they were).
    pub fn is_paper(&self) -> bool {
        *self == SurfaceModel::Paper
    }
}

/// Every surface model, the bindings' default (`measured`) first.
pub const ALL_SURFACE_MODELS: [SurfaceModel; 2] = [SurfaceModel::Measured, SurfaceModel::Paper];

/// One Beckmann lobe of the measured model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BeckmannLobe {
    /// w_k: the lobe's share of the Fresnel reflectance, dimensionless; the lobes' weights sum to 1.
    pub weight: f64,
    /// m_k: Beckmann roughness (RMS microfacet slope), dimensionless.
    pub beckmann_m: f64,
}

/// The measured model's lobe parameters as functions of the oiliness o in [0, 1], all in one table
/// ([`TWO_LOBE_TABLE`]): broad `m = broad_beckmann_m`, `w = 1 - w_sharp(o)`; sharp
/// `m_sharp(o) = sharp_beckmann_m_dry + sharp_beckmann_m_per_oiliness o`,
/// `w_sharp(o) = sharp_weight_dry + sharp_weight_per_oiliness o`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TwoLobeTable {
    /// Beckmann m of the broad lobe (rough stratum corneum), at every oiliness.
    pub broad_beckmann_m: f64,
    /// Beckmann m of the sharp lobe on dry skin (o = 0).
    pub sharp_beckmann_m_dry: f64,
    /// Change of the sharp lobe's m per unit oiliness (negative: oil smooths the surface).
    pub sharp_beckmann_m_per_oiliness: f64,
    /// Weight of the sharp lobe on dry skin (o = 0).
    pub sharp_weight_dry: f64,
    /// Change of the sharp lobe's weight per unit oiliness (positive: oil covers more of the surface).
    pub sharp_weight_per_oiliness: f64,
}

/// The measured model's parameters: this project's construction between the cited values below, not a fit to
/// measurements (Weyrich et al. 2006's per-region tables, ACM TOG 25(3) 1013-1024, were not read for it: an open
/// item, docs/model.md). Anchors:
/// - single-lobe Beckmann fits to skin: DJ2006's m = 0.35 (`surface::BECKMANN_ROUGHNESS_M`) and d'Eon & Luebke,
///   GPU Gems 3 ch. 14 (2007): m = 0.3 for their Kelemen/Szirmay-Kalos lobe, from Weyrich et al. 2006's face
///   measurements. Both lie between the broad and the sharp lobe at every oiliness.
/// - the production precedent for two lobes: Unreal Engine's dual-lobe skin specular (SubsurfaceProfile defaults
///   Roughness0 = 0.75 and Roughness1 = 1.30, multipliers of the material's roughness, and LobeMix = 0.85, read as
///   the rougher lobe's share, `lerp(lobe0, lobe1, LobeMix)`). Its lobes' GGX alpha ratio is (1.30 / 0.75)^2 = 3.0
///   (alpha = roughness^2); this table's m ratio runs from 2.0 (o = 0) to 3.3 (o = 1), and its dry sharp weight is
///   Unreal's 1 - 0.85.
pub const TWO_LOBE_TABLE: TwoLobeTable = TwoLobeTable {
    // Rougher than both single-lobe fits (0.35, 0.3): the broad part of a two-lobe fit is wider than one lobe's.
    broad_beckmann_m: 0.5,
    // m_sharp(0) = 0.25, m_sharp(1) = 0.15: below both single-lobe fits; oil smooths it (the brief of issue 24).
    sharp_beckmann_m_dry: 0.25,
    sharp_beckmann_m_per_oiliness: -0.10,
    // w_sharp(0) = 0.15 = 1 - Unreal's LobeMix 0.85; w_sharp(1) = 0.85, the mix reversed: oil-covered skin's
    // highlight is mostly the sharp lobe.
    sharp_weight_dry: 0.15,
    sharp_weight_per_oiliness: 0.70,
};

impl TwoLobeTable {
    /// `[broad, sharp]` at oiliness `o` (taken as valid: [`measured_lobes`] checks it).
    pub fn lobes(&self, oiliness: f64) -> [BeckmannLobe; 2] {
        let sharp_weight = self.sharp_weight_dry + self.sharp_weight_per_oiliness * oiliness;
        let sharp_m = self.sharp_beckmann_m_dry + self.sharp_beckmann_m_per_oiliness * oiliness;
        [
            BeckmannLobe { weight: 1.0 - sharp_weight, beckmann_m: self.broad_beckmann_m },
            BeckmannLobe { weight: sharp_weight, beckmann_m: sharp_m },
        ]
    }
}

/// `[broad, sharp]` lobes of the measured model at `oiliness` in [0, 1] ([`TWO_LOBE_TABLE`]).
pub fn measured_lobes(oiliness: f64) -> Result<[BeckmannLobe; 2], SkinError> {
    Ok(TWO_LOBE_TABLE.lobes(check_oiliness(oiliness)?))
}

/// From this `a` on, `Lambda(a) ~ exp(-a^2) / (4 a^3 sqrt(pi)) < 2e-19`: `G1` rounds to exactly 1 in double
/// precision.
const SMITH_A_EXACTLY_ONE: f64 = 6.0;

/// `G1(theta) = 1 / (1 + Lambda(a))` with `Lambda(a) = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2` and
/// `a = 1 / (m tan theta)`: Smith's masking of one direction for the Beckmann distribution, dimensionless, in its exact
/// erf form (Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces", EGSR, eq. 25; its rational
/// approximation, eq. 27, is checked against it in the tests). 1 along the normal, 0 at or below the horizon.
pub fn smith_g1_beckmann(cos_theta: f64, m: f64) -> f64 {
    if cos_theta.is_nan() || cos_theta <= 0.0 {
        return 0.0;
    }
    if cos_theta >= 1.0 || m <= 0.0 {
        return 1.0;
    }
    let a = cos_theta / (m * (1.0 - cos_theta * cos_theta).sqrt());
    if a >= SMITH_A_EXACTLY_ONE {
        return 1.0;
    }
    1.0 / (1.0 + 0.5 * ((-a * a).exp() / (a * PI.sqrt()) - libm::erfc(a)))
}

/// `G(i, o) = G1(i) G1(o)`: Smith shadowing-masking for Beckmann in the separable (uncorrelated) form Walter et al.
/// 2007 use, dimensionless. Symmetric in i and o, so the BRDF is reciprocal.
pub fn smith_g_beckmann(cos_theta_i: f64, cos_theta_o: f64, m: f64) -> f64 {
    smith_g1_beckmann(cos_theta_i, m) * smith_g1_beckmann(cos_theta_o, m)
}

/// `F(i.h; 1.4) sum_k w_k D_k(h) G_k(i, o) / (4 cos_i cos_o)`: the lobes' BRDF, sr^-1, for unit directions in the
/// local frame (z = normal). 0 unless both are above the surface.
fn lobes_f_r(lobes: &[BeckmannLobe], omega_i: [f64; 3], omega_o: [f64; 3]) -> f64 {
    let (cos_i, cos_o) = (omega_i[2], omega_o[2]);
    if !(cos_i > 0.0 && cos_o > 0.0) {
        return 0.0;
    }
    let h = [omega_i[0] + omega_o[0], omega_i[1] + omega_o[1], cos_i + cos_o];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let (cos_h, i_dot_h) = (h[2] / len, (omega_i[0] * h[0] + omega_i[1] * h[1] + cos_i * h[2]) / len);
    let lobes_sum: f64 = lobes
        .iter()
        .map(|l| l.weight * beckmann_d(cos_h, l.beckmann_m) * smith_g_beckmann(cos_i, cos_o, l.beckmann_m))
        .sum();
    fresnel_dielectric(i_dot_h, SKIN_SURFACE_IOR) * lobes_sum / (4.0 * cos_i * cos_o)
}

/// One Beckmann lobe with Smith G for the half-vector albedo quadrature (`surface::microfacet_albedo`): Fresnel at
/// `eta` (None: F = 1, the white furnace of the tests). Smooth in azimuth: no kinks. `g1_i` keeps the last
/// `(cos_i, G1(cos_i))`: one quadrature has one incidence.
struct SmithBeckmannLobe {
    m: f64,
    eta: Option<f64>,
    g1_i: Cell<(f64, f64)>,
}

impl SmithBeckmannLobe {
    fn new(m: f64, eta: Option<f64>) -> Self {
        SmithBeckmannLobe { m, eta, g1_i: Cell::new((f64::NAN, f64::NAN)) }
    }
}

impl Lobe for SmithBeckmannLobe {
    fn d(&self, cos_h: f64) -> f64 {
        beckmann_d(cos_h, self.m)
    }
    fn g_times_f(&self, _cos_h: f64, cos_i: f64, cos_o: f64, i_dot_h: f64) -> f64 {
        let g1_i = match self.g1_i.get() {
            (cached, g1) if cached == cos_i => g1,
            _ => {
                let g1 = smith_g1_beckmann(cos_i, self.m);
                self.g1_i.set((cos_i, g1));
                g1
            }
        };
        g1_i * smith_g1_beckmann(cos_o, self.m) * self.eta.map_or(1.0, |eta| fresnel_dielectric(i_dot_h, eta))
    }
    fn kinks(&self, _cos_h: f64, _cos_i: f64) -> [f64; 3] {
        [f64::NAN; 3]
    }
}

/// `sum_k w_k int D_k G_k F (i.h) / cos_i ...`: the lobes' directional albedo, dimensionless, by the half-vector
/// quadrature of `surface` (`panels` theta_h panels per region; F = 1 when `eta` is None).
fn lobes_albedo(lobes: &[BeckmannLobe], cos_theta_i: f64, panels: usize, eta: Option<f64>) -> f64 {
    lobes
        .iter()
        .map(|l| l.weight * microfacet_albedo(cos_theta_i, panels, &SmithBeckmannLobe::new(l.beckmann_m, eta)))
        .sum()
}

/// `H(m) = 2 int E_m(mu) mu dmu` of one Beckmann-Smith lobe of roughness `m` with Fresnel at the skin's index (weight
/// 1), memoised by `m` (at most 4096 values kept: a run over many oiliness values starts the memo afresh).
fn lobe_hemispherical_albedo(beckmann_m: f64) -> f64 {
    static MEMO: OnceLock<Mutex<HashMap<u64, f64>>> = OnceLock::new();
    let memo = MEMO.get_or_init(Default::default);
    if let Some(&h) = memo.lock().unwrap_or_else(|e| e.into_inner()).get(&beckmann_m.to_bits()) {
        return h;
    }
    let lobe = [BeckmannLobe { weight: 1.0, beckmann_m }];
    let h = hemispherical_average_par(|mu| lobes_albedo(&lobe, mu, ALBEDO_THETA_PANELS, Some(SKIN_SURFACE_IOR)));
    let mut held = memo.lock().unwrap_or_else(|e| e.into_inner());
    if held.len() >= 4096 {
        held.clear();
    }
    held.insert(beckmann_m.to_bits(), h);
    h
}

/// `oiliness` if finite and in [0, 1].
fn check_oiliness(oiliness: f64) -> Result<f64, SkinError> {
    if oiliness.is_finite() && (0.0..=1.0).contains(&oiliness) {
        Ok(oiliness)
    } else {
        Err(SkinError::invalid("oiliness", format!("must be finite and in [0, 1]; got {oiliness}")))
    }
}

/// A polar angle in degrees if finite and in [0, 90).
fn check_polar_deg(name: &str, theta_deg: f64) -> Result<f64, SkinError> {
    if theta_deg.is_finite() && (0.0..90.0).contains(&theta_deg) {
        Ok(theta_deg)
    } else {
        Err(SkinError::invalid(
            name,
            format!("must be finite and in [0, 90) degrees (0: along the surface normal); got {theta_deg}"),
        ))
    }
}

/// The relative azimuth in degrees if finite (any value: it is periodic).
fn check_azimuth_deg(phi_deg: f64) -> Result<f64, SkinError> {
    if phi_deg.is_finite() {
        Ok(phi_deg)
    } else {
        Err(SkinError::invalid("phi_deg", format!("must be finite (degrees, 180: the specular plane); got {phi_deg}")))
    }
}

/// `(sin theta cos phi, sin theta sin phi, cos theta)`: the unit direction of polar angle theta and azimuth phi, local
/// frame (z = normal).
fn direction(theta_deg: f64, phi_deg: f64) -> [f64; 3] {
    let (sin_t, cos_t) = theta_deg.to_radians().sin_cos();
    let (sin_p, cos_p) = phi_deg.to_radians().sin_cos();
    [sin_t * cos_p, sin_t * sin_p, cos_t]
}

/// A surface reflection model at one oiliness, checked once: its BRDF and albedos.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SurfaceReflection {
    model: SurfaceModel,
    oiliness: f64,
}

impl SurfaceReflection {
    /// `model` at `oiliness` (finite, in [0, 1]; else an error naming "oiliness").
    pub fn new(model: SurfaceModel, oiliness: f64) -> Result<Self, SkinError> {
        Ok(SurfaceReflection { model, oiliness: check_oiliness(oiliness)? })
    }

    pub fn model(&self) -> SurfaceModel {
        self.model
    }

    pub fn oiliness(&self) -> f64 {
        self.oiliness
    }

    /// The measured model's `[broad, sharp]` lobes at this oiliness (None for `paper`, whose one lobe is
    /// `surface`'s).
    pub fn lobes(&self) -> Option<[BeckmannLobe; 2]> {
        (self.model == SurfaceModel::Measured).then(|| TWO_LOBE_TABLE.lobes(self.oiliness))
    }

    /// `f_r(theta_i, theta_o, phi)`, sr^-1: incident polar angle `theta_in_deg`, outgoing `theta_out_deg` (both in
    /// [0, 90)), outgoing azimuth `phi_deg` relative to the incident direction's (180: the specular plane).
    pub fn f_r_per_sr(&self, theta_in_deg: f64, theta_out_deg: f64, phi_deg: f64) -> Result<f64, SkinError> {
        let omega_i = direction(check_polar_deg("theta_in_deg", theta_in_deg)?, 0.0);
        let omega_o = direction(check_polar_deg("theta_out_deg", theta_out_deg)?, check_azimuth_deg(phi_deg)?);
        Ok(match self.model {
            SurfaceModel::Paper => torrance_sparrow_f_r(omega_i, omega_o, self.oiliness),
            SurfaceModel::Measured => lobes_f_r(&TWO_LOBE_TABLE.lobes(self.oiliness), omega_i, omega_o),
        })
    }

    /// [`Self::f_r_per_sr`] of each `(theta_in_deg[k], theta_out_deg[k], phi_deg[k])`; the three of equal length
    /// (else an error naming "theta_out_deg" or "phi_deg").
    pub fn f_r_per_sr_each(
        &self,
        theta_in_deg: &[f64],
        theta_out_deg: &[f64],
        phi_deg: &[f64],
    ) -> Result<Vec<f64>, SkinError> {
        for (name, other) in [("theta_out_deg", theta_out_deg), ("phi_deg", phi_deg)] {
            if other.len() != theta_in_deg.len() {
                return Err(SkinError::invalid(
                    name,
                    format!("expected {} values, as many as theta_in_deg; got {}", theta_in_deg.len(), other.len()),
                ));
            }
        }
        theta_in_deg.iter().zip(theta_out_deg).zip(phi_deg).map(|((&i, &o), &p)| self.f_r_per_sr(i, o, p)).collect()
    }

    /// `E(theta_i) = int f_r cos theta_o d omega_o`: the directional albedo, dimensionless, at incidence
    /// `theta_in_deg` in [0, 90). `paper`: `surface::torrance_sparrow_directional_albedo`; `measured`: the weighted sum
    /// of the lobes' albedos by the same half-vector quadrature (64 panels x 8 Gauss-Legendre nodes per theta_h
    /// region, 16 in phi; converged to < 1e-6 relative, tests). A few ms a call.
    pub fn directional_albedo(&self, theta_in_deg: f64) -> Result<f64, SkinError> {
        let cos_i = check_polar_deg("theta_in_deg", theta_in_deg)?.to_radians().cos();
        Ok(match self.model {
            SurfaceModel::Paper => torrance_sparrow_directional_albedo(cos_i, self.oiliness),
            SurfaceModel::Measured => {
                lobes_albedo(&TWO_LOBE_TABLE.lobes(self.oiliness), cos_i, ALBEDO_THETA_PANELS, Some(SKIN_SURFACE_IOR))
            }
        })
    }

    /// `2 int E(mu) mu dmu`: the hemispherical (diffuse-light) albedo, dimensionless. `measured`: the model is linear
    /// in its lobe weights, so this is `sum_k w_k H(m_k)` with `H(m)` one Fresnel-weighted Beckmann-Smith lobe's
    /// average, each computed once per `m` (memoised: the broad lobe's once, the sharp lobe's once per oiliness), its
    /// nodes in parallel: tens of ms the first time, nothing after. `paper`: linear in the oiliness (cached).
    pub fn hemispherical_albedo(&self) -> f64 {
        match self.model {
            SurfaceModel::Paper => self.oiliness * torrance_sparrow_unit_albedos().1,
            SurfaceModel::Measured => TWO_LOBE_TABLE
                .lobes(self.oiliness)
                .iter()
                .map(|l| l.weight * lobe_hemispherical_albedo(l.beckmann_m))
                .sum(),
        }
    }

    /// [`Self::directional_albedo`] of each value of `theta_in_deg`, in parallel, each distinct value once. Stops with
    /// an "interrupted" error once `cancel` is set.
    pub fn directional_albedo_each(&self, theta_in_deg: &[f64], cancel: &AtomicBool) -> Result<Vec<f64>, SkinError> {
        for &theta in theta_in_deg {
            check_polar_deg("theta_in_deg", theta)?;
        }
        let mut distinct: Vec<f64> = theta_in_deg.to_vec();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup_by(|a, b| a.to_bits() == b.to_bits());
        let albedos: Vec<f64> = distinct
            .par_iter()
            .map(|&theta| {
                SkinError::check_cancel(cancel, "surface albedo")?;
                self.directional_albedo(theta)
            })
            .collect::<Result<_, _>>()?;
        Ok(theta_in_deg
            .iter()
            .map(|theta| albedos[distinct.binary_search_by(|d| d.total_cmp(theta)).unwrap_or_default()])
            .collect())
    }

    /// The normal-incidence reflectance `E(0)`, dimensionless: the share of light arriving along the normal that the
    /// surface reflects (all directions). `paper`: `specular_from_oiliness(o).directional_albedo_normal` (cached).
    pub fn normal_incidence_reflectance(&self) -> f64 {
        match self.model {
            SurfaceModel::Paper => self.oiliness * torrance_sparrow_unit_albedos().0,
            SurfaceModel::Measured => {
                lobes_albedo(&TWO_LOBE_TABLE.lobes(self.oiliness), 1.0, ALBEDO_THETA_PANELS, Some(SKIN_SURFACE_IOR))
            }
        }
    }
}

/// `f_r`, sr^-1, of `model` at `oiliness`: see [`SurfaceReflection::f_r_per_sr`].
pub fn surface_f_r_per_sr(
    model: SurfaceModel,
    oiliness: f64,
    theta_in_deg: f64,
    theta_out_deg: f64,
    phi_deg: f64,
) -> Result<f64, SkinError> {
    SurfaceReflection::new(model, oiliness)?.f_r_per_sr(theta_in_deg, theta_out_deg, phi_deg)
}

/// `E(theta_i)`, dimensionless, of `model` at `oiliness`: see [`SurfaceReflection::directional_albedo`].
pub fn surface_directional_albedo(model: SurfaceModel, oiliness: f64, theta_in_deg: f64) -> Result<f64, SkinError> {
    SurfaceReflection::new(model, oiliness)?.directional_albedo(theta_in_deg)
}

/// `E(0)`, dimensionless, of `model` at `oiliness`: see [`SurfaceReflection::normal_incidence_reflectance`].
pub fn surface_normal_incidence_reflectance(model: SurfaceModel, oiliness: f64) -> Result<f64, SkinError> {
    Ok(SurfaceReflection::new(model, oiliness)?.normal_incidence_reflectance())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::oil_layer::BECKMANN_ROUGHNESS_M;
    use crate::surface::principled::specular_from_oiliness;

    const OILINESS: [f64; 3] = [0.0, 0.3, 1.0];

    fn measured(oiliness: f64) -> SurfaceReflection {
        SurfaceReflection::new(SurfaceModel::Measured, oiliness).unwrap()
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    /// Composite Simpson's rule on [a, b] with `n` (even) intervals: the tests' own quadrature.
    fn simpson(a: f64, b: f64, n: usize, f: impl Fn(f64) -> f64) -> f64 {
        let h = (b - a) / n as f64;
        let inner: f64 = (1..n).map(|k| if k % 2 == 1 { 4.0 } else { 2.0 } * f(a + h * k as f64)).sum();
        h / 3.0 * (f(a) + inner + f(b))
    }

    /// Every Beckmann m the table produces (the broad lobe, the sharp lobe over the oiliness range).
    fn table_ms() -> Vec<f64> {
        let mut ms = vec![TWO_LOBE_TABLE.broad_beckmann_m];
        ms.extend(OILINESS.iter().map(|&o| TWO_LOBE_TABLE.lobes(o)[1].beckmann_m));
        ms
    }

    /// `int D(h) cos theta_h d omega_h = 2 pi int_0^{pi/2} D cos sin dtheta = 1` for each lobe's m, by Simpson's rule.
    #[test]
    fn beckmann_lobes_are_normalised() {
        for m in table_ms() {
            let total = 2.0 * PI * simpson(0.0, PI / 2.0, 20_000, |t| beckmann_d(t.cos(), m) * t.cos() * t.sin());
            assert!((total - 1.0).abs() < 1e-9, "m = {m}: {total}");
        }
    }

    /// Each lobe's D against pbrt-v3's `BeckmannDistribution::D` written out (isotropic: alpha_x = alpha_y = m):
    /// `exp(-tan^2 theta (cos^2 phi / ax^2 + sin^2 phi / ay^2)) / (pi ax ay cos^4 theta)`.
    #[test]
    fn beckmann_d_is_pbrt_v3s() {
        for m in table_ms() {
            for theta_deg in [0.0f64, 5.0, 17.0, 33.0, 50.0, 71.0, 88.0] {
                for phi_deg in [0.0f64, 40.0, 200.0] {
                    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
                    let (ax, ay) = (m, m);
                    let cos2 = t.cos() * t.cos();
                    let tan2 = t.tan() * t.tan();
                    let pbrt = (-tan2 * (p.cos().powi(2) / (ax * ax) + p.sin().powi(2) / (ay * ay))).exp()
                        / (PI * ax * ay * cos2 * cos2);
                    let ours = beckmann_d(t.cos(), m);
                    assert!(rel(ours, pbrt) < 1e-12 || (ours - pbrt).abs() < 1e-300, "m {m} theta {theta_deg}");
                }
            }
        }
    }

    /// Smith's G1 against the definition it solves (the projected area of the visible microfacets equals the
    /// geometric surface's: `int G1(o) max(0, o.h) D(h) d omega_h = cos theta_o`, Heitz 2014, JCGT 3(2), eq. 7), by a
    /// 2-D Simpson quadrature; and against Walter et al. 2007's rational approximation, eq. 27, written out
    /// (`(3.535 a + 2.181 a^2) / (1 + 2.276 a + 2.577 a^2)` for a < 1.6, else 1; pbrt-v3's Lambda), within its 0.35%.
    #[test]
    fn smith_g1_is_smiths() {
        for m in [0.15, 0.35, 0.5] {
            for theta_o_deg in [0.0f64, 30.0, 60.0, 80.0, 88.0] {
                let (sin_o, cos_o) = theta_o_deg.to_radians().sin_cos();
                let projected = 2.0
                    * simpson(0.0, PI / 2.0, 2000, |th| {
                        let (sin_h, cos_h) = th.sin_cos();
                        simpson(0.0, PI, 400, |ph| {
                            let o_dot_h = sin_o * sin_h * ph.cos() + cos_o * cos_h;
                            o_dot_h.max(0.0) * beckmann_d(cos_h, m) * sin_h
                        })
                    });
                let g1 = smith_g1_beckmann(cos_o, m);
                assert!((g1 * projected - cos_o).abs() < 1e-6 * cos_o, "m {m} theta {theta_o_deg}");
                let a = cos_o / (m * sin_o);
                let walter =
                    if a < 1.6 { (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) } else { 1.0 };
                assert!(rel(g1, walter) < 0.0035, "m {m} theta {theta_o_deg}: {g1} vs {walter}");
            }
        }
        // The shortcut: from a = 6 on the erf form itself rounds to exactly 1.
        for a in [SMITH_A_EXACTLY_ONE, 7.5, 20.0] {
            let lambda = 0.5 * ((-a * a).exp() / (a * PI.sqrt()) - libm::erfc(a));
            assert_eq!(1.0 / (1.0 + lambda), 1.0, "a = {a}");
        }
        assert_eq!(smith_g1_beckmann(1.0, 0.5), 1.0);
        assert_eq!(smith_g1_beckmann(0.0, 0.5), 0.0);
    }

    /// At normal incidence and exitance h = n, D_k = 1 / (pi m_k^2), G = 1, F = ((eta - 1) / (eta + 1))^2:
    /// `f_r = F0 sum_k w_k D_k(0) / 4`.
    #[test]
    fn normal_incidence_brdf_written_out() {
        let eta = 1.4f64;
        let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!((f0 - 0.0278).abs() < 1e-4, "F0 = {f0}");
        for o in OILINESS {
            let w_sharp = 0.15 + 0.70 * o;
            let m_sharp = 0.25 - 0.10 * o;
            let d = |m: f64| 1.0 / (PI * m * m);
            let want = f0 * ((1.0 - w_sharp) * d(0.5) + w_sharp * d(m_sharp)) * 1.0 / 4.0;
            let got = measured(o).f_r_per_sr(0.0, 0.0, 180.0).unwrap();
            assert!(rel(got, want) < 1e-12, "o = {o}: {got} vs {want}");
        }
    }

    /// Unpolarised Fresnel reflectance of a smooth dielectric written out (Fresnel's equations, as in Born & Wolf):
    /// `rs = (cos_i - n cos_t) / (cos_i + n cos_t)`, `rp = (n cos_i - cos_t) / (n cos_i + cos_t)`,
    /// `R = (rs^2 + rp^2) / 2`.
    fn smooth_fresnel(theta_i_deg: f64, n: f64) -> f64 {
        let (sin_i, cos_i) = theta_i_deg.to_radians().sin_cos();
        let cos_t = (1.0 - (sin_i / n).powi(2)).sqrt();
        let rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
        let rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
        0.5 * (rs * rs + rp * rp)
    }

    /// As both lobes' roughness goes to 0, E(theta) goes to the smooth dielectric's Fresnel reflectance.
    #[test]
    fn smooth_limit_is_fresnel() {
        for theta in [0.0f64, 30.0, 60.0] {
            let want = smooth_fresnel(theta, SKIN_SURFACE_IOR);
            let mut last_error = f64::INFINITY;
            for m in [0.04, 0.02, 0.01] {
                let lobes =
                    [BeckmannLobe { weight: 0.4, beckmann_m: m }, BeckmannLobe { weight: 0.6, beckmann_m: 0.5 * m }];
                let cos_i = theta.to_radians().cos();
                let got = lobes_albedo(&lobes, cos_i, 4 * ALBEDO_THETA_PANELS, Some(SKIN_SURFACE_IOR));
                let error = rel(got, want);
                assert!(error <= last_error + 1e-9, "theta {theta} m {m}: {got} vs {want}");
                last_error = error;
            }
            // The error falls as m^2 (the Fresnel term varies over the lobe): 1.4e-4 at 60 degrees, m = 0.01.
            assert!(last_error < 2e-4, "theta {theta}: error {last_error}");
        }
    }

    #[test]
    fn reciprocal() {
        for model in ALL_SURFACE_MODELS {
            for o in OILINESS {
                let s = SurfaceReflection::new(model, o).unwrap();
                for (ti, to, phi) in [(0.0, 40.0, 180.0), (10.0, 70.0, 123.0), (35.0, 35.0, 180.0), (80.0, 5.0, 30.0)] {
                    let (a, b) = (s.f_r_per_sr(ti, to, phi).unwrap(), s.f_r_per_sr(to, ti, phi).unwrap());
                    assert!(rel(a, b) < 1e-12 || (o == 0.0 && model == SurfaceModel::Paper), "{model:?} {o}: {a} {b}");
                }
            }
        }
    }

    /// E <= 1 (F = 1: the white furnace loses only what Smith's G shadows); with Fresnel, F0 E_white <= E <=
    /// F_max E_white, where F_max = F at the largest half-angle a reflection from theta_i can have,
    /// cos theta_d = cos((90 deg + theta_i) / 2) (F rises with the angle for eta > 1).
    #[test]
    fn energy_bounds() {
        let f0 = smooth_fresnel(0.0, SKIN_SURFACE_IOR);
        for o in OILINESS {
            let lobes = TWO_LOBE_TABLE.lobes(o);
            for theta in [0.0f64, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0] {
                let cos_i = theta.to_radians().cos();
                let white = lobes_albedo(&lobes, cos_i, ALBEDO_THETA_PANELS, None);
                let e = measured(o).directional_albedo(theta).unwrap();
                let f_max = smooth_fresnel(0.5 * (90.0 + theta), SKIN_SURFACE_IOR);
                assert!(white <= 1.0 + 1e-9 && white > 0.85, "o {o} theta {theta}: white furnace {white}");
                assert!(f0 * white <= e && e <= f_max * white && e <= 1.0, "o {o} theta {theta}: {e}");
            }
        }
    }

    /// Four times the theta_h panels changes E by < 1e-6 relative.
    #[test]
    fn albedo_quadrature_converged() {
        for o in OILINESS {
            let lobes = TWO_LOBE_TABLE.lobes(o);
            for theta in [0.0f64, 30.0, 60.0, 75.0, 89.0] {
                let cos_i = theta.to_radians().cos();
                let eta = Some(SKIN_SURFACE_IOR);
                let (base, fine) = (
                    lobes_albedo(&lobes, cos_i, ALBEDO_THETA_PANELS, eta),
                    lobes_albedo(&lobes, cos_i, 4 * ALBEDO_THETA_PANELS, eta),
                );
                assert!(rel(base, fine) < 1e-6, "o {o} theta {theta}: {base} vs {fine}");
            }
        }
    }

    /// E by direct integration of f_r cos theta_o over the outgoing hemisphere (Simpson in theta_o and phi), an
    /// independent check of the half-vector quadrature.
    #[test]
    fn albedo_matches_direct_integration() {
        for o in [0.0, 1.0] {
            let s = measured(o);
            for theta in [0.0f64, 40.0, 70.0] {
                let direct =
                    2.0 * simpson(0.0, 89.999, 3000, |to_deg| {
                        let (sin_o, cos_o) = to_deg.to_radians().sin_cos();
                        simpson(0.0, 180.0, 600, |phi| s.f_r_per_sr(theta, to_deg, phi).unwrap() * cos_o * sin_o) * PI
                            / 180.0
                    }) * PI
                        / 180.0;
                let quad = s.directional_albedo(theta).unwrap();
                assert!(rel(quad, direct) < 1e-7, "o {o} theta {theta}: half-vector {quad} vs direct {direct}");
            }
        }
    }

    #[test]
    fn oil_sharpens_and_weights_the_sharp_lobe() {
        let mut last: Option<[BeckmannLobe; 2]> = None;
        for k in 0..=10 {
            let lobes = measured_lobes(k as f64 / 10.0).unwrap();
            assert!(
                (lobes[0].weight + lobes[1].weight - 1.0).abs() < 1e-15,
                "k {k}: weights {} + {}",
                lobes[0].weight,
                lobes[1].weight
            );
            assert_eq!(lobes[0].beckmann_m, 0.5, "k {k}");
            assert!(
                lobes[1].beckmann_m < lobes[0].beckmann_m && lobes[1].beckmann_m > 0.0,
                "k {k}: sharp m {} vs broad m {}",
                lobes[1].beckmann_m,
                lobes[0].beckmann_m
            );
            // DJ2006's and d'Eon & Luebke's single lobes lie between the two.
            for single in [BECKMANN_ROUGHNESS_M, 0.3] {
                assert!(
                    lobes[1].beckmann_m < single && single < lobes[0].beckmann_m,
                    "k {k}: single m {single} vs sharp m {} and broad m {}",
                    lobes[1].beckmann_m,
                    lobes[0].beckmann_m
                );
            }
            if let Some(prev) = last {
                assert!(lobes[1].weight > prev[1].weight, "oil raises the sharp lobe's weight");
                assert!(lobes[1].beckmann_m < prev[1].beckmann_m, "oil lowers the sharp lobe's roughness");
            }
            last = Some(lobes);
        }
        // Oil sharpens the highlight: the mirror peak at 30 degrees rises with oiliness.
        let peak = |o: f64| measured(o).f_r_per_sr(30.0, 30.0, 180.0).unwrap();
        assert!(peak(0.0) < peak(0.3) && peak(0.3) < peak(1.0), "{} {} {}", peak(0.0), peak(0.3), peak(1.0));
    }

    /// Dry skin reflects: E(0) of the measured model is about F0 at every oiliness; the paper's is o times it.
    #[test]
    fn dry_skin_reflects() {
        for o in OILINESS {
            let e0 = measured(o).normal_incidence_reflectance();
            assert!((0.024..=0.05).contains(&e0), "o {o}: {e0}");
            assert_eq!(e0, measured(o).directional_albedo(0.0).unwrap(), "o {o}");
        }
        assert_eq!(surface_normal_incidence_reflectance(SurfaceModel::Paper, 0.0).unwrap(), 0.0);
        assert_eq!(surface_f_r_per_sr(SurfaceModel::Paper, 0.0, 20.0, 20.0, 180.0).unwrap(), 0.0);
    }

    /// "paper" is `surface`'s oil layer, bit for bit.
    #[test]
    fn paper_is_surface_rs() {
        for o in [0.0, 0.3, 0.77, 1.0] {
            let s = SurfaceReflection::new(SurfaceModel::Paper, o).unwrap();
            for (ti, to, phi) in [(0.0, 0.0, 180.0), (30.0, 30.0, 180.0), (10.0, 60.0, 45.0), (75.0, 20.0, 270.0)] {
                let (st, ct) = f64::to_radians(ti).sin_cos();
                let (so, co) = f64::to_radians(to).sin_cos();
                let (sp, cp) = f64::to_radians(phi).sin_cos();
                let want = torrance_sparrow_f_r([st, 0.0, ct], [so * cp, so * sp, co], o);
                assert_eq!(s.f_r_per_sr(ti, to, phi).unwrap().to_bits(), want.to_bits(), "o {o} ({ti}, {to}, {phi})");
            }
            for theta in [0.0f64, 30.0, 60.0, 75.0] {
                let want = torrance_sparrow_directional_albedo(theta.to_radians().cos(), o);
                assert_eq!(s.directional_albedo(theta).unwrap().to_bits(), want.to_bits(), "o {o} theta {theta}");
            }
            let want = specular_from_oiliness(o).directional_albedo_normal;
            assert_eq!(s.normal_incidence_reflectance().to_bits(), want.to_bits(), "o {o}");
            assert_eq!(s.directional_albedo(0.0).unwrap().to_bits(), want.to_bits(), "o {o}");
        }
    }

    #[test]
    fn invalid_input_is_refused() {
        let message = |e: SkinError| e.to_string();
        for o in [-0.1, 1.1, f64::NAN, f64::INFINITY] {
            for model in ALL_SURFACE_MODELS {
                let e = message(SurfaceReflection::new(model, o).unwrap_err());
                assert!(e.contains("oiliness") && e.contains("[0, 1]"), "{e}");
            }
        }
        let s = measured(0.3);
        for bad in [-1.0, 90.0, 95.0, f64::NAN, f64::NEG_INFINITY] {
            let e = message(s.f_r_per_sr(bad, 10.0, 180.0).unwrap_err());
            assert!(e.contains("theta_in_deg") && e.contains("[0, 90)"), "{e}");
            let e = message(s.f_r_per_sr(10.0, bad, 180.0).unwrap_err());
            assert!(e.contains("theta_out_deg") && e.contains("[0, 90)"), "{e}");
            let e = message(s.directional_albedo(bad).unwrap_err());
            assert!(e.contains("theta_in_deg") && e.contains("[0, 90)"), "{e}");
        }
        for bad in [f64::NAN, f64::INFINITY] {
            assert!(
                message(s.f_r_per_sr(10.0, 10.0, bad).unwrap_err()).contains("phi_deg"),
                "phi {bad}: {}",
                message(s.f_r_per_sr(10.0, 10.0, bad).unwrap_err())
            );
        }
        assert!(
            message(s.f_r_per_sr_each(&[1.0], &[1.0, 2.0], &[180.0]).unwrap_err()).contains("theta_out_deg"),
            "{}",
            message(s.f_r_per_sr_each(&[1.0], &[1.0, 2.0], &[180.0]).unwrap_err())
        );
        let never = AtomicBool::new(false);
        assert!(
            message(s.directional_albedo_each(&[10.0, 90.0], &never).unwrap_err()).contains("theta_in_deg"),
            "{}",
            message(s.directional_albedo_each(&[10.0, 90.0], &never).unwrap_err())
        );
        let stopped = AtomicBool::new(true);
        assert!(
            message(s.directional_albedo_each(&[10.0], &stopped).unwrap_err()).contains("interrupted"),
            "{}",
            message(s.directional_albedo_each(&[10.0], &stopped).unwrap_err())
        );
    }

    #[test]
    fn batches_match_single_calls() {
        let s = measured(0.3);
        let thetas = [60.0, 0.0, 30.0, 60.0, 0.0];
        let each = s.directional_albedo_each(&thetas, &AtomicBool::new(false)).unwrap();
        for (theta, e) in thetas.iter().zip(&each) {
            assert_eq!(e.to_bits(), s.directional_albedo(*theta).unwrap().to_bits(), "theta {theta}");
        }
        let f = s.f_r_per_sr_each(&[10.0, 20.0], &[10.0, 50.0], &[180.0, 90.0]).unwrap();
        assert_eq!(f[1].to_bits(), s.f_r_per_sr(20.0, 50.0, 90.0).unwrap().to_bits());
    }

    /// The numbers docs/model.md quotes (run with --nocapture to print them).
    #[test]
    fn print_reference_numbers() {
        for model in ALL_SURFACE_MODELS {
            for o in OILINESS {
                let s = SurfaceReflection::new(model, o).unwrap();
                let e: Vec<String> = [0.0, 30.0, 60.0, 75.0]
                    .iter()
                    .map(|&t| format!("{:.5}", s.directional_albedo(t).unwrap()))
                    .collect();
                println!(
                    "{model:?} o={o}: E(0)={:.5} E(0/30/60/75)={} f_r(0,0)={:.4} f_r(30,30)={:.4}",
                    s.normal_incidence_reflectance(),
                    e.join(" / "),
                    s.f_r_per_sr(0.0, 0.0, 180.0).unwrap(),
                    s.f_r_per_sr(30.0, 30.0, 180.0).unwrap()
                );
            }
        }
    }
}
