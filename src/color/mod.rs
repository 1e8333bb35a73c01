//! Colour: spectra to CIE XYZ (1931 2-degree observer, D65) to a linear RGB working space.

pub mod cmf;
pub mod difference;
pub mod gamut;
pub mod ita;
pub mod rgb;
pub mod spectrum;

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

pub use difference::{ciede2000, lab_from_xyz};
pub use gamut::{RgbMapping, ALL_RGB_MAPPINGS};
pub use rgb::{WorkingSpace, ALL_WORKING_SPACES};
pub use spectrum::{spectrum_to_xyz, WavelengthGrid, WavelengthPlacement, ALL_WAVELENGTH_PLACEMENTS};

/// A request's colour integration: its wavelength grid, the weights turning a spectrum on it into linear RGB
/// ([`placement_rgb_weights`]) and the RGB's luminance weights ([`rgb_luminance_weights`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ColourIntegration {
    pub grid: WavelengthGrid,
    pub rgb_weights: Vec<[f64; 3]>,
    pub luminance: [f64; 3],
}

/// Distinct colour integrations kept per process before the cache is cleared (a process uses a handful).
const COLOUR_CACHE_ENTRIES: usize = 64;

impl ColourIntegration {
    /// The integration of `placement` at `step_nm` in `space`, built once per process: building it integrates the
    /// 1 nm colour tables (about 80 µs, most of an albedo's evaluation before it was kept; docs/performance.md).
    pub fn of(placement: WavelengthPlacement, step_nm: f64, space: WorkingSpace) -> Arc<ColourIntegration> {
        type Key = (WavelengthPlacement, u64, WorkingSpace);
        static CACHE: OnceLock<Mutex<HashMap<Key, Arc<ColourIntegration>>>> = OnceLock::new();
        let key = (placement, step_nm.to_bits(), space);
        let cache = CACHE.get_or_init(Default::default);
        if let Some(hit) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return Arc::clone(hit);
        }
        let grid = WavelengthGrid::new(placement, step_nm);
        let fresh = Arc::new(ColourIntegration {
            rgb_weights: placement_rgb_weights(&grid, placement, space),
            luminance: rgb_luminance_weights(&grid, space),
            grid,
        });
        let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= COLOUR_CACHE_ENTRIES {
            cache.clear();
        }
        cache.insert(key, Arc::clone(&fresh));
        fresh
    }
}

/// Weights turning a spectrum sampled on `grid` into linear RGB in `space`: rgb[c] = sum_k w[k][c] R(lambda_k).
pub fn spectral_rgb_weights(grid: &WavelengthGrid, space: WorkingSpace) -> Vec<[f64; 3]> {
    let xyz_w = grid.xyz_weights();
    let m = space.xyz_to_rgb_matrix(grid_white(&xyz_w));
    xyz_w.iter().map(|w| rgb::mat_vec(m, *w)).collect()
}

/// The luminance of linear RGB in `space` made by [`spectral_rgb_weights`] on `grid`: Y = l . rgb, relative to the
/// white (l sums to 1), for [`RgbMapping::apply`].
pub fn rgb_luminance_weights(grid: &WavelengthGrid, space: WorkingSpace) -> [f64; 3] {
    space.luminance_weights(grid_white(&grid.xyz_weights()))
}

/// XYZ of the perfect white reflector under the grid's weights (the illuminant's white).
fn grid_white(xyz_weights: &[[f64; 3]]) -> [f64; 3] {
    spectrum_to_xyz(&vec![1.0; xyz_weights.len()], xyz_weights)
}

/// Weights for a grid made by `placement`: the colour integration of [`spectral_rgb_weights`], except for the RGB
/// shortcut, whose three samples (435.8, 546.1, 700 nm) are taken as B, G and R as they are, in any working space.
pub fn placement_rgb_weights(
    grid: &WavelengthGrid,
    placement: WavelengthPlacement,
    space: WorkingSpace,
) -> Vec<[f64; 3]> {
    match placement {
        WavelengthPlacement::RgbShortcut => vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        _ => spectral_rgb_weights(grid, space),
    }
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
        for placement in [WavelengthPlacement::CmfAdapted, WavelengthPlacement::RgbShortcut] {
            let g = WavelengthGrid::new(placement, 10.0);
            let rgb = spectrum_to_rgb(
                &vec![1.0; g.wavelengths_nm.len()],
                &placement_rgb_weights(&g, placement, WorkingSpace::LinearRec709),
            );
            assert!(rgb.iter().all(|v| (v - 1.0).abs() < 1e-12), "{placement:?} {rgb:?}");
        }
    }

    /// The CMF-adapted grid has the uniform grid's count, spans 380-780 nm, increases, and is densest where the
    /// colour-matching functions are large (the 500-600 nm gap is smaller than the 700-780 nm one).
    #[test]
    fn cmf_adapted_grid() {
        let g = WavelengthGrid::new(WavelengthPlacement::CmfAdapted, 20.0);
        let w = &g.wavelengths_nm;
        assert_eq!(w.len(), WavelengthGrid::uniform(20.0).wavelengths_nm.len());
        assert!((w[0] - 380.0).abs() < 1e-9 && (w[w.len() - 1] - 780.0).abs() < 1e-9, "{w:?}");
        assert!(w.windows(2).all(|p| p[1] > p[0]), "{w:?}");
        let gap_at = |x: f64| w.windows(2).find(|p| p[0] <= x && x < p[1]).map(|p| p[1] - p[0]).unwrap();
        assert!(gap_at(550.0) < 0.7 * gap_at(740.0), "{} vs {}", gap_at(550.0), gap_at(740.0));
    }
}
