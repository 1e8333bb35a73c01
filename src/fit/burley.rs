//! Christensen-Burley profile length fitted to a model profile, as Cycles' BURLEY method uses it (docs/model.md,
//! Burley fit).
//!
//! Cycles renders R(r) = A (e^(-r/d) + e^(-r/3d)) / (8 pi d r) with d = Radius * Scale / (4 pi), and the total A =
//! Base Color exactly. The fit chooses d so that the edge response (light on a half-plane, as in the renders of
//! docs/blender-principled.md, Edge and spot renders) of the Burley profile is as close as possible, in L2 over the
//! line, to the model's edge response. By the projection-slice theorem the 1-D Fourier transform of the line-spread
//! function is the 2-D transform R~(s), and by Parseval
//! || E_model - E_burley ||^2 = (1/pi) int_0^inf (N(s) - B~(s d))^2 / s^2 ds with N = R~ / R~(0): the fit needs only
//! the Hankel-domain reflectance, never a radial profile.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

use serde::{Deserialize, Serialize};

use crate::numeric::{clamp_nan_to_low, newton_min};

/// Hankel transform of the normalised Burley profile: B~(s; d) = (1/4) [1/sqrt(1+(s d)^2) + 3/sqrt(1+(3 s d)^2)]
/// (from FT{e^(-r/a)/r} = 2 pi / sqrt(s^2 + 1/a^2)). The 16 d truncation of Cycles (0.4 % of the energy) is ignored.
pub fn burley_transform(s_per_mm: f64, d_mm: f64) -> f64 {
    let x = s_per_mm * d_mm;
    0.25 * (1.0 / (1.0 + x * x).sqrt() + 3.0 / (1.0 + 9.0 * x * x).sqrt())
}

/// Frequencies (mm^-1) on which transfer functions are compared: log-spaced, 1e-3 to 1e5 mm^-1 (Burley lengths d
/// from ~0.005 mm to ~5 mm have their transfer edge, s d ~ 0.03..30, well inside).
pub fn fit_frequencies(per_decade: f64) -> Vec<f64> {
    const DECADES: (f64, f64) = (-3.0, 5.0);
    let n = ((DECADES.1 - DECADES.0) * per_decade).round() as usize;
    (0..=n).map(|i| 10f64.powf(DECADES.0 + (DECADES.1 - DECADES.0) * i as f64 / n as f64)).collect()
}

/// A fitted Burley profile length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BurleyFit {
    /// Burley's d, mm.
    pub d_mm: f64,
    /// The Principled Subsurface Radius x Scale that gives this d in Cycles: 4 pi d, mm.
    pub radius_mm: f64,
    /// || E_model - E_burley || / || E_model - step ||: the edge misfit relative to the edge's own blur (0 = perfect).
    pub edge_residual: f64,
}

/// `int (f(s))^2 / s^2 ds` on a log-spaced grid (trapezoid in ln s, so the integrand is f^2 / s), as one weight per
/// frequency: `sum_i weight_i f(s_i)^2`, each node taking half the log-widths on either side over its s.
fn squared_norm_weights(s: &[f64]) -> Vec<f64> {
    let log_width = |i: usize| if i == 0 || i >= s.len() { 0.0 } else { (s[i] / s[i - 1]).ln() };
    (0..s.len()).map(|i| 0.5 * (log_width(i) + log_width(i + 1)) / s[i]).collect()
}

/// || E_model - E_burley(d) || / || E_model - step ||: the edge misfit of Burley length `d_mm` against the normalised
/// model transfer function on the log grid `s`, relative to the edge's own blur (0 = perfect).
pub fn edge_misfit(s: &[f64], normalized: &[f64], d_mm: f64) -> f64 {
    relative_misfit(s, &squared_norm_weights(s), normalized, d_mm)
}

