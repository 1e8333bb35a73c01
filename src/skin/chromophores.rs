//! Absorption spectra of the skin's chromophores, in mm^-1 (DJ2006 eqs. 3-5; docs/model.md, section Absorption).

use std::sync::OnceLock;

use crate::table::SpectralTable;

/// Eumelanin constant `K_em` of DJ2006 eq. 3, in mm^-1 (with wavelength in nm). The printed 6.6e11 is Jacques' cm^-1 value;
/// every implementation uses 6.6e10 mm^-1 (docs/model.md, section Absorption, and Pitfalls 1).
pub const K_EM_PER_MM: f64 = 6.6e10;
/// Eumelanin wavelength exponent (DJ2006 eq. 3).
const EUMELANIN_EXPONENT: f64 = -3.33;
/// Pheomelanin constant of DJ2006 eq. 4, in mm^-1 (consensus 2.9e14 mm^-1 = 2.9e15 cm^-1; docs/model.md, section
/// Absorption).
pub const K_PM_PER_MM: f64 = 2.9e14;
/// Pheomelanin wavelength exponent (DJ2006 eq. 4).
const PHEOMELANIN_EXPONENT: f64 = -4.75;
/// Haemoglobin concentration of whole blood, g/L (Prahl's conversion; docs/model.md, section Absorption).
pub const HEMOGLOBIN_G_PER_L: f64 = 150.0;
/// Molar mass of haemoglobin, g/mol (Prahl; docs/model.md, section Absorption).
pub const HEMOGLOBIN_G_PER_MOL: f64 = 64_500.0;

const HEMOGLOBIN_CSV: &str = include_str!("../../data/hemoglobin_extinction.csv");

fn hemoglobin_table() -> &'static SpectralTable {
    static TABLE: OnceLock<SpectralTable> = OnceLock::new();
    TABLE.get_or_init(|| SpectralTable::parse(HEMOGLOBIN_CSV))
}

/// `sigma_a_em(lambda)`: eumelanin absorption, mm^-1, with the given `K_em` (DJ2006 eq. 3).
pub fn sigma_a_eumelanin_per_mm(wavelength_nm: f64, k_em_per_mm: f64) -> f64 {
    k_em_per_mm * wavelength_nm.powf(EUMELANIN_EXPONENT)
}

/// `sigma_a_pm(lambda)`: pheomelanin absorption, mm^-1 (DJ2006 eq. 4).
pub fn sigma_a_pheomelanin_per_mm(wavelength_nm: f64) -> f64 {
    K_PM_PER_MM * wavelength_nm.powf(PHEOMELANIN_EXPONENT)
}

/// `sigma_a_baseline(lambda)`: melanin- and blood-free tissue absorption, mm^-1 (DJ2006 eq. 5; Jacques 1998 divided by 10).
pub fn sigma_a_baseline_per_mm(wavelength_nm: f64) -> f64 {
    0.0244 + 8.53 * (-(wavelength_nm - 154.0) / 66.2).exp()
}

/// Whole-blood absorption from a decadic molar extinction in cm^-1/M: ln(10) eps c / M, then /10 for mm^-1
/// (docs/model.md, Absorption).
fn blood_sigma_a_per_mm(extinction_per_cm_per_molar: f64) -> f64 {
    std::f64::consts::LN_10 * extinction_per_cm_per_molar * (HEMOGLOBIN_G_PER_L / HEMOGLOBIN_G_PER_MOL) / 10.0
}

/// `sigma_a_oxy(lambda)`: absorption of fully oxygenated whole blood, mm^-1 (Prahl's HbO2 table, linearly interpolated).
pub fn sigma_a_oxy_blood_per_mm(wavelength_nm: f64) -> f64 {
    blood_sigma_a_per_mm(hemoglobin_table().interpolate(0, wavelength_nm))
}

/// `sigma_a_deoxy(lambda)`: absorption of fully deoxygenated whole blood, mm^-1 (Prahl's Hb table, linearly interpolated).
pub fn sigma_a_deoxy_blood_per_mm(wavelength_nm: f64) -> f64 {
    blood_sigma_a_per_mm(hemoglobin_table().interpolate(1, wavelength_nm))
}

