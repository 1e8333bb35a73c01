//! CIE XYZ to linear RGB working spaces (Blender 5.0's scene-linear spaces), derived from primaries and the white
//! of the illuminant computed from the same tables, so that a perfect white reflector is exactly RGB (1, 1, 1).
//!
//! The D65 spaces (Rec.709, Rec.2020) take the tables' D65 white as their own white. ACEScg has the ACES white
//! (x, y) = (0.32168, 0.33767) (a "D60"), so scene XYZ (integrated under D65) is first chromatically adapted to it
//! with the Bradford transform (Lam 1985; ICC.1 Annex E). Blender 5.0's OCIO config does the same: its ACEScg
//! colour space is `UTILITY - ACES-AP1_to_CIE-XYZ-D65_BFD`, OCIO's AP1 <-> XYZ(D65) with Bradford adaptation.

use serde::{Deserialize, Serialize};

/// A linear RGB working space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum WorkingSpace {
    /// ITU-R BT.709 / sRGB primaries, linear (Blender's default scene-linear space).
    #[default]
    #[serde(rename = "Linear Rec.709")]
    LinearRec709,
    /// ITU-R BT.2020 primaries, linear.
    #[serde(rename = "Linear Rec.2020")]
    LinearRec2020,
    /// ACES AP1 primaries, linear, ACES white (SMPTE ST 2065-1, ACES TB-2014-004); scene XYZ is Bradford-adapted
    /// from D65 to the ACES white, as in Blender's OCIO config.
    #[serde(rename = "ACEScg")]
    AcesCg,
}

/// Every working space, in the order Blender lists them.
pub const ALL_WORKING_SPACES: [WorkingSpace; 3] =
    [WorkingSpace::LinearRec709, WorkingSpace::LinearRec2020, WorkingSpace::AcesCg];

/// The Bradford cone-response matrix M_BFD (Lam 1985; ICC.1:2010 Annex E).
const BRADFORD: [[f64; 3]; 3] = [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]];

/// The ACES white chromaticity (x, y) (SMPTE ST 2065-1; ACES TB-2014-004).
const ACES_WHITE_XY: [f64; 2] = [0.32168, 0.33767];

