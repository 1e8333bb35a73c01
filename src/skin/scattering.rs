//! Reduced scattering of the skin layers, in mm^-1 (DJ2006 eq. 8; docs/model.md, section Scattering).

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Independently computed values (docs/model.md, section Reference numbers).
    #[test]
    fn matches_spec_values() {
        for (w, v) in [(450.0, 9.2091), (550.0, 6.0823), (650.0, 4.7778), (700.0, 4.40)] {
            let got = sigma_s_reduced_epidermis_per_mm(w);
            assert!(((got - v) / v).abs() < 2e-3, "{w}: {got}");
        }
    }
}
