//! CIELAB and the CIEDE2000 colour difference ΔE00.
//!
//! - CIELAB: CIE 15:2004, section 8.2.1 (f(t) = t^(1/3) above (6/29)^3, linear below), relative to a white's XYZ.
//! - CIEDE2000: G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula: implementation notes,
//!   supplementary test data, and mathematical observations", Color Research and Application 30(1), 21-30 (2005),
//!   equations (1)-(22), with k_L = k_C = k_H = 1; the test checks their Table 1.

/// `6/29`, CIE 15:2004, 8.2.1.
const DELTA: f64 = 6.0 / 29.0;

/// A hue difference of exactly 180° falls on the "<= 180" side of Sharma et al.'s eqs. (10) and (14); hue angles
/// from `atan2` land a rounding error either side of it (Table 1, pairs 13-14), so it is compared with this margin,
/// degrees.
const HUE_EPS_DEG: f64 = 1e-9;

/// CIELAB (L*, a*, b*) of `xyz` relative to the white `white_xyz` (same scale).
pub fn lab_from_xyz(xyz: [f64; 3], white_xyz: [f64; 3]) -> [f64; 3] {
    let f = |t: f64| if t > DELTA.powi(3) { t.cbrt() } else { t / (3.0 * DELTA * DELTA) + 4.0 / 29.0 };
    let [fx, fy, fz] = [0, 1, 2].map(|c| f(xyz[c] / white_xyz[c]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// ΔE00 between two CIELAB colours, Sharma et al. (2005) eqs. (1)-(22).
pub fn ciede2000(lab1: [f64; 3], lab2: [f64; 3]) -> f64 {
    let [l1, a1, b1] = lab1;
    let [l2, a2, b2] = lab2;
    // (2)-(7): a' with the chroma-dependent factor G, C' and h' (degrees in [0, 360); 0 where a' = b = 0).
    let c_mean = 0.5 * (a1.hypot(b1) + a2.hypot(b2));
    let c7 = c_mean.powi(7);
    let g = 0.5 * (1.0 - (c7 / (c7 + 25f64.powi(7))).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = (a1p.hypot(b1), a2p.hypot(b2));
    let hue = |a: f64, b: f64| if a == 0.0 && b == 0.0 { 0.0 } else { b.atan2(a).to_degrees().rem_euclid(360.0) };
    let (h1p, h2p) = (hue(a1p, b1), hue(a2p, b2));
    // (8)-(11): the differences.
    let dl = l2 - l1;
    let dc = c2p - c1p;
    let product = c1p * c2p;
    let dh = if product == 0.0 {
        0.0
    } else {
        let d = h2p - h1p;
        if d > 180.0 + HUE_EPS_DEG {
            d - 360.0
        } else if d < -180.0 - HUE_EPS_DEG {
            d + 360.0
        } else {
            d
        }
    };
    let dhh = 2.0 * product.sqrt() * (dh / 2.0).to_radians().sin();
    // (12)-(22): means, weights, rotation.
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
    let cos_deg = |x: f64| x.to_radians().cos();
    let t = 1.0 - 0.17 * cos_deg(hp - 30.0) + 0.24 * cos_deg(2.0 * hp) + 0.32 * cos_deg(3.0 * hp + 6.0)
        - 0.20 * cos_deg(4.0 * hp - 63.0);
    let d_theta = 30.0 * (-((hp - 275.0) / 25.0).powi(2)).exp();
    let cp7 = cp.powi(7);
    let rc = 2.0 * (cp7 / (cp7 + 25f64.powi(7))).sqrt();
    let sl = 1.0 + 0.015 * (lp - 50.0).powi(2) / (20.0 + (lp - 50.0).powi(2)).sqrt();
    let sc = 1.0 + 0.045 * cp;
    let sh = 1.0 + 0.015 * cp * t;
    let rt = -(2.0 * d_theta).to_radians().sin() * rc;
    ((dl / sl).powi(2) + (dc / sc).powi(2) + (dhh / sh).powi(2) + rt * (dc / sc) * (dhh / sh)).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sharma et al. (2005), Table 1: L1, a1, b1, L2, a2, b2, ΔE00 (given to 4 decimals).
    const SHARMA_TABLE_1: [[f64; 7]; 34] = [
        [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
        [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
        [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
        [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
        [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
        [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
        [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
        [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
        [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
        [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
        [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
        [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
        [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
        [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
        [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
        [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
        [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
        [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
        [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
        [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
        [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
        [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
        [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
        [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
    ];

    #[test]
    fn ciede2000_matches_sharmas_table_1() {
        for (i, row) in SHARMA_TABLE_1.iter().enumerate() {
            let (lab1, lab2) = ([row[0], row[1], row[2]], [row[3], row[4], row[5]]);
            for d in [ciede2000(lab1, lab2), ciede2000(lab2, lab1)] {
                assert!((d - row[6]).abs() < 5e-5, "pair {}: {d} vs {}", i + 1, row[6]);
            }
            assert_eq!(ciede2000(lab1, lab1), 0.0);
        }
    }

    /// The white is L* = 100, a* = b* = 0; a grey of half the white's luminance has L* = 116 * 0.5^(1/3) - 16; below
    /// (6/29)^3 the linear branch: Y = 0.008856 / 2 gives L* = 903.3 * Y / 2 (CIE 15:2004's kappa, 24389/27).
    #[test]
    fn lab_of_white_and_greys() {
        let white = [0.950423, 1.0, 1.088610];
        let lab = lab_from_xyz(white, white);
        assert!((lab[0] - 100.0).abs() < 1e-12 && lab[1].abs() < 1e-12 && lab[2].abs() < 1e-12, "{lab:?}");
        let lab = lab_from_xyz(white.map(|v| 0.5 * v), white);
        assert!((lab[0] - (116.0 * 0.5f64.cbrt() - 16.0)).abs() < 1e-12 && lab[1].abs() < 1e-12, "{lab:?}");
        let y = 0.004;
        let lab = lab_from_xyz(white.map(|v| y * v), white);
        assert!((lab[0] - 24389.0 / 27.0 * y).abs() < 1e-9, "{lab:?}");
    }
}