/// [`edge_misfit`] with the grid's weights at hand.
fn relative_misfit(s: &[f64], weights: &[f64], normalized: &[f64], d_mm: f64) -> f64 {
    let norm = |f: &dyn Fn(usize) -> f64| (0..s.len()).map(|i| weights[i] * f(i).powi(2)).sum::<f64>();
    let blur = norm(&|i| normalized[i] - 1.0);
    let misfit = norm(&|i| normalized[i] - burley_transform(s[i], d_mm));
    if blur > 0.0 {
        (misfit / blur).sqrt()
    } else {
        0.0
    }
}

/// Frequency (mm^-1) at which [`fit_burley_second_moment`] reads the curvature of the transfer function: low enough
/// that s^2 <r^2> / 4 stays below 1e-3 for profiles up to 10 mm wide, high enough that 1 - N(s) is not lost to
/// rounding (>= 1e-9 for the narrowest, 0.005 mm).
pub const SECOND_MOMENT_FREQUENCY_PER_MM: f64 = 1e-3;

/// The cheap alternative to [`fit_burley`]: match the second moment <r^2> = int r^2 R dA / int R dA, read from the
/// transfer function at one low frequency (N(s) = 1 - s^2 <r^2> / 4 + O(s^4)). Burley's profile has <r^2> = 14 d^2
/// (int r^2 (e^(-r/d) + e^(-r/3d)) / (4 d) dr = (2 d^3 + 54 d^3) / (4 d)). The moment weighs the far tail, so the
/// edge (which weighs the near field) is matched less well; `edge_residual` is left at NaN (not measured here).
pub fn fit_burley_second_moment(normalized_at_moment_frequency: f64) -> BurleyFit {
    let s = SECOND_MOMENT_FREQUENCY_PER_MM;
    let r2_mm2 = (4.0 * (1.0 - normalized_at_moment_frequency) / (s * s)).max(0.0);
    let d_mm = (r2_mm2 / 14.0).sqrt();
    BurleyFit { d_mm, radius_mm: 4.0 * PI * d_mm, edge_residual: f64::NAN }
}

/// Fit d to the normalised model transfer function `normalized[i] = R~(s[i]) / R~(0)` on the grid `s` (one fit; a
/// caller fitting many on one grid keeps a [`BurleyGrid`]).
pub fn fit_burley(s: &[f64], normalized: &[f64]) -> BurleyFit {
    BurleyGrid::new(s.to_vec()).fit(normalized)
}

/// Intervals of the coarse scan of ln d over the grid's range (ln d from 0.1 / s_max to 10 / s_min).
const SCAN: usize = 48;

/// Newton steps on ln d below which the fit stops: tighter than the 1e-7 bracket the golden-section search it replaces
/// stopped at (the step after one this small is below 1e-15; the misfit is analytic in ln d).
const LN_D_TOLERANCE: f64 = 1e-9;

/// Most steps of the refinement (Newton converges in 3 to 6 on the presets; a bisection fallback halves a bracket of
/// 0.96 in ln d to below [`LN_D_TOLERANCE`] in 30).
const REFINE_STEPS: usize = 100;

/// What the edge-L2 fit needs of one frequency grid, whatever is fitted on it: the grid, each frequency's weight in the
/// squared norm, and the Burley transform at every scan length. Built once per grid ([`BurleyGrid::of`]) instead of
/// once per fit: the scan's transforms were 49 x 33 square roots per channel.
#[derive(Debug, Clone)]
pub struct BurleyGrid {
    s_per_mm: Vec<f64>,
    /// `int f^2 / s^2 ds ~ sum_i weights[i] f(s_i)^2` (trapezoid in ln s).
    weights: Vec<f64>,
    /// ln d of the scan's ends (mm).
    scan_ln_d_mm: (f64, f64),
    /// B~(s_i; d_k) at the scan lengths d_k, k-major ((SCAN + 1) x s).
    scan_transforms: Vec<f64>,
}

