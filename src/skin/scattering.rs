//! Reduced scattering of the skin layers, in mm^-1 (DJ2006 eq. 8; docs/model.md, section Scattering).

use serde::{Deserialize, Serialize};

/// Mie-like term of DJ2006 eq. 8: 14.74 lambda^-0.22 mm^-1 (the paper's own fit).
const MIE_COEFFICIENT_PER_MM: f64 = 14.74;
const MIE_EXPONENT: f64 = -0.22;
/// Rayleigh term of DJ2006 eq. 8: 2.2e11 lambda^-4 mm^-1 (Jacques' 2e12 cm^-1 with 2.2 for 2).
const RAYLEIGH_COEFFICIENT_PER_MM: f64 = 2.2e11;
/// The dermis scatters half as much as the epidermis (DJ2006 as read by every implementation; docs/model.md, section
/// Scattering).
pub const DERMIS_SCATTERING_RATIO: f64 = 0.5;

/// `sigma_s'_epi(lambda)`: reduced scattering of the epidermis, mm^-1 (DJ2006 eq. 8).
pub fn sigma_s_reduced_epidermis_per_mm(wavelength_nm: f64) -> f64 {
    MIE_COEFFICIENT_PER_MM * wavelength_nm.powf(MIE_EXPONENT) + RAYLEIGH_COEFFICIENT_PER_MM * wavelength_nm.powi(-4)
}

/// `sigma_s'_derm(lambda)`: reduced scattering of the dermis, mm^-1 (half the epidermis).
pub fn sigma_s_reduced_dermis_per_mm(wavelength_nm: f64) -> f64 {
    DERMIS_SCATTERING_RATIO * sigma_s_reduced_epidermis_per_mm(wavelength_nm)
}

/// The wavelength where an alternative scattering spectrum ([`ScatteringShape`]) equals DJ2006's eq. 8, nm: the same
/// mid-visible reference as the eumelanin shapes (`chromophores::EUMELANIN_SHAPE_REFERENCE_NM`), so that only the
/// spectrum's shape changes, not its magnitude.
pub const SCATTERING_SHAPE_REFERENCE_NM: f64 = 550.0;

/// The shape of both layers' reduced-scattering spectrum: DJ2006's eq. 8 (the default) or the Mie + Rayleigh form of
/// Jacques' reviews, `f_ray (λ/500)^-4 + (1 - f_ray) (λ/500)^-b_mie` (Jacques, "Optical properties of biological
/// tissues: a review", Phys. Med. Biol. 58:R37, 2013, eq. 2), scaled to equal eq. 8 at
/// [`SCATTERING_SHAPE_REFERENCE_NM`] (the dermis keeps half the epidermis). An option for issue 39's study of dark
/// skin's red-end misfit (examples/measured_skin_report/study.rs), off by default. `f_ray = 0` is a single power law
/// `λ^-b_mie` (the review's eq. 1). For comparison, eq. 8 is 48 % Rayleigh at 500 nm with a Mie exponent of 0.22.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScatteringShape {
    /// DJ2006 eq. 8: `14.74 λ^-0.22 + 2.2e11 λ^-4` mm^-1.
    #[default]
    Dj2006,
    /// `f_ray (λ/500)^-4 + (1 - f_ray) (λ/500)^-b_mie`, f_ray in 0..=1, b_mie in 0..=4. The dermis of Jacques and
    /// Li's mcxyz Monte Carlo tissue list has f_ray = 0.62, b_mie = 1.0 (µs'(500 nm) = 42.4 cm^-1; makeTissueList.m,
    /// omlc.org/software/mc/mcxyz, 2013).
    MieRayleigh { f_ray: f64, b_mie: f64 },
}

impl ScatteringShape {
    /// True for DJ2006's eq. 8 (the default).
    pub fn is_default(&self) -> bool {
        *self == ScatteringShape::Dj2006
    }

    /// The epidermis's reduced scattering, mm^-1, of this shape.
    pub fn epidermis_per_mm(self, wavelength_nm: f64) -> f64 {
        match self {
            ScatteringShape::Dj2006 => sigma_s_reduced_epidermis_per_mm(wavelength_nm),
            ScatteringShape::MieRayleigh { f_ray, b_mie } => {
                let form = |w: f64| {
                    let x = w / 500.0;
                    f_ray * x.powi(-4) + (1.0 - f_ray) * x.powf(-b_mie)
                };
                let r = SCATTERING_SHAPE_REFERENCE_NM;
                sigma_s_reduced_epidermis_per_mm(r) * form(wavelength_nm) / form(r)
            }
        }
    }

    /// The dermis's reduced scattering, mm^-1, of this shape ([`DERMIS_SCATTERING_RATIO`] times the epidermis's).
    pub fn dermis_per_mm(self, wavelength_nm: f64) -> f64 {
        DERMIS_SCATTERING_RATIO * self.epidermis_per_mm(wavelength_nm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independently computed values (docs/model.md, section Reference numbers).
    #[test]
    fn matches_spec_values() {
        for (w, v) in [(450.0, 9.2091), (550.0, 6.0823), (650.0, 4.7778), (700.0, 4.40)] {
            let got = sigma_s_reduced_epidermis_per_mm(w);
            assert!(((got - v) / v).abs() < 2e-3, "{w}: {got}");
            assert_eq!(ScatteringShape::Dj2006.epidermis_per_mm(w), got);
        }
    }

    #[test]
    fn shapes_meet_eq8_at_the_reference() {
        let r = SCATTERING_SHAPE_REFERENCE_NM;
        let mcxyz = ScatteringShape::MieRayleigh { f_ray: 0.62, b_mie: 1.0 };
        assert!((mcxyz.epidermis_per_mm(r) / sigma_s_reduced_epidermis_per_mm(r) - 1.0).abs() < 1e-12);
        assert!((mcxyz.dermis_per_mm(r) / sigma_s_reduced_dermis_per_mm(r) - 1.0).abs() < 1e-12);
        // A single power law λ^-1.5: 700 over 500 nm is (1.4)^-1.5.
        let p = ScatteringShape::MieRayleigh { f_ray: 0.0, b_mie: 1.5 };
        assert!((p.epidermis_per_mm(700.0) / p.epidermis_per_mm(500.0) - 1.4f64.powf(-1.5)).abs() < 1e-12);
    }
}