/// The largest blood vessel radius the packaging correction accepts, mm: 0.1 mm, twice the largest vessels of the
/// superficial dermal plexus (venules up to about 0.1 mm across; Braverman, "The cutaneous microcirculation", J.
/// Investig. Dermatol. Symp. Proc. 5:3, 2000); deeper, larger vessels lie below the light's reach in the visible.
pub const MAX_VESSEL_RADIUS_MM: f64 = 0.1;

/// The vessel packaging factor of blood of absorption `sigma_a_blood_per_mm` confined to cylinders of radius
/// `vessel_radius_mm`: C_pack = (1 - exp(-2 mu_a R)) / (2 mu_a R), Svaasand et al.'s correction (Lasers Med. Sci.
/// 10:55, 1995) in the form of van Veen, Verkruysse & Sterenborg (Opt. Lett. 27:246, 2002; also Zonios et al., J.
/// Invest. Dermatol. 117:1452, 2001). The blood's mean absorption over the tissue is C_pack times that of the same
/// blood spread evenly: light crossing a vessel is absorbed at most once, so a vessel absorbs less than its blood
/// would spread out, the more so where blood absorbs strongly (the Soret band, the Q-band peaks). 1 at R = 0.
pub fn vessel_packaging_factor(sigma_a_blood_per_mm: f64, vessel_radius_mm: f64) -> f64 {
    let x = 2.0 * sigma_a_blood_per_mm * vessel_radius_mm;
    if x < 1e-12 {
        1.0
    } else {
        -(-x).exp_m1() / x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        ((a - b) / b).abs() < rel
    }

    /// Independently computed values (docs/model.md, section Reference numbers).
    #[test]
    fn coefficients_match_spec_table() {
        let rows = [
            (450.0, 0.12192, 96.460, 72.383, 33.637, 55.311),
            (550.0, 0.04593, 49.447, 27.905, 23.034, 28.601),
            (650.0, 0.02915, 28.349, 12.620, 0.1971, 2.0081),
        ];
        for (w, base, em, pm, oxy, deoxy) in rows {
            assert!(close(sigma_a_baseline_per_mm(w), base, 1e-3), "baseline {w}");
            assert!(close(sigma_a_eumelanin_per_mm(w, K_EM_PER_MM), em, 1e-4), "em {w}");
            assert!(close(sigma_a_pheomelanin_per_mm(w), pm, 1e-4), "pm {w}");
            assert!(close(sigma_a_oxy_blood_per_mm(w), oxy, 1e-3), "oxy {w}: {}", sigma_a_oxy_blood_per_mm(w));
            assert!(close(sigma_a_deoxy_blood_per_mm(w), deoxy, 1e-3), "deoxy {w}");
        }
    }

    /// C_pack: 1 without packaging, 1 - x/2 for small x = 2 mu_a R, 1/x for large (the vessel absorbs all that
    /// crosses it), and (1 - e^-1) at x = 1.
    #[test]
    fn packaging_factor_limits() {
        assert_eq!(vessel_packaging_factor(30.0, 0.0), 1.0);
        assert!((vessel_packaging_factor(1e-6, 1e-3) - 1.0).abs() < 1e-9);
        assert!((vessel_packaging_factor(25.0, 0.02) - (1.0 - (-1.0f64).exp())).abs() < 1e-12);
        assert!((vessel_packaging_factor(300.0, 0.05) * 30.0 - 1.0).abs() < 1e-9);
    }

    /// Prahl's table peaks (docs/model.md, section Data files): HbO2 Soret at 414 nm.
    #[test]
    fn soret_peak() {
        let peak = sigma_a_oxy_blood_per_mm(414.0);
        assert!(
            peak > sigma_a_oxy_blood_per_mm(406.0) && peak > sigma_a_oxy_blood_per_mm(422.0),
            "414 nm {peak} vs 406 nm {} and 422 nm {}",
            sigma_a_oxy_blood_per_mm(406.0),
            sigma_a_oxy_blood_per_mm(422.0)
        );
    }
}