impl BurleyGrid {
    /// The grid of [`fit_frequencies`]`(per_decade)`, built once per process (a few distinct grids at most: one per
    /// accuracy level).
    pub fn of(per_decade: f64) -> Arc<BurleyGrid> {
        static CACHE: OnceLock<Mutex<HashMap<u64, Arc<BurleyGrid>>>> = OnceLock::new();
        let cache = CACHE.get_or_init(Default::default);
        let key = per_decade.to_bits();
        if let Some(hit) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return Arc::clone(hit);
        }
        let fresh = Arc::new(BurleyGrid::new(fit_frequencies(per_decade)));
        let mut cache = cache.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= GRID_CACHE_ENTRIES {
            cache.clear();
        }
        cache.insert(key, Arc::clone(&fresh));
        fresh
    }

    /// The fit's tables on the log-spaced grid `s_per_mm` (rising, at least two frequencies).
    pub fn new(s_per_mm: Vec<f64>) -> BurleyGrid {
        let weights = squared_norm_weights(&s_per_mm);
        let scan_ln_d_mm = ((0.1 / s_per_mm[s_per_mm.len() - 1]).ln(), (10.0 / s_per_mm[0]).ln());
        let mut grid = BurleyGrid { s_per_mm, weights, scan_ln_d_mm, scan_transforms: Vec::new() };
        grid.scan_transforms = (0..=SCAN)
            .flat_map(|k| {
                let d_mm = grid.scan_ln_d(k as f64).exp();
                grid.s_per_mm.iter().map(move |&s| burley_transform(s, d_mm)).collect::<Vec<_>>()
            })
            .collect();
        grid
    }

    pub fn s_per_mm(&self) -> &[f64] {
        &self.s_per_mm
    }

    /// ln d (mm) of scan position `k` (fractional and beyond the ends allowed).
    fn scan_ln_d(&self, k: f64) -> f64 {
        let (lo, hi) = self.scan_ln_d_mm;
        lo + (hi - lo) * k / SCAN as f64
    }

    /// Fit d to `normalized[i] = R~(s_i) / R~(0)`: the best of the coarse scan of ln d, refined to the minimum of the
    /// misfit between its neighbours by Newton's method on the misfit's slope ([`newton_min`]).
    pub fn fit(&self, normalized: &[f64]) -> BurleyFit {
        let n = self.s_per_mm.len();
        let scan_misfit = |k: usize| {
            let b = &self.scan_transforms[k * n..(k + 1) * n];
            (0..n).map(|i| self.weights[i] * (normalized[i] - b[i]).powi(2)).sum::<f64>()
        };
        let best =
            (0..=SCAN).map(|k| (k, scan_misfit(k))).fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        let (lo, hi) = (self.scan_ln_d(best.0 as f64 - 1.0), self.scan_ln_d(best.0 as f64 + 1.0));
        let ln_d = newton_min(lo, hi, self.scan_ln_d(best.0 as f64), LN_D_TOLERANCE, REFINE_STEPS, |u| {
            self.misfit_slope_curvature(normalized, u)
        });
        let d_mm = ln_d.exp();
        BurleyFit {
            d_mm,
            radius_mm: 4.0 * PI * d_mm,
            edge_residual: relative_misfit(&self.s_per_mm, &self.weights, normalized, d_mm),
        }
    }

    /// (dm/du, d2m/du2) of the misfit m(u) = sum_i w_i (N_i - B~(s_i e^u))^2 at u = ln d.
    fn misfit_slope_curvature(&self, normalized: &[f64], ln_d_mm: f64) -> (f64, f64) {
        let d_mm = ln_d_mm.exp();
        let (mut slope, mut curvature) = (0.0, 0.0);
        for ((&s, &w), &target) in self.s_per_mm.iter().zip(&self.weights).zip(normalized) {
            let (b, db, d2b) = burley_transform_ln_derivatives(s * d_mm);
            let residual = target - b;
            slope -= 2.0 * w * residual * db;
            curvature += 2.0 * w * (db * db - residual * d2b);
        }
        (slope, curvature)
    }
}

