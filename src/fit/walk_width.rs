//! Measured width of Cycles' random walks: the Christensen-Burley length d that fits a rendered half-shadow edge,
//! per unit of the walk's transport mean free path, against Base Color.
//!
//! The measurements live once, in `docs/data/random_walk_width.json` (written by
//! `<venv>/bin/python scripts/calibration/calibrate_random_walk.py`, scene and method in
//! `docs/blender-render-tests.md`); they are compiled in with `include_str!` and read here. Between measured Base
//! Colors `ln k` is interpolated linearly (k > 0 and rising, so the result is monotone). Below the lowest measured
//! Base Color, k follows Christensen-Burley's `1/s(A)` scaled to meet the lowest point (continuous; the measured k
//! tracks 1/s to within 10 % at A = 0.1-0.5). Above the highest one, the last segment's slope in `ln k` continues up
//! to `a_max` (the Base Color past which the walk's medium stops changing: the Wrenninge fit's saturation, 1
//! otherwise) and k is held beyond.

use std::sync::OnceLock;

use serde::Deserialize;

use super::burley::christensen_burley_s;

/// The render measurements, compiled in.
const CALIBRATION_JSON: &str = include_str!("../../docs/data/random_walk_width.json");

#[derive(Deserialize)]
struct CalibrationFile {
    entries: Vec<CalibrationEntry>,
}

#[derive(Deserialize)]
struct CalibrationEntry {
    blender: String,
    method: String,
    cases: Vec<CalibrationCase>,
}

#[derive(Deserialize)]
struct CalibrationCase {
    albedo: f64,
    d_over_mfp: f64,
}

/// Which measured walk: the measurement's Blender version and Cycles method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeasuredWalk {
    /// `RANDOM_WALK` in bpy 5.0 (Wrenninge fit for alpha; `RANDOM_WALK_LEGACY` from 5.2).
    WrenningeFit,
    /// `RANDOM_WALK` in bpy 5.3 (Van de Hulst alpha, 5.2 and later).
    VanDeHulst,
    /// `RANDOM_WALK_SKIN` in bpy 5.0 (mean free path = Radius x Scale x sqrt(3 (1 - alpha')), `random_walk_skin`).
    Skin,
}

impl MeasuredWalk {
    const ALL: [MeasuredWalk; 3] = [MeasuredWalk::WrenningeFit, MeasuredWalk::VanDeHulst, MeasuredWalk::Skin];

    /// (Blender version, Cycles method) of the JSON entry that measured this walk.
    fn key(self) -> (&'static str, &'static str) {
        match self {
            MeasuredWalk::WrenningeFit => ("5.0", "RANDOM_WALK"),
            MeasuredWalk::VanDeHulst => ("5.3", "RANDOM_WALK"),
            MeasuredWalk::Skin => ("5.0", "RANDOM_WALK_SKIN"),
        }
    }
}

/// (Base Color, k = d / mean free path) rows of `walk`, rising in Base Color. The JSON is part of the source: a
/// malformed or missing entry is a build defect, caught by this module's tests.
pub fn measured_points(walk: MeasuredWalk) -> &'static [(f64, f64)] {
    static TABLES: OnceLock<Vec<Vec<(f64, f64)>>> = OnceLock::new();
    let tables = TABLES.get_or_init(|| {
        let file: CalibrationFile =
            serde_json::from_str(CALIBRATION_JSON).expect("docs/data/random_walk_width.json parses");
        MeasuredWalk::ALL
            .iter()
            .map(|w| {
                let (blender, method) = w.key();
                let entry = file
                    .entries
                    .iter()
                    .find(|e| e.blender == blender && e.method == method)
                    .expect("docs/data/random_walk_width.json has every measured walk");
                let mut rows: Vec<(f64, f64)> = entry.cases.iter().map(|c| (c.albedo, c.d_over_mfp)).collect();
                rows.sort_by(|a, b| a.0.total_cmp(&b.0));
                rows
            })
            .collect()
    });
    let index = MeasuredWalk::ALL.iter().position(|&w| w == walk).unwrap_or(0);
    &tables[index]
}

