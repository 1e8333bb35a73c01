//! Absorption spectra of the skin's chromophores, in mm^-1 (DJ2006 eqs. 3-5; docs/model.md, section Absorption).

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

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

const CAROTENE_CSV: &str = include_str!("../../data/beta_carotene_extinction.csv");

/// The most epidermal β-carotene the model accepts, µmol/L: ten times the 10 µmol/L the study tries
/// (examples/measured_skin_report/study.rs); skin carotenoid contents are of the order of 0.1-1 nmol per gram of
/// tissue (about µmol/L; docs/model.md, Epidermal carotene).
pub const MAX_CAROTENE_UMOL_PER_L: f64 = 100.0;

fn carotene_table() -> &'static SpectralTable {
    static TABLE: OnceLock<SpectralTable> = OnceLock::new();
    TABLE.get_or_init(|| SpectralTable::parse(CAROTENE_CSV))
}

/// Absorption of β-carotene at `umol_per_l` µmol/L, mm^-1: ln(10) ε c, ε the decadic molar extinction of
/// data/beta_carotene_extinction.csv (PhotochemCAD, in hexane; 139500 cm^-1/M at 451 nm), 0 beyond 540 nm.
pub fn sigma_a_carotene_per_mm(wavelength_nm: f64, umol_per_l: f64) -> f64 {
    if umol_per_l == 0.0 {
        return 0.0;
    }
    let per_cm_per_molar = carotene_table().interpolate(0, wavelength_nm).max(0.0);
    std::f64::consts::LN_10 * per_cm_per_molar * umol_per_l * 1e-6 / 10.0
}

/// `sigma_a_em(lambda)`: eumelanin absorption, mm^-1, with the given `K_em` (DJ2006 eq. 3).
pub fn sigma_a_eumelanin_per_mm(wavelength_nm: f64, k_em_per_mm: f64) -> f64 {
    k_em_per_mm * wavelength_nm.powf(EUMELANIN_EXPONENT)
}

/// The wavelength where an alternative eumelanin shape ([`EumelaninShape`]) equals DJ2006's eq. 3 with the same
/// `K_em`, nm: mid-visible, so that a fitted melanin fraction keeps about its meaning. Jacques' melanosome law
/// (1.70e12 λ^-3.48 cm^-1) and eq. 3's (6.6e11 λ^-3.33 cm^-1) already agree there within 0.1 %.
pub const EUMELANIN_SHAPE_REFERENCE_NM: f64 = 550.0;

/// The shape of the eumelanin absorption spectrum: DJ2006's eq. 3 (the default) or a published alternative, for
/// issue 39's study of the fit's spectral misfit (examples/measured_skin_report/study.rs). An option of the model, off
/// by default: the alternatives are scaled to equal eq. 3 (with the model's `K_em`) at
/// [`EUMELANIN_SHAPE_REFERENCE_NM`], so only the shape changes. Pheomelanin (eq. 4) is unchanged by it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EumelaninShape {
    /// `K_em λ^-3.33` (DJ2006 eq. 3; Jacques 1998's skin-optics summary).
    #[default]
    Dj2006,
    /// `λ^exponent`: -3.48 is Jacques' melanosome-interior law, µa = 1.70e12 λ^-3.48 cm^-1 for skin (Jacques,
    /// Glickman & Schwartz, Proc. SPIE 2681:468, 1996; omlc.org/spectra/melanin/mua.html, 1998).
    PowerLaw { exponent: f64 },
    /// `exp(-k λ)`, k in nm^-1: the exponential form Zonios et al. found for in-vivo melanin by diffuse reflectance
    /// (J. Biomed. Opt. 13:014017, 2008; Zonios & Dimou, Opt. Express 16:8263, 2008), with a steeper slope than
    /// in vitro. For comparison, eq. 3's local slope, 3.33 / λ, is 0.0061 nm^-1 at 550 nm and 0.0048 at 700.
    Exponential { k_per_nm: f64 },
}

