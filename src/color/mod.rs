//! Colour: spectra to CIE XYZ (1931 2-degree observer, D65) to a linear RGB working space.

pub mod cmf;
pub mod rgb;
pub mod spectrum;

pub use rgb::{WorkingSpace, ALL_WORKING_SPACES};
pub use spectrum::{spectrum_to_xyz, WavelengthGrid};

/// Weights turning a spectrum sampled on `grid` into linear RGB in `space`: rgb[c] = sum_k w[k][c] R(lambda_k).
pub fn spectral_rgb_weights(grid: &WavelengthGrid, space: WorkingSpace) -> Vec<[f64; 3]> {
    let xyz_w = grid.xyz_weights();
    let white = spectrum_to_xyz(&vec![1.0; xyz_w.len()], &xyz_w);
    let m = space.xyz_to_rgb_matrix(white);
    xyz_w.iter().map(|w| rgb::mat_vec(m, *w)).collect()
}

/// Linear RGB of a spectrum with weights from [`spectral_rgb_weights`].
pub fn spectrum_to_rgb(values: &[f64], weights: &[[f64; 3]]) -> [f64; 3] {
    spectrum_to_xyz(values, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A perfect white reflector is exactly (1, 1, 1) in every working space and on every grid.
    #[test]
    fn white_reflector_is_one() {
        for step in [1.0, 2.0, 5.0, 10.0, 20.0] {
            let g = WavelengthGrid::uniform(step);
            for ws in ALL_WORKING_SPACES {
                let rgb = spectrum_to_rgb(&vec![1.0; g.wavelengths_nm.len()], &spectral_rgb_weights(&g, ws));
                assert!(rgb.iter().all(|v| (v - 1.0).abs() < 1e-12), "{step} {ws:?} {rgb:?}");
            }
        }
    }
}
