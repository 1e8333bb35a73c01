//! Wavelength grids and the weights that turn a sampled reflectance spectrum into CIE XYZ under D65.

use serde::{Deserialize, Serialize};

use super::cmf::{cie1931_2deg, illuminant_d65};

/// The visible range integrated for colour, nm (as the reference colours of docs/model.md, Reference numbers).
pub const VISIBLE_RANGE_NM: (f64, f64) = (380.0, 780.0);

/// Where the spectral computation places its wavelengths (the number is set by the step, see [`WavelengthGrid::new`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum WavelengthPlacement {
    /// Every `step` nm from 380 to 780 nm.
    #[default]
    Uniform,
    /// As many wavelengths as the uniform step gives, placed where the colour-matching functions weigh most: equal
    /// steps of the cumulative sqrt((xbar + ybar + zbar) D65), the density that minimises the weighted error of linear
    /// interpolation for a spectrum of uniform curvature.
    CmfAdapted,
    /// The three-wavelength shortcut DJ06 argues against: R, G and B are the reflectance at the CIE 1931 RGB primaries,
    /// 700, 546.1 and 435.8 nm, with no colour integration.
    RgbShortcut,
}

/// Every placement, in the order the docs list them.
pub const ALL_WAVELENGTH_PLACEMENTS: [WavelengthPlacement; 3] =
    [WavelengthPlacement::Uniform, WavelengthPlacement::CmfAdapted, WavelengthPlacement::RgbShortcut];

/// The CIE 1931 RGB primaries, nm (CIE 1931; Wyszecki & Stiles, Color Science, 2nd ed., table 3.3.3): B, G, R.
pub const CIE_RGB_PRIMARIES_NM: [f64; 3] = [435.8, 546.1, 700.0];

/// Wavelength sampling of the spectral computation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WavelengthGrid {
    pub wavelengths_nm: Vec<f64>,
}

impl WavelengthGrid {
    /// The grid of a placement: uniform or CMF-adapted with the uniform step's count, or the three RGB primaries.
    pub fn new(placement: WavelengthPlacement, step_nm: f64) -> WavelengthGrid {
        match placement {
            WavelengthPlacement::Uniform => WavelengthGrid::uniform(step_nm),
            WavelengthPlacement::CmfAdapted => {
                WavelengthGrid::cmf_adapted(WavelengthGrid::uniform(step_nm).wavelengths_nm.len())
            }
            WavelengthPlacement::RgbShortcut => WavelengthGrid { wavelengths_nm: CIE_RGB_PRIMARIES_NM.to_vec() },
        }
    }

    /// `count` (>= 2) wavelengths from 380 to 780 nm at equal steps of the cumulative sqrt((xbar + ybar + zbar) D65),
    /// with a floor of 1 % of its peak so that no gap grows without bound where the tables are near zero.
    pub fn cmf_adapted(count: usize) -> WavelengthGrid {
        let count = count.max(2);
        let (cmf, d65) = (cie1931_2deg(), illuminant_d65());
        let (lo, hi) = VISIBLE_RANGE_NM;
        let nm: Vec<f64> = (0..=(hi - lo) as usize).map(|i| lo + i as f64).collect();
        let raw: Vec<f64> = nm
            .iter()
            .map(|&l| (d65.interpolate(0, l) * (0..3).map(|c| cmf.interpolate(c, l)).sum::<f64>()).sqrt())
            .collect();
        let floor = 0.01 * raw.iter().cloned().fold(0.0, f64::max);
        let density: Vec<f64> = raw.iter().map(|v| v.max(floor)).collect();
        // Cumulative density (trapezoid, 1 nm), then its inverse at equal steps.
        let mut cumulative = vec![0.0; nm.len()];
        for i in 1..nm.len() {
            cumulative[i] = cumulative[i - 1] + 0.5 * (density[i] + density[i - 1]);
        }
        let total = cumulative[nm.len() - 1];
        let wavelengths_nm = (0..count)
            .map(|k| {
                let target = total * k as f64 / (count - 1) as f64;
                let (i, t) = bracket(&cumulative, target);
                if t == 0.0 {
                    nm[i]
                } else {
                    nm[i] + t * (nm[i + 1] - nm[i])
                }
            })
            .collect();
        WavelengthGrid { wavelengths_nm }
    }

