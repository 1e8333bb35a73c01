//! The bounded Levenberg-Marquardt least-squares solver of this module: the spectrum fit ([`super::spectrum`]) and the
//! albedo fit ([`super::albedo`], once per distinct colour of a texture: the hot path) both call [`minimize`].
//!
//! Hand-written rather than taken from a crate: the problems here have at most eight unknowns, each inside a box
//! (the parameter ranges of `PARAMS`, or the unit cube of the albedo fit's table coordinates), and a residual that is
//! a few numbers (the albedo fit: four) or a few dozen (a spectrum). The `levenberg-marquardt` crate has no bounds and
//! brings nalgebra; argmin's least-squares solvers have no bounds either. The unknowns are a fixed-size array (`N`, a
//! const generic) so that the albedo fit's 3 x 3 normal equations live on the stack; a caller with fewer unknowns
//! than `N` holds the rest (equal bounds), which costs no evaluation.
//!
//! Bounds are handled by projection: a step is clipped to the box, and a variable at a bound whose gradient points out
//! of the box is held there for the step (the usual active-set treatment of projected Gauss-Newton; Kanzow, Yamashita
//! & Fukushima 2004, J. Comput. Appl. Math. 172:375, give the convergence theory). Derivatives are forward
//! differences (the step flipped at the upper bound, so that it stays in the box). The damping is Marquardt's
//! (1963, J. SIAM 11:431): the diagonal of JᵀJ scaled by 1 + lambda; lambda falls by 3 after an accepted step and
//! rises by 4 after a rejected one.

/// Settings of [`minimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmSettings {
    /// Most iterations (each: one Jacobian, then trial steps until one lowers the cost).
    pub max_iterations: usize,
    /// Finite-difference step as a share of each variable's range.
    pub difference_step: f64,
    /// The fit ends after an accepted step that lowers the sum of squares by no more than `relative_tolerance *
    /// (cost_floor + cost)`, with `cost` the new sum: relative to the cost for `cost_floor` 0, absolute (in the
    /// residual's units squared) below a cost of `cost_floor`.
    pub relative_tolerance: f64,
    pub cost_floor: f64,
    /// The fit ends after an accepted step that moves no variable by more than this share of its range.
    pub step_tolerance: f64,
}

impl Default for LmSettings {
    /// 60 iterations, derivatives over 1e-6 of each range, stop on a relative gain of 1e-10.
    fn default() -> Self {
        LmSettings {
            max_iterations: 60,
            difference_step: 1e-6,
            relative_tolerance: 1e-10,
            cost_floor: 0.0,
            step_tolerance: 0.0,
        }
    }
}

/// The result of [`minimize`]: `R` is the residual's type (a fixed-size array or a `Vec`).
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult<const N: usize, R> {
    pub x: [f64; N],
    pub residuals: R,
    /// Sum of squared residuals at `x` (infinite if a residual there is NaN).
    pub cost: f64,
    pub iterations: usize,
    /// Residual evaluations made (each is one forward model evaluation).
    pub evaluations: usize,
}

/// Smallest damping added to a diagonal entry of JᵀJ, as a share of lambda: keeps the step of a variable the residual
/// hardly depends on bounded.
const DAMPING_FLOOR: f64 = 1e-9;
/// Added to every free diagonal entry, so the damped normal matrix stays positive definite.
const DIAGONAL_SHIFT: f64 = 1e-12;