impl EumelaninShape {
    /// The shape's value relative to its value at [`EUMELANIN_SHAPE_REFERENCE_NM`] (1 there).
    fn relative(self, wavelength_nm: f64) -> f64 {
        let r = EUMELANIN_SHAPE_REFERENCE_NM;
        match self {
            EumelaninShape::Dj2006 => (wavelength_nm / r).powf(EUMELANIN_EXPONENT),
            EumelaninShape::PowerLaw { exponent } => (wavelength_nm / r).powf(exponent),
            EumelaninShape::Exponential { k_per_nm } => (-k_per_nm * (wavelength_nm - r)).exp(),
        }
    }

    /// True for DJ2006's eq. 3 (the default).
    pub fn is_default(&self) -> bool {
        *self == EumelaninShape::Dj2006
    }
}

/// Eumelanin absorption, mm^-1, of the given shape and `K_em`: eq. 3 itself for [`EumelaninShape::Dj2006`], else the
/// shape scaled to eq. 3 at [`EUMELANIN_SHAPE_REFERENCE_NM`].
pub fn sigma_a_eumelanin_shaped_per_mm(wavelength_nm: f64, k_em_per_mm: f64, shape: EumelaninShape) -> f64 {
    match shape {
        EumelaninShape::Dj2006 => sigma_a_eumelanin_per_mm(wavelength_nm, k_em_per_mm),
        _ => sigma_a_eumelanin_per_mm(EUMELANIN_SHAPE_REFERENCE_NM, k_em_per_mm) * shape.relative(wavelength_nm),
    }
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

const WHOLE_BLOOD_CSV: &str = include_str!("../../data/bosschaart2014_whole_blood_absorption.csv");

fn whole_blood_table() -> &'static SpectralTable {
    static TABLE: OnceLock<SpectralTable> = OnceLock::new();
    TABLE.get_or_init(|| SpectralTable::parse(WHOLE_BLOOD_CSV))
}

/// Which absorption spectrum of whole blood the dermis uses: DJ2006's (haemoglobin in solution, Prahl's table at
/// 150 g/L; the default) or measured whole blood. An option of the model for issue 39's study of the Q bands
/// (examples/measured_skin_report/study.rs; docs/model.md, Whole-blood spectrum).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BloodSpectrum {
    /// [`sigma_a_oxy_blood_per_mm`] and [`sigma_a_deoxy_blood_per_mm`]: Prahl's compilation of Gratzer and Kollias's
    /// haemoglobin solution spectra, converted at 150 g/L (DJ2006).
    #[default]
    Dj2006,
    /// Whole blood at haematocrit 45 % (about 150 g/L of haemoglobin, so the blood fraction keeps its meaning), the
    /// average of the published measurements Bosschaart et al. compiled (Lasers Med. Sci. 29:453, 2014;
    /// data/bosschaart2014_whole_blood_absorption.csv): haemoglobin packed in red cells, its strong bands flatter
    /// than in solution (the Soret peak 118 against 280 mm^-1, the Q bands' peak-to-trough ratio 1.42 against 1.70).
    WholeBlood2014,
}

impl BloodSpectrum {
    /// Absorption of fully oxygenated blood, mm^-1.
    pub fn oxy_per_mm(self, wavelength_nm: f64) -> f64 {
        match self {
            BloodSpectrum::Dj2006 => sigma_a_oxy_blood_per_mm(wavelength_nm),
            BloodSpectrum::WholeBlood2014 => whole_blood_table().interpolate(0, wavelength_nm),
        }
    }

    /// Absorption of fully deoxygenated blood, mm^-1.
    pub fn deoxy_per_mm(self, wavelength_nm: f64) -> f64 {
        match self {
            BloodSpectrum::Dj2006 => sigma_a_deoxy_blood_per_mm(wavelength_nm),
            BloodSpectrum::WholeBlood2014 => whole_blood_table().interpolate(1, wavelength_nm),
        }
    }