/// Grids [`BurleyGrid::of`] keeps before it starts afresh.
const GRID_CACHE_ENTRIES: usize = 16;

/// [`burley_transform`] at x = s d and its first two derivatives in ln x (= in ln d). Each term g = (1 + t)^(-1/2),
/// t = c x^2 (c = 1, 9), has dg/du = -t g^3 and d2g/du2 = t (t - 2) g^5 (dt/du = 2 t).
fn burley_transform_ln_derivatives(x: f64) -> (f64, f64, f64) {
    let term = |c: f64| {
        let t = c * x * x;
        let g = 1.0 / (1.0 + t).sqrt();
        let g3 = g * g * g;
        (g, -t * g3, t * (t - 2.0) * g3 * g * g)
    };
    let (one, three) = (term(1.0), term(9.0));
    (0.25 * (one.0 + 3.0 * three.0), 0.25 * (one.1 + 3.0 * three.1), 0.25 * (one.2 + 3.0 * three.2))
}

/// Christensen-Burley 2015 eq. 6 fit `s(A) = 1.9 - A + 3.5 (A - 0.8)^2`: constant, linear and quadratic terms.
const BURLEY_S_CONST: f64 = 1.9;
const BURLEY_S_QUADRATIC: f64 = 3.5;
const BURLEY_S_CENTRE: f64 = 0.8;

