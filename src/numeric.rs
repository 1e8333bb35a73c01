//! Guarded numerics shared by the physics modules.

/// `a / b`, or `fallback` when `b` is zero or the quotient is not finite.
pub fn safe_div(a: f64, b: f64, fallback: f64) -> f64 {
    let q = a / b;
    if q.is_finite() {
        q
    } else {
        fallback
    }
}

/// `max(x, 0)`, mapping NaN to 0.
pub fn clamp_zero(x: f64) -> f64 {
    if x > 0.0 {
        x
    } else {
        0.0
    }
}

/// `(1 - e^(-a q)) / (1 - e^(-b q))` for a, b > 0 and q >= 0, exact to rounding for every q, including its limit a / b at q = 0.
/// It is the sum of a geometric series of multipole images (see `diffusion::multipole`).
pub fn expm1_ratio(a: f64, b: f64, q: f64) -> f64 {
    let den = -(-b * q).exp_m1();
    if den > 0.0 {
        -(-a * q).exp_m1() / den
    } else {
        a / b
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, 0.0);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
            }
            let dp = n as f64 * (z * p0 - p1) / (z * z - 1.0);
            let dz = p0 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                let dp = {
                    let (mut p0, mut p1) = (1.0, 0.0);
                    for j in 0..n {
                        let p2 = p1;
                        p1 = p0;
                        p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
                    }
                    n as f64 * (z * p0 - p1) / (z * z - 1.0)
                };
                x[i] = -z;
                w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
                break;
            }
        }
    }
    (x, w)
}

/// `table[n][j] = P_n(x_j)`, Legendre polynomials of degree n < `order` at the points `x` (three-term recurrence).
pub fn legendre_table(order: usize, x: &[f64]) -> Vec<Vec<f64>> {
    let mut table = vec![vec![1.0; x.len()]; order];
    if order > 1 {
        table[1] = x.to_vec();
    }
    for n in 1..order.saturating_sub(1) {
        let next: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(j, &xj)| ((2 * n + 1) as f64 * xj * table[n][j] - n as f64 * table[n - 1][j]) / (n + 1) as f64)
            .collect();
        table[n + 1] = next;
    }
    table
}

/// Spherical Bessel functions `j_n(x)` for n < `count` and x > 0: upward recurrence from j_0, j_1 where it is stable
/// (n < x), Miller's downward recurrence normalised by sum (2n+1) j_n^2 = 1 otherwise (Abramowitz & Stegun 10.1.50,
/// 10.1.19; Numerical Recipes 6.7).
pub fn spherical_bessel_j(count: usize, x: f64) -> Vec<f64> {
    let mut out = vec![0.0; count];
    if count == 0 {
        return out;
    }
    if x >= count as f64 {
        let (s, c) = x.sin_cos();
        out[0] = s / x;
        if count > 1 {
            out[1] = s / (x * x) - c / x;
        }
        for n in 1..count.saturating_sub(1) {
            out[n + 1] = (2 * n + 1) as f64 / x * out[n] - out[n - 1];
        }
        return out;
    }
    let start = count + 40 + x as usize;
    let mut values = vec![0.0; start + 2];
    values[start] = 1.0;
    for n in (1..=start).rev() {
        values[n - 1] = (2 * n + 1) as f64 / x * values[n] - values[n + 1];
        if values[n - 1].abs() > 1e100 {
            for v in values[n - 1..].iter_mut() {
                *v *= 1e-100;
            }
        }
    }
    let norm: f64 = values.iter().enumerate().map(|(n, v)| (2 * n + 1) as f64 * v * v).sum::<f64>().sqrt();
    // The sign from whichever of j_0, j_1 is larger in closed form.
    let (s, c) = x.sin_cos();
    let (j0, j1) = (s / x, s / (x * x) - c / x);
    let sign = if j0.abs() >= j1.abs() { (j0 * values[0]).signum() } else { (j1 * values[1]).signum() };
    for (o, v) in out.iter_mut().zip(&values) {
        *o = sign * v / norm;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm1_ratio_limits() {
        assert_eq!(expm1_ratio(1.0, 4.0, 0.0), 0.25);
        assert!((expm1_ratio(1.0, 4.0, 1e-300) - 0.25).abs() < 1e-15);
        let q: f64 = 0.3;
        let direct = (1.0 - (-q).exp()) / (1.0 - (-4.0 * q).exp());
        assert!((expm1_ratio(1.0, 4.0, q) - direct).abs() < 1e-15);
        assert_eq!(expm1_ratio(1.0, 4.0, 1e6), 1.0);
    }

    /// Spherical Bessel functions against their closed forms j_2 = (3/x^3 - 1/x) sin x - 3 cos x / x^2, on both
    /// sides of the switch between the recurrences, and the small-argument limit x^n / (2n+1)!!.
    #[test]
    fn spherical_bessel_closed_forms() {
        for x in [0.7, 3.0, 11.9, 12.0, 40.0, 1e4] {
            let j = spherical_bessel_j(12, x);
            let (s, c) = (x.sin(), x.cos());
            let j2 = (3.0 / (x * x * x) - 1.0 / x) * s - 3.0 * c / (x * x);
            assert!((j[0] - s / x).abs() < 1e-14 && (j[2] - j2).abs() < 1e-12 * j2.abs().max(1e-3), "x={x}: {j:?}");
        }
        let j = spherical_bessel_j(12, 1e-3);
        let double_factorial_21: f64 = (1..=21).step_by(2).map(|k| k as f64).product();
        assert!((j[10] / (1e-30 / double_factorial_21) - 1.0).abs() < 1e-6, "{}", j[10]);
    }

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(8);
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
        assert!((integral - 2.0 / 15.0).abs() < 1e-14);
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-14);
    }
}
