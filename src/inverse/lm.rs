//! A small bounded Levenberg-Marquardt least-squares solver, shared by the fits of this module.
//!
//! Hand-written rather than taken from a crate: the problems here have at most eight unknowns, each inside a box
//! (the parameter ranges of `PARAMS`), and a residual that is a few dozen numbers. The `levenberg-marquardt` crate has no
//! bounds and brings nalgebra; argmin's least-squares solvers have no bounds either. Bounds are handled by
//! projection: a step is clipped to the box, and a variable at a bound whose gradient points out of the box is held
//! there for the step (the usual active-set treatment of projected Gauss-Newton; Kanzow, Yamashita & Fukushima 2004,
//! J. Comput. Appl. Math. 172:375, give the convergence theory). Derivatives are one-sided finite differences (taken
//! into the box at a bound).

/// Settings of [`minimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmSettings {
    /// Most iterations (accepted or rejected steps).
    pub max_iterations: usize,
    /// Stop when a step lowers the sum of squares by less than this share of it.
    pub relative_tolerance: f64,
    /// Finite-difference step as a share of each variable's range.
    pub difference_step: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        LmSettings { max_iterations: 60, relative_tolerance: 1e-10, difference_step: 1e-6 }
    }
}

/// The result of [`minimize`].
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    pub x: Vec<f64>,
    pub residuals: Vec<f64>,
    /// Sum of squared residuals at `x`.
    pub cost: f64,
    pub iterations: usize,
    /// Residual evaluations made (each is one forward model evaluation).
    pub evaluations: usize,
}

/// Minimise `sum(residuals(x)^2)` over the box `lower <= x <= upper` from `x0` (clipped into the box). `residuals`
/// returns a vector of the same length at every `x`; a non-finite residual counts as an infinite cost (the step is
/// rejected).
pub fn minimize<F>(residuals: F, x0: &[f64], lower: &[f64], upper: &[f64], settings: &LmSettings) -> LmResult
where
    F: Fn(&[f64]) -> Vec<f64>,
{
    let n = x0.len();
    let mut x: Vec<f64> = (0..n).map(|i| x0[i].clamp(lower[i], upper[i])).collect();
    let mut r = residuals(&x);
    let mut evaluations = 1;
    let mut cost = sum_sq(&r);
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < settings.max_iterations && cost.is_finite() && cost > 0.0 {
        iterations += 1;
        // Jacobian by one-sided differences, into the box.
        let mut jac = vec![vec![0.0; r.len()]; n];
        for i in 0..n {
            let range = upper[i] - lower[i];
            let mut h = settings.difference_step * range.max(f64::MIN_POSITIVE);
            if x[i] + h > upper[i] {
                h = -h;
            }
            let mut xh = x.clone();
            xh[i] += h;
            let rh = residuals(&xh);
            evaluations += 1;
            for (k, v) in rh.iter().enumerate() {
                jac[i][k] = (v - r[k]) / h;
            }
        }
        // Gradient g = J^T r and the normal matrix J^T J.
        let g: Vec<f64> = (0..n).map(|i| dot(&jac[i], &r)).collect();
        let jtj: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| dot(&jac[i], &jac[j])).collect()).collect();
        // Variables at a bound whose descent direction (-g) points out of the box are held for this step.
        let active: Vec<bool> =
            (0..n).map(|i| (x[i] <= lower[i] && g[i] > 0.0) || (x[i] >= upper[i] && g[i] < 0.0)).collect();
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = jtj.clone();
            let mut b: Vec<f64> = g.iter().map(|v| -v).collect();
            for i in 0..n {
                if active[i] {
                    a[i].iter_mut().for_each(|v| *v = 0.0);
                    a.iter_mut().for_each(|row| row[i] = 0.0);
                    a[i][i] = 1.0;
                    b[i] = 0.0;
                } else {
                    a[i][i] += lambda * a[i][i].max(1e-12);
                }
            }
            let Some(step) = solve(a, b) else {
                lambda *= 10.0;
                continue;
            };
            let x_new: Vec<f64> = (0..n).map(|i| (x[i] + step[i]).clamp(lower[i], upper[i])).collect();
            let r_new = residuals(&x_new);
            evaluations += 1;
            let cost_new = sum_sq(&r_new);
            if cost_new.is_finite() && cost_new < cost {
                let gain = (cost - cost_new) / cost;
                x = x_new;
                r = r_new;
                cost = cost_new;
                lambda = (lambda * 0.3).max(1e-9);
                improved = gain > settings.relative_tolerance;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    LmResult { x, residuals: r, cost, iterations, evaluations }
}

fn sum_sq(r: &[f64]) -> f64 {
    let s: f64 = r.iter().map(|v| v * v).sum();
    if s.is_nan() {
        f64::INFINITY
    } else {
        s
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve `a x = b` (small, dense) by Gaussian elimination with partial pivoting; None if singular.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-300 || a[pivot][col].is_nan() {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col].clone();
            for (v, p) in a[row].iter_mut().zip(&pivot_row).skip(col) {
                *v -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares (r = (10 (y - x^2), 1 - x)): the minimum (1, 1) from the classic start (-1.2, 1).
    #[test]
    fn rosenbrock_minimum() {
        let f = |x: &[f64]| vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]];
        let settings = LmSettings { max_iterations: 200, ..LmSettings::default() };
        let res = minimize(f, &[-1.2, 1.0], &[-5.0, -5.0], &[5.0, 5.0], &settings);
        assert!((res.x[0] - 1.0).abs() < 1e-6 && (res.x[1] - 1.0).abs() < 1e-6, "{res:?}");
    }

    /// A bound that cuts off the unconstrained minimum: min (x - 2)^2 + (y + 1)^2 on [0, 1]^2 is the corner (1, 0),
    /// where both variables are held at their bounds.
    #[test]
    fn bounded_minimum_is_on_the_boundary() {
        let f = |x: &[f64]| vec![x[0] - 2.0, x[1] + 1.0];
        let res = minimize(f, &[0.5, 0.5], &[0.0, 0.0], &[1.0, 1.0], &LmSettings::default());
        assert_eq!(res.x, vec![1.0, 0.0]);
        assert!((res.cost - 2.0).abs() < 1e-12);
    }
}