impl WorkingSpace {
    /// The name Blender's colour management uses.
    pub fn name(self) -> &'static str {
        match self {
            WorkingSpace::LinearRec709 => "Linear Rec.709",
            WorkingSpace::LinearRec2020 => "Linear Rec.2020",
            WorkingSpace::AcesCg => "ACEScg",
        }
    }

    /// Chromaticities (x, y) of the red, green and blue primaries (ITU-R BT.709-6, BT.2020-2, ACES AP1).
    fn primaries_xy(self) -> [[f64; 2]; 3] {
        match self {
            WorkingSpace::LinearRec709 => [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
            WorkingSpace::LinearRec2020 => [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]],
            WorkingSpace::AcesCg => [[0.713, 0.293], [0.165, 0.830], [0.128, 0.044]],
        }
    }

    /// The space's own white (Y = 1), or None where it is the scene's (D65) white.
    fn own_white_xyz(self) -> Option<[f64; 3]> {
        match self {
            WorkingSpace::LinearRec709 | WorkingSpace::LinearRec2020 => None,
            WorkingSpace::AcesCg => Some(xy_to_xyz(ACES_WHITE_XY)),
        }
    }

    /// The full XYZ -> RGB matrix for a scene whose white has tristimulus `white_xyz` (the illuminant, Y = 1):
    /// RGB (1, 1, 1) is `white_xyz` in every space. For the D65 spaces this is the inverse of the normalised
    /// primary matrix built on `white_xyz`; for ACEScg it is the AP1 matrix on the ACES white times the Bradford
    /// adaptation from `white_xyz` to the ACES white.
    pub fn xyz_to_rgb_matrix(self, white_xyz: [f64; 3]) -> [[f64; 3]; 3] {
        match self.own_white_xyz() {
            None => invert(self.rgb_to_xyz_on_white(white_xyz)),
            Some(own) => mat_mul(invert(self.rgb_to_xyz_on_white(own)), bradford_adaptation(white_xyz, own)),
        }
    }

    /// The RGB -> XYZ matrix for a scene whose white is `white_xyz`: the inverse of
    /// [`WorkingSpace::xyz_to_rgb_matrix`].
    pub fn rgb_to_xyz_matrix(self, white_xyz: [f64; 3]) -> [[f64; 3]; 3] {
        invert(self.xyz_to_rgb_matrix(white_xyz))
    }

    /// The luminance of linear RGB in this space for a scene whose white is `white_xyz`: Y = l . rgb with Y relative
    /// to the white's (so l sums to 1): the middle row of the RGB -> XYZ matrix (the inverse of
    /// [`WorkingSpace::xyz_to_rgb_matrix`]) divided by the white's Y.
    pub fn luminance_weights(self, white_xyz: [f64; 3]) -> [f64; 3] {
        invert(self.xyz_to_rgb_matrix(white_xyz))[1].map(|v| v / white_xyz[1])
    }

    /// The normalised primary matrix (RGB -> XYZ) whose white (1, 1, 1) is `white_xyz` (SMPTE RP 177).
    fn rgb_to_xyz_on_white(self, white_xyz: [f64; 3]) -> [[f64; 3]; 3] {
        // Columns of P are the primaries' XYZ at Y = 1; scale them so that P S (1,1,1) = white.
        let p = transpose(self.primaries_xy().map(|[x, y]| [x / y, 1.0, (1.0 - x - y) / y]));
        let s = mat_vec(invert(p), white_xyz);
        [0, 1, 2].map(|i| [0, 1, 2].map(|j| p[i][j] * s[j]))
    }
}

/// XYZ at Y = 1 of chromaticity (x, y).
fn xy_to_xyz([x, y]: [f64; 2]) -> [f64; 3] {
    [x / y, 1.0, (1.0 - x - y) / y]
}

/// The Bradford chromatic adaptation matrix taking XYZ seen under white `src` to XYZ under white `dst`
/// (von Kries scaling in the Bradford cone space; the linear form used by ICC and OCIO).
pub fn bradford_adaptation(src: [f64; 3], dst: [f64; 3]) -> [[f64; 3]; 3] {
    let (cs, cd) = (mat_vec(BRADFORD, src), mat_vec(BRADFORD, dst));
    let scale = [0, 1, 2].map(|i| [0, 1, 2].map(|j| if i == j { cd[i] / cs[i] } else { 0.0 }));
    mat_mul(invert(BRADFORD), mat_mul(scale, BRADFORD))
}

fn mat_mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| m[j][i]))
}