    /// True for DJ2006's (the default).
    pub fn is_default(&self) -> bool {
        *self == BloodSpectrum::Dj2006
    }
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

    /// The carotene table's peak: 139500 cm^-1/M at 451 nm (Zechmeister & Polgar's value, to which PhotochemCAD's
    /// spectrum is scaled; the table's 1 nm means sit within 1 % of it), and nothing past 540 nm.
    #[test]
    fn carotene_peak_and_end() {
        let per_mm = sigma_a_carotene_per_mm(451.0, 1.0);
        let expected = std::f64::consts::LN_10 * 139_500.0 * 1e-6 / 10.0;
        assert!((per_mm / expected - 1.0).abs() < 0.01, "{per_mm} vs {expected}");
        assert_eq!(sigma_a_carotene_per_mm(600.0, 10.0), 0.0);
        assert_eq!(sigma_a_carotene_per_mm(451.0, 0.0), 0.0);
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

    /// The alternative eumelanin shapes equal eq. 3 at the reference wavelength; Jacques' literal law (1.70e12
    /// λ^-3.48 cm^-1) is the power-law shape at -3.48 within 0.2 % over 400-700 nm.
    #[test]
    fn eumelanin_shapes_meet_eq3_at_the_reference() {
        let w0 = EUMELANIN_SHAPE_REFERENCE_NM;
        let eq3 = sigma_a_eumelanin_per_mm(w0, K_EM_PER_MM);
        for shape in [
            EumelaninShape::Dj2006,
            EumelaninShape::PowerLaw { exponent: -3.48 },
            EumelaninShape::Exponential { k_per_nm: 0.01 },
        ] {
            assert!(close(sigma_a_eumelanin_shaped_per_mm(w0, K_EM_PER_MM, shape), eq3, 1e-12), "{shape:?}");
        }
        for w in [400.0, 450.0, 550.0, 650.0, 700.0] {
            let d = EumelaninShape::Dj2006;
            assert_eq!(sigma_a_eumelanin_shaped_per_mm(w, K_EM_PER_MM, d), sigma_a_eumelanin_per_mm(w, K_EM_PER_MM));
            let jacques = 1.70e12 * f64::powf(w, -3.48) / 10.0;
            let shaped = sigma_a_eumelanin_shaped_per_mm(w, K_EM_PER_MM, EumelaninShape::PowerLaw { exponent: -3.48 });
            assert!(close(shaped, jacques, 2e-3), "{w}: {shaped} vs {jacques}");
        }
    }

    /// The whole-blood table as published (Bosschaart et al. 2014's supplementary values at 542, 560 and 576 nm and
    /// the Soret peak), and against Prahl's solution spectrum at 150 g/L: close in the red (deoxygenated within 15 % at
    /// 650 nm), flatter Q bands, a Soret band well under half as strong.
    #[test]
    fn whole_blood_against_solution() {
        let b = BloodSpectrum::WholeBlood2014;
        assert_eq!((b.oxy_per_mm(542.0), b.oxy_per_mm(560.0), b.oxy_per_mm(576.0)), (27.31, 19.12, 27.20));
        assert_eq!((b.oxy_per_mm(416.0), b.deoxy_per_mm(556.0)), (118.04, 26.80));
        let d = BloodSpectrum::Dj2006;
        let w_ratio = |s: BloodSpectrum| s.oxy_per_mm(576.0) / s.oxy_per_mm(560.0);
        assert!(w_ratio(b) < 1.45 && w_ratio(d) > 1.65, "{} {}", w_ratio(b), w_ratio(d));
        assert!(b.oxy_per_mm(414.0) < 0.45 * d.oxy_per_mm(414.0));
        assert!(close(b.deoxy_per_mm(650.0), d.deoxy_per_mm(650.0), 0.15));
        assert_eq!(d.oxy_per_mm(550.0), sigma_a_oxy_blood_per_mm(550.0));
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
