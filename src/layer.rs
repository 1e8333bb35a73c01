//! One layer's optics at one wavelength (thickness, absorption, reduced scattering, index) and the ranges a layer
//! is accepted in: the floor below every transport (the multipole in `diffusion`, the adding-doubling and the exact
//! profile shapes in `transport`) and the reflectance that composes them (`reflectance`).

use serde::{Deserialize, Serialize};

use crate::error::SkinError;

/// One layer's optics at one wavelength (top to bottom in a stack).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// Thickness, mm; `f64::INFINITY` for a semi-infinite last layer.
    pub thickness_mm: f64,
    /// Absorption coefficient, mm^-1.
    pub sigma_a_per_mm: f64,
    /// Reduced scattering coefficient sigma_s (1 - g), mm^-1.
    pub sigma_s_reduced_per_mm: f64,
    /// Index of refraction.
    pub ior: f64,
}

/// Indices of refraction accepted for a layer. With air (1) above, every relative index at a boundary then lies in
/// [1/2, 2], where the polynomial fits of F_dr (see `diffusion::boundary`) stay within 0.5 % of the exact diffuse Fresnel
/// integral in A = (1 + F_dr) / (1 - F_dr); beyond it they part fast (A is 4.6 % off at 2.5 and 7 % at 0.4, F_dr
/// reaches 1 at 3.85 and at 0.26), which `boundary`'s tests measure against the integral.
pub const IOR_RANGE: (f64, f64) = (1.0, 2.0);
/// Nonzero absorption and reduced scattering coefficients accepted, mm^-1. Below 1e-12 a coefficient is zero to
/// every output (1e-12 mm^-1 is one event per 10^9 m); above 1e6 mm^-1 the mean free path is under a nanometre,
/// beyond geometrical optics, and the transforms would need frequencies past the quadrature's 1e9 mm^-1 probe.
pub const COEFFICIENT_RANGE_PER_MM: (f64, f64) = (1e-12, 1e6);
/// Finite thicknesses accepted, mm: from a hundredth of a nanometre to a kilometre (use infinity for thicker).
pub const THICKNESS_RANGE_MM: (f64, f64) = (1e-11, 1e6);

impl Layer {
    fn validate(&self, index: usize, is_last: bool) -> Result<(), SkinError> {
        // The name is formatted only for an error: validation runs for every wavelength of every evaluation.
        let bad = |reason: String| Err(SkinError::invalid(format!("layer {index}"), reason));
        let t = self.thickness_mm;
        let (t_min, t_max) = THICKNESS_RANGE_MM;
        let finite_ok = t.is_finite() && (t_min..=t_max).contains(&t);
        if !(finite_ok || (t == f64::INFINITY && is_last)) {
            return bad(format!(
                "thickness_mm must be in [{t_min:e}, {t_max:e}] mm (infinity only for the last layer); got {}",
                readable(t)
            ));
        }
        let (c_min, c_max) = COEFFICIENT_RANGE_PER_MM;
        for (field, value) in
            [("sigma_a_per_mm", self.sigma_a_per_mm), ("sigma_s_reduced_per_mm", self.sigma_s_reduced_per_mm)]
        {
            if !(value == 0.0 || (c_min..=c_max).contains(&value)) {
                let sign = if value < 0.0 { ">= 0: " } else { "" };
                return bad(format!(
                    "{field} must be {sign}0 or in [{c_min:e}, {c_max:e}] per mm; got {}",
                    readable(value)
                ));
            }
        }
        if self.sigma_a_per_mm + self.sigma_s_reduced_per_mm <= 0.0 {
            return bad("sigma_a_per_mm + sigma_s_reduced_per_mm must be > 0 (a layer must interact with light)".into());
        }
        let (n_min, n_max) = IOR_RANGE;
        if !(self.ior.is_finite() && (n_min..=n_max).contains(&self.ior)) {
            return bad(format!(
                "ior must be in [{n_min}, {n_max}] (the range where the diffuse Fresnel fits hold); got {}",
                self.ior
            ));
        }
        Ok(())
    }
}

/// At least one layer, each valid ([`Layer`]'s ranges), infinite thickness only for the last.
pub(crate) fn validate_layers(layers: &[Layer]) -> Result<(), SkinError> {
    if layers.is_empty() {
        return Err(SkinError::invalid("layers", "need at least one layer"));
    }
    let last = layers.len() - 1;
    layers.iter().enumerate().try_for_each(|(i, layer)| layer.validate(i, i == last))
}

/// A number as written by hand where that is short (0.25, -0.1, 1e101, 1e-310).
fn readable(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
