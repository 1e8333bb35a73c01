//! CIELAB and the CIEDE2000 colour difference ΔE00, for the inverse fits (src/inverse) that compare a model albedo
//! with a target colour.
//!
//! - CIELAB: CIE 15:2004, section 8.2.1 (f(t) = t^(1/3) above (6/29)^3, linear below, so that negative XYZ of an
//!   out-of-gamut linear RGB colour still gives a finite L*a*b*).
//! - CIEDE2000: G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula: implementation notes,
//!   supplementary test data, and mathematical observations", Color Research and Application 30(1), 21-30 (2005),
//!   equations (1)-(22), k_L = k_C = k_H = 1. The same formula as scripts/lib/color_difference.py (the Python
//!   reports').

use super::rgb::{mat_vec, WorkingSpace};
use super::WavelengthGrid;

/// 6/29 (CIE 15:2004, 8.2.1).
const DELTA: f64 = 6.0 / 29.0;
/// Rounding of hue angles (degrees) at the 180° branch of Sharma et al.'s eqs. (10) and (14) (Table 1, pairs 13-14).
const HUE_EPS_DEG: f64 = 1e-9;

/// CIELAB of XYZ relative to the white `white_xyz` (CIE 15:2004, 8.2.1).
pub fn lab_from_xyz(xyz: [f64; 3], white_xyz: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| if t > DELTA.powi(3) { t.cbrt() } else { t / (3.0 * DELTA * DELTA) + 4.0 / 29.0 };
    let [fx, fy, fz] = [0, 1, 2].map(|i| f(xyz[i] / white_xyz[i]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Linear RGB of a working space (RGB (1, 1, 1) the D65 white of the CIE tables, as the core's albedo) to CIELAB
/// relative to that white.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LabConverter {
    rgb_to_xyz: [[f64; 3]; 3],
    white_xyz: [f64; 3],
}

impl LabConverter {
    pub fn new(space: WorkingSpace) -> LabConverter {
        let w = WavelengthGrid::uniform(1.0).xyz_weights();
        let white_xyz = super::spectrum_to_xyz(&vec![1.0; w.len()], &w);
        LabConverter { rgb_to_xyz: space.rgb_to_xyz_matrix(white_xyz), white_xyz }
    }

    pub fn lab(&self, rgb: [f64; 3]) -> [f64; 3] {
        lab_from_xyz(mat_vec(self.rgb_to_xyz, rgb), self.white_xyz)
    }

    /// The luminance Y of linear RGB relative to the white's (RGB (1, 1, 1) gives 1).
    pub fn luminance(&self, rgb: [f64; 3]) -> f64 {
        mat_vec(self.rgb_to_xyz, rgb)[1] / self.white_xyz[1]
    }
}

/// ΔE00 between two CIELAB colours (symmetric).
pub fn ciede2000(lab1: [f64; 3], lab2: [f64; 3]) -> f64 {
    let r = ciede2000_terms(lab1, lab2);
    (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
}

/// ΔE00 written as the length of a vector, for least squares: with x = ΔC'/S_C, y = ΔH'/S_H and the rotation R_T,
/// x² + y² + R_T x y = (x + R_T y / 2)² + (1 - R_T² / 4) y² (|R_T| <= 2), so ΔE00² = |(ΔL'/S_L, x + R_T y / 2,
/// sqrt(1 - R_T²/4) y)|². Differences are lab2 - lab1.
pub fn ciede2000_terms(lab1: [f64; 3], lab2: [f64; 3]) -> [f64; 3] {
    let [l1, a1, b1] = lab1;
    let [l2, a2, b2] = lab2;
    // (2)-(7)
    let c_mean = 0.5 * (a1.hypot(b1) + a2.hypot(b2));
    let c7 = c_mean.powi(7);
    let g = 0.5 * (1.0 - (c7 / (c7 + 25f64.powi(7))).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = (a1p.hypot(b1), a2p.hypot(b2));
    let hue = |a: f64, b: f64| if a == 0.0 && b == 0.0 { 0.0 } else { b.atan2(a).to_degrees().rem_euclid(360.0) };
    let (h1p, h2p) = (hue(a1p, b1), hue(a2p, b2));
    // (8)-(11)
    let dl = l2 - l1;
    let dc = c2p - c1p;
    let product = c1p * c2p;
    let mut dh = h2p - h1p;
    if product == 0.0 {
        dh = 0.0;
    } else if dh > 180.0 + HUE_EPS_DEG {
        dh -= 360.0;
    } else if dh < -180.0 - HUE_EPS_DEG {
        dh += 360.0;
    }
    let dhh = 2.0 * product.sqrt() * (dh / 2.0).to_radians().sin();
    // (12)-(22)
    let lp = 0.5 * (l1 + l2);
    let cp = 0.5 * (c1p + c2p);
    let hsum = h1p + h2p;
    let hp = if product == 0.0 {
        hsum
    } else if (h1p - h2p).abs() <= 180.0 + HUE_EPS_DEG {
        hsum / 2.0
    } else if hsum < 360.0 {
        (hsum + 360.0) / 2.0
    } else {
        (hsum - 360.0) / 2.0
    };
    let cos = |deg: f64| deg.to_radians().cos();
    let t =
        1.0 - 0.17 * cos(hp - 30.0) + 0.24 * cos(2.0 * hp) + 0.32 * cos(3.0 * hp + 6.0) - 0.20 * cos(4.0 * hp - 63.0);
    let d_theta = 30.0 * (-((hp - 275.0) / 25.0).powi(2)).exp();
    let cp7 = cp.powi(7);
    let rc = 2.0 * (cp7 / (cp7 + 25f64.powi(7))).sqrt();
    let sl = 1.0 + 0.015 * (lp - 50.0).powi(2) / (20.0 + (lp - 50.0).powi(2)).sqrt();
    let sc = 1.0 + 0.045 * cp;
    let sh = 1.0 + 0.015 * cp * t;
    let rt = -(2.0 * d_theta).to_radians().sin() * rc;
    let (x, y) = (dc / sc, dhh / sh);
    [dl / sl, x + 0.5 * rt * y, (1.0 - 0.25 * rt * rt).max(0.0).sqrt() * y]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sharma et al. (2005), Table 1 (data/sharma2005_ciede2000_pairs.csv): L1, a1, b1, L2, a2, b2, ΔE00 (to 4
    /// decimals).
    fn sharma_table_1() -> Vec<[f64; 7]> {
        include_str!("../../data/sharma2005_ciede2000_pairs.csv")
            .lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with('L'))
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2], v[3], v[4], v[5], v[6]]
            })
            .collect()
    }

    #[test]
    fn ciede2000_matches_sharmas_table_1() {
        let table = sharma_table_1();
        assert_eq!(table.len(), 34);
        for row in table {
            let (a, b) = ([row[0], row[1], row[2]], [row[3], row[4], row[5]]);
            for d in [ciede2000(a, b), ciede2000(b, a)] {
                assert!((d - row[6]).abs() < 5e-5, "{row:?}: {d}");
            }
            assert_eq!(ciede2000(a, a), 0.0, "{row:?}");
        }
    }

    /// White is L* = 100, a* = b* = 0; the sRGB red primary is (53.24, 80.09, 67.20) (B. Lindbloom's RGB/XYZ and
    /// XYZ/Lab equations); a negative colour still has a finite Lab.
    #[test]
    fn lab_of_white_red_and_an_out_of_gamut_colour() {
        let c = LabConverter::new(WorkingSpace::LinearRec709);
        let w = c.lab([1.0; 3]);
        assert!((w[0] - 100.0).abs() < 1e-9 && w[1].abs() < 1e-9 && w[2].abs() < 1e-9, "{w:?}");
        let r = c.lab([1.0, 0.0, 0.0]);
        assert!((r[0] - 53.24).abs() < 0.05 && (r[1] - 80.09).abs() < 0.1 && (r[2] - 67.20).abs() < 0.1, "{r:?}");
        assert!(c.lab([-0.2, 0.5, -0.1]).iter().all(|v| v.is_finite()), "{:?}", c.lab([-0.2, 0.5, -0.1]));
    }
}