/// Minimise `sum(residuals(x)^2)` over the box `lower <= x <= upper` from `x0` (clipped into the box). A variable
/// whose bounds are equal (or crossed) is held at its lower bound: no derivative is taken in it. `residuals` returns
/// a vector of the same length at every `x`; a NaN residual counts as an infinite cost (the step is rejected).
pub fn minimize<const N: usize, R, F>(
    residuals: F,
    x0: [f64; N],
    lower: [f64; N],
    upper: [f64; N],
    settings: &LmSettings,
) -> LmResult<N, R>
where
    R: AsRef<[f64]> + AsMut<[f64]>,
    F: Fn(&[f64; N]) -> R,
{
    let held: [bool; N] = std::array::from_fn(|i| upper[i] <= lower[i]);
    let range: [f64; N] = std::array::from_fn(|i| upper[i] - lower[i]);
    let clip = |v: f64, i: usize| if held[i] { lower[i] } else { v.clamp(lower[i], upper[i]) };
    let mut x: [f64; N] = std::array::from_fn(|i| clip(x0[i], i));
    let mut r = residuals(&x);
    let mut evaluations = 1;
    let mut cost = sum_sq(r.as_ref());
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < settings.max_iterations && cost.is_finite() && cost > 0.0 {
        iterations += 1;
        // Jacobian columns by forward differences, into the box.
        let columns: [Option<R>; N] = std::array::from_fn(|i| {
            if held[i] {
                return None;
            }
            let mut h = settings.difference_step * range[i];
            if x[i] + h > upper[i] {
                h = -h;
            }
            let mut xh = x;
            xh[i] += h;
            let mut column = residuals(&xh);
            evaluations += 1;
            for (v, r0) in column.as_mut().iter_mut().zip(r.as_ref()) {
                *v = (*v - r0) / h;
            }
            Some(column)
        });
        // Gradient g = Jᵀr and the normal matrix JᵀJ (zero in held variables).
        let mut g = [0.0; N];
        let mut jtj = [[0.0; N]; N];
        for i in 0..N {
            let Some(ci) = &columns[i] else { continue };
            g[i] = dot(ci.as_ref(), r.as_ref());
            for j in i..N {
                if let Some(cj) = &columns[j] {
                    jtj[i][j] = dot(ci.as_ref(), cj.as_ref());
                    jtj[j][i] = jtj[i][j];
                }
            }
        }
        // Variables at a bound whose descent direction (-g) points out of the box are held for this step (a projected
        // step would otherwise shrink to nothing there).
        let fixed: [bool; N] =
            std::array::from_fn(|i| held[i] || (x[i] <= lower[i] && g[i] > 0.0) || (x[i] >= upper[i] && g[i] < 0.0));
        let mut improved = false;
        while lambda < 1e12 {
            // Fixed variables: their rows and columns are the identity and their right-hand side zero (no step).
            let mut a = jtj;
            let mut b = [0.0; N];
            for i in 0..N {
                if fixed[i] {
                    a[i] = [0.0; N];
                    a.iter_mut().for_each(|row| row[i] = 0.0);
                    a[i][i] = 1.0;
                } else {
                    a[i][i] += lambda * a[i][i].max(DAMPING_FLOOR) + DIAGONAL_SHIFT;
                    b[i] = -g[i];
                }
            }
            let Some(step) = solve(a, b) else {
                lambda *= 4.0;
                continue;
            };
            let x_new: [f64; N] = std::array::from_fn(|i| clip(x[i] + step[i], i));
            let r_new = residuals(&x_new);
            evaluations += 1;
            let cost_new = sum_sq(r_new.as_ref());
            if cost_new.is_finite() && cost_new < cost {
                let moved =
                    (0..N).filter(|&i| !held[i]).map(|i| (x_new[i] - x[i]).abs() / range[i]).fold(0.0, f64::max);
                let gain = cost - cost_new;
                x = x_new;
                r = r_new;
                cost = cost_new;
                lambda = (lambda / 3.0).max(1e-9);
                improved = moved > settings.step_tolerance
                    && gain > settings.relative_tolerance * (settings.cost_floor + cost);
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    LmResult { x, residuals: r, cost, iterations, evaluations }
}

/// Sum of squares; NaN (a residual the model could not compute) counts as infinite.
fn sum_sq(r: &[f64]) -> f64 {
    let s = dot(r, r);
    if s.is_nan() {
        f64::INFINITY
    } else {
        s
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        s += x * y;
    }
    s
}

/// Solve `a x = b` (small, dense) by Gaussian elimination with partial pivoting; None if singular.
fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-300 || a[pivot][col].is_nan() {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for row in col + 1..N {
            let f = a[row][col] / pivot_row[col];
            for k in col..N {
                a[row][k] -= f * pivot_row[k];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let mut s = 0.0;
        for k in row + 1..N {
            s += a[row][k] * x[k];
        }
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as least squares (r = (10 (y - x^2), 1 - x)): the minimum (1, 1) from the classic start (-1.2, 1),
    /// with the residual as a fixed-size array and as a `Vec`.
    #[test]
    fn rosenbrock_minimum() {
        let settings = LmSettings { max_iterations: 200, ..LmSettings::default() };
        let array = minimize(
            |x: &[f64; 2]| [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]],
            [-1.2, 1.0],
            [-5.0; 2],
            [5.0; 2],
            &settings,
        );
        assert!((array.x[0] - 1.0).abs() < 1e-6 && (array.x[1] - 1.0).abs() < 1e-6, "{array:?}");
        let vec = minimize(
            |x: &[f64; 2]| vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]],
            [-1.2, 1.0],
            [-5.0; 2],
            [5.0; 2],
            &settings,
        );
        assert_eq!((vec.x, vec.cost, vec.evaluations), (array.x, array.cost, array.evaluations));
    }

    /// A bound that cuts off the unconstrained minimum: min (x - 2)^2 + (y + 1)^2 on [0, 1]^2 is the corner (1, 0),
    /// where both variables are held at their bounds.
    #[test]
    fn bounded_minimum_is_on_the_boundary() {
        let f = |x: &[f64; 2]| [x[0] - 2.0, x[1] + 1.0];
        let res = minimize(f, [0.5, 0.5], [0.0; 2], [1.0; 2], &LmSettings::default());
        assert_eq!(res.x, [1.0, 0.0]);
        assert!((res.cost - 2.0).abs() < 1e-12, "{res:?}");
    }

    /// A variable with equal bounds is held there and costs no evaluation: the other is fitted as if alone (the same
    /// steps and evaluations, none for the held variable's derivative).
    #[test]
    fn equal_bounds_hold_a_variable() {
        let f = |x: &[f64; 2]| [x[0] - 0.3, 10.0 * (x[1] - 0.9)];
        let res = minimize(f, [0.8, 0.5], [0.0, 0.5], [1.0, 0.5], &LmSettings::default());
        assert_eq!(res.x[1], 0.5);
        assert!((res.x[0] - 0.3).abs() < 1e-9, "{res:?}");
        let alone = minimize(|x: &[f64; 1]| [x[0] - 0.3, -4.0], [0.8], [0.0], [1.0], &LmSettings::default());
        assert_eq!((res.x[0], res.evaluations), (alone.x[0], alone.evaluations));
    }

    /// A NaN residual is an infinite cost: a start there ends the fit at once, a step there is rejected.
    #[test]
    fn nan_residuals_are_rejected() {
        let at_start = minimize(|_: &[f64; 1]| [f64::NAN], [0.5], [0.0], [1.0], &LmSettings::default());
        assert_eq!((at_start.cost, at_start.iterations, at_start.evaluations), (f64::INFINITY, 0, 1));
        // NaN above 0.6: the minimum at 0.8 is out of reach, the fit ends below 0.6.
        let f = |x: &[f64; 1]| [if x[0] > 0.6 { f64::NAN } else { x[0] - 0.8 }];
        let res = minimize(f, [0.1], [0.0], [1.0], &LmSettings::default());
        assert!(res.cost.is_finite() && res.x[0] <= 0.6, "{res:?}");
    }
}
