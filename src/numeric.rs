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

    #[test]
    fn gauss_legendre_integrates_polynomials() {
        let (x, w) = gauss_legendre(8);
        let integral: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
        assert!((integral - 2.0 / 15.0).abs() < 1e-14);
        assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-14);
    }
}
