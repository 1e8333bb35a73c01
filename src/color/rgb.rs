//! CIE XYZ to linear RGB working spaces (Blender 5.0's scene-linear spaces), derived from primaries and the white
//! of the illuminant computed from the same tables, so that a perfect white reflector is exactly RGB (1, 1, 1).

use serde::{Deserialize, Serialize};

/// A linear RGB working space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum WorkingSpace {
    /// ITU-R BT.709 / sRGB primaries, linear (Blender's default scene-linear space).
    #[default]
    #[serde(rename = "Linear Rec.709")]
    LinearRec709,
    /// ITU-R BT.2020 primaries, linear.
    #[serde(rename = "Linear Rec.2020")]
    LinearRec2020,
}

impl WorkingSpace {
    /// The name Blender's colour management uses.
    pub fn name(self) -> &'static str {
        match self {
            WorkingSpace::LinearRec709 => "Linear Rec.709",
            WorkingSpace::LinearRec2020 => "Linear Rec.2020",
        }
    }

    /// Chromaticities (x, y) of the red, green and blue primaries (ITU-R BT.709-6 and BT.2020-2).
    fn primaries_xy(self) -> [[f64; 2]; 3] {
        match self {
            WorkingSpace::LinearRec709 => [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]],
            WorkingSpace::LinearRec2020 => [[0.708, 0.292], [0.170, 0.797], [0.131, 0.046]],
        }
    }

    /// The XYZ -> RGB matrix for a scene whose white has tristimulus `white_xyz` (the illuminant, Y = 1).
    pub fn xyz_to_rgb_matrix(self, white_xyz: [f64; 3]) -> [[f64; 3]; 3] {
        // Columns of P are the primaries' XYZ at Y = 1; scale them so that P S (1,1,1) = white (SMPTE RP 177).
        let p = self.primaries_xy().map(|[x, y]| [x / y, 1.0, (1.0 - x - y) / y]);
        let p = transpose(p);
        let s = mat_vec(invert(p), white_xyz);
        let npm = [0, 1, 2].map(|i| [0, 1, 2].map(|j| p[i][j] * s[j]));
        invert(npm)
    }
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

    /// The XYZ -> sRGB matrix of model.md section 7 (Lindbloom's, made with the D65 white XYZ (0.95047, 1, 1.08883)).
    #[test]
    fn rec709_matches_published_matrix() {
        let m = WorkingSpace::LinearRec709.xyz_to_rgb_matrix([0.95047, 1.0, 1.08883]);
        let published = [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]];
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - published[i][j]).abs() < 2e-6, "{i}{j}: {} vs {}", m[i][j], published[i][j]);
            }
        }
    }

    #[test]
    fn white_maps_to_one() {
        let white = [0.95047, 1.0, 1.08883];
        for ws in [WorkingSpace::LinearRec709, WorkingSpace::LinearRec2020] {
            let rgb = mat_vec(ws.xyz_to_rgb_matrix(white), white);
            assert!(rgb.iter().all(|v| (v - 1.0).abs() < 1e-12), "{rgb:?}");
        }
    }
}