/// `s(A) = 1.9 - A + 3.5 (A - 0.8)^2`, dimensionless: Christensen & Burley 2015, eq. 6 (`bssrdf_burley_fitting` in
/// `src/kernel/closure/bssrdf.h`, `blender/cycles` 695bae346ba1: dead code in Cycles, used by EEVEE's
/// `burley_setup`). A is clamped to [0, 1], NaN counts as 0.
pub fn christensen_burley_s(albedo: f64) -> f64 {
    let a = clamp_nan_to_low(albedo, 0.0, 1.0);
    BURLEY_S_CONST - a + BURLEY_S_QUADRATIC * (a - BURLEY_S_CENTRE) * (a - BURLEY_S_CENTRE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transform is the 2-D Fourier transform of the real-space Burley profile (direct quadrature).
    #[test]
    fn transform_matches_quadrature() {
        let d = 0.7;
        for s in [0.0, 0.5, 3.0] {
            // 2 pi int_0^inf R(r) J0(s r) r dr with R = (e^(-r/d) + e^(-r/3d)) / (8 pi d r): substitute r = -3d ln u.
            let n = 200_000;
            let h = 1.0 / n as f64;
            let mut sum = 0.0;
            for k in 0..n {
                let u = (k as f64 + 0.5) * h;
                let r = -3.0 * d * u.ln();
                let dr_du = 3.0 * d / u;
                sum += ((-r / d).exp() + (-r / (3.0 * d)).exp()) / (4.0 * d) * libm::j0(s * r) * dr_du * h;
            }
            assert!((sum - burley_transform(s, d)).abs() < 1e-4, "s={s}: {sum} vs {}", burley_transform(s, d));
        }
    }

    /// A Burley transfer function is recovered exactly, with zero residual.
    #[test]
    fn recovers_burley() {
        let s = fit_frequencies(10.0);
        for d in [0.003, 0.2, 4.0] {
            let n: Vec<f64> = s.iter().map(|&x| burley_transform(x, d)).collect();
            let fit = fit_burley(&s, &n);
            assert!((fit.d_mm / d - 1.0).abs() < 1e-5, "{d}: {}", fit.d_mm);
            assert!(fit.edge_residual < 1e-4, "{d}: {}", fit.edge_residual);
        }
    }

    /// The fit as it was before its Newton refinement: the squared norm summed as trapezoids, the same scan, then a
    /// golden-section search of ln d to a 1e-7 bracket.
    fn golden_section_fit(s: &[f64], normalized: &[f64]) -> f64 {
        let squared_norm = |f: &dyn Fn(usize) -> f64| {
            let g: Vec<f64> = (0..s.len()).map(|i| f(i).powi(2) / s[i]).collect();
            (1..s.len()).map(|i| 0.5 * (g[i] + g[i - 1]) * (s[i] / s[i - 1]).ln()).sum::<f64>()
        };
        let misfit = |d: f64| squared_norm(&|i| normalized[i] - burley_transform(s[i], d));
        let (lo, hi) = ((0.1 / s[s.len() - 1]).ln(), (10.0 / s[0]).ln());
        let ln_d = |k: f64| lo + (hi - lo) * k / SCAN as f64;
        let best = (0..=SCAN).map(|k| (k, misfit(ln_d(k as f64).exp()))).fold((0, f64::INFINITY), |a, b| {
            if b.1 < a.1 {
                b
            } else {
                a
            }
        });
        let (a, b) =
            crate::numeric::golden_section_min(ln_d(best.0 as f64 - 1.0), ln_d(best.0 as f64 + 1.0), 1e-7, |u| {
                misfit(u.exp())
            });
        (0.5 * (a + b)).exp()
    }

    /// The Newton refinement finds the d the golden-section search found (within its 1e-7 bracket in ln d) on
    /// transfer functions that are not Burley's: two Burley lengths mixed, and a dipole-like 1/(1 + (s a)^2)^(3/2),
    /// over the widths skin has and beyond, on the default and the finest grids.
    #[test]
    fn newton_refinement_matches_golden_section() {
        for per_decade in [4.0, 16.0] {
            let grid = BurleyGrid::of(per_decade);
            let s = grid.s_per_mm();
            for scale in [0.004, 0.03, 0.2, 1.0, 3.0] {
                let shapes: [&dyn Fn(f64) -> f64; 3] = [
                    &|x| 0.7 * burley_transform(x, scale) + 0.3 * burley_transform(x, 8.0 * scale),
                    &|x| (1.0 + (x * scale).powi(2)).powf(-1.5),
                    &|x| 0.5 * burley_transform(x, scale) + 0.5 * (1.0 + (x * scale * 0.3).powi(2)).powf(-0.5),
                ];
                for (k, shape) in shapes.iter().enumerate() {
                    let n: Vec<f64> = s.iter().map(|&x| shape(x)).collect();
                    let (newton, golden) = (grid.fit(&n).d_mm, golden_section_fit(s, &n));
                    assert!(
                        (newton / golden).ln().abs() < 1e-7,
                        "{per_decade} {scale} shape {k}: {newton} vs {golden}"
                    );
                    assert_eq!(grid.fit(&n), fit_burley(s, &n));
                }
            }
        }
    }

    /// The second-moment fit recovers a Burley profile's d from its transfer function at the moment frequency.
    #[test]
    fn second_moment_recovers_burley() {
        for d in [0.005, 0.2, 2.0] {
            let fit = fit_burley_second_moment(burley_transform(SECOND_MOMENT_FREQUENCY_PER_MM, d));
            assert!((fit.d_mm / d - 1.0).abs() < 2e-3, "{d}: {}", fit.d_mm);
        }
    }

    /// Christensen-Burley s(A) and its inverse 1/s = 0.34 / 0.58 / 0.91 at A = 0.2 / 0.5 / 0.8
    /// (docs/blender-principled.md, Edge and spot renders).
    #[test]
    fn christensen_burley_s_matches_its_inverse_values() {
        for (a, inv_s) in [(0.2, 0.34), (0.5, 0.58), (0.8, 0.91)] {
            let s = christensen_burley_s(a);
            assert!((1.0 / s - inv_s).abs() < 0.006, "A = {a}: 1/s = {}", 1.0 / s);
        }
        assert!((christensen_burley_s(0.8) - 1.1).abs() < 1e-12, "{}", christensen_burley_s(0.8));
    }

    #[test]
    fn christensen_burley_s_is_finite_everywhere() {
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0, 2.0] {
            assert!(christensen_burley_s(x).is_finite(), "x = {x}: {}", christensen_burley_s(x));
        }
    }
}