/// `k(A)` = Burley d / walk mean free path at Base Color `a` for `walk` (module doc: log-linear inside the measured
/// range, `1/s(A)` joined below, the last trend continued up to `a_max` above). Dimensionless, > 0. NaN counts as 0.
pub fn measured_k(walk: MeasuredWalk, a: f64, a_max: f64) -> f64 {
    let t = measured_points(walk);
    let a = if a >= 0.0 { a.min(1.0) } else { 0.0 };
    let (first, last) = (t[0], t[t.len() - 1]);
    if a <= first.0 {
        return first.1 * christensen_burley_s(first.0) / christensen_burley_s(a);
    }
    let k = if a >= last.0 { t.len() - 1 } else { t.partition_point(|&(x, _)| x < a).clamp(1, t.len() - 1) };
    let ((x0, y0), (x1, y1)) = (t[k - 1], t[k]);
    let x = a.min(a_max.max(last.0));
    (y0.ln() + (y1.ln() - y0.ln()) * (x - x0) / (x1 - x0)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The compiled-in table holds what the JSON file says, read independently by a plain text scan, and its rows
    /// rise in Base Color and k.
    #[test]
    fn tables_match_the_json_and_rise() {
        for walk in MeasuredWalk::ALL {
            let t = measured_points(walk);
            assert_eq!(t.len(), 9, "{walk:?}");
            assert!(t.windows(2).all(|w| w[1].0 > w[0].0 && w[1].1 > w[0].1), "{walk:?}: {t:?}");
        }
        // Brief's table (from the same render run): d/l at A = 0.1 / 0.5 / 0.9.
        for (walk, want) in [
            (MeasuredWalk::WrenningeFit, [0.257, 0.584, 1.284]),
            (MeasuredWalk::VanDeHulst, [0.256, 0.580, 1.228]),
            (MeasuredWalk::Skin, [0.280, 0.586, 0.997]),
        ] {
            for (a, w) in [0.1, 0.5, 0.9].iter().zip(want) {
                let got = measured_k(walk, *a, 1.0);
                assert!((got - w).abs() < 6e-4, "{walk:?} A = {a}: {got} vs {w}");
            }
        }
    }

    /// Interpolation reproduces every measured point, stays between neighbours, joins 1/s below the table
    /// continuously and holds past `a_max`.
    #[test]
    fn interpolation_and_extrapolation() {
        for walk in MeasuredWalk::ALL {
            let t = measured_points(walk);
            for &(a, k) in t {
                assert!((measured_k(walk, a, 1.0) / k - 1.0).abs() < 1e-12, "{walk:?} A = {a}");
            }
            for w in t.windows(2) {
                let mid = measured_k(walk, 0.5 * (w[0].0 + w[1].0), 1.0);
                assert!(mid > w[0].1 && mid < w[1].1, "{walk:?}: {mid} not in {w:?}");
            }
            let (a0, k0) = t[0];
            assert!(
                (measured_k(walk, a0 - 1e-9, 1.0) / k0 - 1.0).abs() < 1e-7,
                "{walk:?}: {} vs {k0}",
                measured_k(walk, a0 - 1e-9, 1.0)
            );
            // Below: the 1/s shape (k(0)/k(0.05) = s(0.05)/s(0)).
            let r = measured_k(walk, 0.0, 1.0) / measured_k(walk, 0.05, 1.0);
            assert!(
                (r - christensen_burley_s(0.05) / christensen_burley_s(0.0)).abs() < 1e-12,
                "{walk:?}: {r} vs {}",
                christensen_burley_s(0.05) / christensen_burley_s(0.0)
            );
            assert!(
                measured_k(walk, f64::NAN, 1.0) == measured_k(walk, 0.0, 1.0),
                "{walk:?}: {} vs {}",
                measured_k(walk, f64::NAN, 1.0),
                measured_k(walk, 0.0, 1.0)
            );
            // Above: continues rising to a_max, then holds.
            let top = t[t.len() - 1];
            assert!(measured_k(walk, 0.95, 1.0) > top.1, "{walk:?}: {} vs {}", measured_k(walk, 0.95, 1.0), top.1);
            assert_eq!(measured_k(walk, 0.95, 0.92), measured_k(walk, 0.92, 0.92), "{walk:?}");
        }
    }
}