/// `m v`.
pub fn mat_vec(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

fn invert(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |i: usize, j: usize| {
        let (a, b) = ((i + 1) % 3, (i + 2) % 3);
        let (x, y) = ((j + 1) % 3, (j + 2) % 3);
        m[a][x] * m[b][y] - m[a][y] * m[b][x]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| c(j, i) / det))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lindbloom's published XYZ -> sRGB matrix, made with the D65 white XYZ (0.95047, 1, 1.08883) (docs/model.md,
    /// Colour).
    #[test]
    fn rec709_matches_published_matrix() {
        let m = WorkingSpace::LinearRec709.xyz_to_rgb_matrix([0.95047, 1.0, 1.08883]);
        let published = [
            [3.2404542, -1.5371385, -0.4985314],
            [-0.9692660, 1.8760108, 0.0415560],
            [0.0556434, -0.2040259, 1.0572252],
        ];
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - published[i][j]).abs() < 2e-6, "{i}{j}: {} vs {}", m[i][j], published[i][j]);
            }
        }
    }

    /// Rec.709 on the D65 white (0.95047, 1, 1.08883): the middle row of Lindbloom's sRGB-to-XYZ matrix
    /// (0.2126729, 0.7151522, 0.0721750); every space's weights sum to 1.
    #[test]
    fn luminance_weights_match_published_row() {
        let l = WorkingSpace::LinearRec709.luminance_weights([0.95047, 1.0, 1.08883]);
        let published = [0.2126729, 0.7151522, 0.0721750];
        assert!((0..3).all(|c| (l[c] - published[c]).abs() < 1e-6), "{l:?}");
        for ws in ALL_WORKING_SPACES {
            let l = ws.luminance_weights(table_white());
            assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{ws:?} {l:?}");
        }
    }

    #[test]
    fn white_maps_to_one() {
        for white in [[0.95047, 1.0, 1.08883], table_white()] {
            for ws in ALL_WORKING_SPACES {
                let rgb = mat_vec(ws.xyz_to_rgb_matrix(white), white);
                assert!(rgb.iter().all(|v| (v - 1.0).abs() < 1e-12), "{ws:?} {rgb:?}");
            }
        }
    }

    /// The D65 white from the tables (1 nm grid), as `spectral_rgb_weights` computes it.
    fn table_white() -> [f64; 3] {
        let w = crate::color::WavelengthGrid::uniform(1.0).xyz_weights();
        crate::color::spectrum_to_xyz(&vec![1.0; w.len()], &w)
    }

    fn assert_close(m: [[f64; 3]; 3], expected: [[f64; 3]; 3], tol: f64) {
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - expected[i][j]).abs() < tol, "{i}{j}: {m:?} vs {expected:?}");
            }
        }
    }

    /// Rec.709 -> ACEScg (Bradford, D65 -> ACES white) as published (e.g. OCIO / colour-science), implied by
    /// ACEScg_from_XYZ * XYZ_from_Rec709 on the tables' D65 white.
    #[test]
    fn rec709_to_acescg_matches_published_bradford_matrix() {
        let published = [[0.6131, 0.3395, 0.0474], [0.0702, 0.9164, 0.0135], [0.0206, 0.1096, 0.8698]];
        for white in [table_white(), xy_to_xyz([0.3127, 0.3290])] {
            let xyz_from_709 = invert(WorkingSpace::LinearRec709.xyz_to_rgb_matrix(white));
            let m = mat_mul(WorkingSpace::AcesCg.xyz_to_rgb_matrix(white), xyz_from_709);
            assert_close(m, published, 2e-3);
        }
        // With the ITU D65 white it is the published matrix to its 4 decimals.
        let white = xy_to_xyz([0.3127, 0.3290]);
        let m = mat_mul(
            WorkingSpace::AcesCg.xyz_to_rgb_matrix(white),
            invert(WorkingSpace::LinearRec709.xyz_to_rgb_matrix(white)),
        );
        assert_close(m, published, 1e-4);
    }

    /// AP1 on the ACES white, unadapted: the ACEScg NPM of TB-2014-004 / S-2014-004.
    #[test]
    fn acescg_npm_matches_published() {
        let npm = WorkingSpace::AcesCg.rgb_to_xyz_on_white(xy_to_xyz(ACES_WHITE_XY));
        let published = [
            [0.6624541811, 0.1340042065, 0.1561876870],
            [0.2722287168, 0.6740817658, 0.0536895174],
            [-0.0055746495, 0.0040607335, 1.0103391003],
        ];
        assert_close(npm, published, 1e-9);
    }

    #[test]
    fn bradford_maps_white_to_white() {
        let (src, dst) = (table_white(), xy_to_xyz(ACES_WHITE_XY));
        let out = mat_vec(bradford_adaptation(src, dst), src);
        assert!((0..3).all(|i| (out[i] - dst[i]).abs() < 1e-12), "{out:?}");
    }

    #[test]
    fn names_are_serde_names() {
        for ws in ALL_WORKING_SPACES {
            assert_eq!(serde_json::to_string(&ws).unwrap(), format!("\"{}\"", ws.name()));
        }
    }
}