    /// Uniform samples every `step_nm` from 380 nm to (at least) 780 nm.
    pub fn uniform(step_nm: f64) -> WavelengthGrid {
        let (lo, hi) = VISIBLE_RANGE_NM;
        let n = ((hi - lo) / step_nm - 1e-9).ceil() as usize;
        WavelengthGrid { wavelengths_nm: (0..=n).map(|i| lo + i as f64 * step_nm).collect() }
    }

    /// Weights `w[k][c]` with X, Y, Z (c = 0, 1, 2) = sum_k w[k][c] R(lambda_k): the reflectance is interpolated
    /// linearly between samples and integrated against the 1 nm CMF x D65 tables over 380-780 nm, normalised so that
    /// R = 1 gives Y = 1. Linear interpolation makes any grid, even a coarse one, integrate the tables exactly.
    pub fn xyz_weights(&self) -> Vec<[f64; 3]> {
        let cmf = cie1931_2deg();
        let d65 = illuminant_d65();
        let w = &self.wavelengths_nm;
        let mut weights = vec![[0.0; 3]; w.len()];
        let mut norm = 0.0;
        let (lo, hi) = VISIBLE_RANGE_NM;
        let mut lambda = lo;
        while lambda <= hi + 1e-9 {
            let e = d65.interpolate(0, lambda);
            let bars = [cmf.interpolate(0, lambda), cmf.interpolate(1, lambda), cmf.interpolate(2, lambda)];
            norm += e * bars[1];
            // Hat-function share of the two samples around lambda.
            let (k, t) = bracket(w, lambda);
            for c in 0..3 {
                weights[k][c] += (1.0 - t) * e * bars[c];
                if t > 0.0 {
                    weights[k + 1][c] += t * e * bars[c];
                }
            }
            lambda += 1.0;
        }
        for row in &mut weights {
            for v in row.iter_mut() {
                *v /= norm;
            }
        }
        weights
    }
}

/// Index k and fraction t with x = (1-t) w[k] + t w[k+1], clamped to the grid.
fn bracket(w: &[f64], x: f64) -> (usize, f64) {
    if w.len() == 1 || x <= w[0] {
        return (0, 0.0);
    }
    if x >= w[w.len() - 1] {
        return (w.len() - 1, 0.0);
    }
    let k = w.partition_point(|&v| v <= x) - 1;
    (k, (x - w[k]) / (w[k + 1] - w[k]))
}

/// CIE XYZ of a spectrum sampled on the grid the weights were made for.
pub fn spectrum_to_xyz(reflectance: &[f64], weights: &[[f64; 3]]) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for (r, w) in reflectance.iter().zip(weights) {
        for c in 0..3 {
            xyz[c] += r * w[c];
        }
    }
    xyz
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_covers_visible_range() {
        let g = WavelengthGrid::uniform(5.0);
        assert_eq!(g.wavelengths_nm.len(), 81);
        assert_eq!(*g.wavelengths_nm.last().unwrap(), 780.0);
        let g = WavelengthGrid::uniform(30.0);
        assert!(*g.wavelengths_nm.last().unwrap() >= 780.0, "{:?}", g.wavelengths_nm.last());
    }

    /// White of D65 over 380-780 nm with these tables, summed at 1 nm by a separate script: XYZ = (0.950423, 1,
    /// 1.088610). (Over the tables' full 360-830 nm they give (0.95047, 1, 1.08883); docs/model.md, Colour.)
    #[test]
    fn white_point() {
        for step in [1.0, 5.0, 20.0] {
            let g = WavelengthGrid::uniform(step);
            let xyz = spectrum_to_xyz(&vec![1.0; g.wavelengths_nm.len()], &g.xyz_weights());
            let ok =
                (xyz[0] - 0.950423).abs() < 1e-6 && (xyz[1] - 1.0).abs() < 1e-12 && (xyz[2] - 1.088610).abs() < 1e-6;
            assert!(ok, "step {step}: {xyz:?}");
        }
    }
}
