//! The report's error metrics and its timer.

use std::time::Instant;

use spectral_skin::color::difference::{ciede2000, lab_from_xyz};

/// Largest relative difference over the three channels.
pub fn max_relative(test: [f64; 3], reference: [f64; 3]) -> f64 {
    (0..3).map(|c| ((test[c] - reference[c]) / reference[c]).abs()).fold(0.0, f64::max)
}

/// Linear Rec.709 to CIE XYZ (IEC 61966-2-1, D65; Y of white = 1).
fn rec709_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]];
    [0, 1, 2].map(|i| M[i][0] * rgb[0] + M[i][1] * rgb[1] + M[i][2] * rgb[2])
}

/// CIELAB of linear Rec.709 under D65 (the core's CIE 15:2004 formula): white (1, 1, 1) is L* = 100.
fn rec709_to_lab(rgb: [f64; 3]) -> [f64; 3] {
    lab_from_xyz(rec709_to_xyz(rgb), rec709_to_xyz([1.0; 3]))
}

/// CIEDE2000 colour difference (the core's, Sharma et al. 2005) of two linear Rec.709 colours (the albedo as
/// rendered); 1 is about a just-noticeable difference side by side.
pub fn delta_e_2000(test: [f64; 3], reference: [f64; 3]) -> f64 {
    ciede2000(rec709_to_lab(test), rec709_to_lab(reference))
}

/// Profile error "in log space": max over the log-spaced radii and the channels of |ln(R / R_ref)|, where both are
/// raised to a floor: 0.1 % of the channel's peak energy per unit ln r, max of r^2 R_ref(r) (below it a radius carries
/// no visible light, and there the green and blue channels are near-cancellations of out-of-gamut red light, which can
/// dip below zero). Weighting by r^2 keeps the far tail, which holds a few per cent of the light of fair skin.
pub fn profile_log_error(radii_mm: &[f64], test: &[[f64; 3]], reference: &[[f64; 3]]) -> f64 {
    let mut worst = 0.0f64;
    for c in 0..3 {
        let peak = radii_mm.iter().zip(reference).map(|(r, v)| r * r * v[c]).fold(0.0, f64::max);
        let floor = 1e-3 * peak;
        for ((radius, t), r) in radii_mm.iter().zip(test).zip(reference) {
            let energy = |v: f64| (radius * radius * v).max(floor);
            worst = worst.max((energy(t[c]) / energy(r[c])).ln().abs());
        }
    }
    worst
}

/// exp(log error) - 1: the log error as a relative factor, for tables.
pub fn log_to_relative(log_error: f64) -> f64 {
    log_error.exp_m1()
}

/// Median wall time of `f`, seconds: at least `min_runs` runs, more until `budget_s` is spent (at most 101).
pub fn median_seconds(min_runs: usize, budget_s: f64, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut times = Vec::new();
    while times.len() < min_runs || (start.elapsed().as_secs_f64() < budget_s && times.len() < 101) {
        let t = Instant::now();
        f();
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// Peak resident memory of this process so far, MiB (Linux `VmHWM`; None elsewhere).
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Times within this factor of each other count as equal (the spread of repeated medians on a shared 2-core machine).
pub const TIME_TOLERANCE: f64 = 1.15;

/// Whether (time, error) point `b` dominates `a`: clearly faster (beyond the timing tolerance) and no less accurate,
/// or no slower (within the tolerance) and clearly more accurate (less than half the error).
fn dominates(b: (f64, f64), a: (f64, f64)) -> bool {
    (b.0 * TIME_TOLERANCE < a.0 && b.1 <= a.1) || (b.0 <= a.0 * TIME_TOLERANCE && b.1 < 0.5 * a.1)
}

/// Indices of the points on the Pareto front of (time, error), in time order: no other point dominates them.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let ok = |p: (f64, f64)| p.0.is_finite() && p.1.is_finite();
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| {
            ok(points[i]) && !(0..points.len()).any(|j| j != i && ok(points[j]) && dominates(points[j], points[i]))
        })
        .collect();
    front.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_is_l100_and_front_is_monotone() {
        let [l, a, b] = rec709_to_lab([1.0; 3]);
        assert!((l - 100.0).abs() < 1e-9 && a.abs() < 1e-9 && b.abs() < 1e-9, "white: L*a*b* = {l}, {a}, {b}");
        let front = pareto_front(&[(1.0, 5.0), (2.0, 6.0), (3.0, 1.0), (0.5, 9.0), (1.05, 4.9)]);
        assert_eq!(front, vec![3, 0, 4, 2]);
        // Within the timing tolerance, a setting with less than half the error dominates.
        assert_eq!(pareto_front(&[(1.0, 5.0), (1.1, 1.0), (0.5, 9.0)]), vec![2, 1]);
    }
}
