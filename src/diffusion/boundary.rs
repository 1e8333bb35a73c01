//! Boundary conditions of the diffusion approximation: diffuse Fresnel reflectance and the extrapolation distance.

/// `F_dr(eta)`: average diffuse Fresnel reflectance for relative index eta = n_inside / n_outside
/// (Egan & Hilgeman polynomial fits as used by Jensen et al. 2001 and DJ05; docs/model.md, Boundary, and Pitfalls 13).
/// As published the two fits meet at eta = 1 with a step of 1e-4 (0.0016 above, 0.0017 below); the one below is
/// shifted by that step so that F_dr, and every output, is continuous in the indices (a vanishing layer must vanish).
pub fn fdr(eta: f64) -> f64 {
    if eta >= 1.0 {
        -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
    } else {
        -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta) + FIT_STEP_AT_ONE
    }
}

/// Value of the eta >= 1 fit minus that of the eta < 1 fit at eta = 1: 0.0016 - 0.0017.
const FIT_STEP_AT_ONE: f64 = (-1.440 + 0.710 + 0.668 + 0.0636) - (-0.4399 + 0.7099 - 0.3319 + 0.0636);

/// `A(eta) = (1 + F_dr) / (1 - F_dr)`: internal-reflection parameter of the boundary (Jensen et al. 2001 eq. 6).
pub fn internal_reflection_a(eta: f64) -> f64 {
    let f = fdr(eta);
    (1.0 + f) / (1.0 - f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independently computed values (docs/model.md, Boundary).
    #[test]
    fn spec_values() {
        assert!((fdr(1.4) - 0.52949).abs() < 5e-5, "{}", fdr(1.4));
        assert!((internal_reflection_a(1.4) - 3.2507).abs() < 5e-4, "{}", internal_reflection_a(1.4));
        assert!((fdr(1.0) - 0.0016).abs() < 1e-4, "{}", fdr(1.0));
        assert!((internal_reflection_a(1.0) - 1.0032).abs() < 2e-4, "{}", internal_reflection_a(1.0));
        // pitfall 13: eta = 1/1.4 would give 0.078
        assert!((fdr(1.0 / 1.4) - 0.078).abs() < 2e-3, "{}", fdr(1.0 / 1.4));
    }

    #[test]
    fn continuous_at_one() {
        assert!((fdr(1.0 - 1e-12) - fdr(1.0)).abs() < 1e-10, "{} {}", fdr(1.0 - 1e-12), fdr(1.0));
    }

    /// Unpolarised Fresnel reflectance for light inside a medium of relative index eta meeting the boundary at
    /// cos(theta) = mu (Born & Wolf 1.5.2); 1 past the critical angle.
    fn fresnel_inside(eta: f64, mu: f64) -> f64 {
        let sin_t2 = eta * eta * (1.0 - mu * mu);
        if sin_t2 >= 1.0 {
            return 1.0;
        }
        let ct = (1.0 - sin_t2).sqrt();
        let rs = ((eta * mu - ct) / (eta * mu + ct)).powi(2);
        let rp = ((eta * ct - mu) / (eta * ct + mu)).powi(2);
        0.5 * (rs + rp)
    }

    /// The exact diffuse reflectance F_dr = int_0^1 2 mu F(mu) dmu (midpoint rule, 2e5 points).
    fn fdr_exact(eta: f64) -> f64 {
        let n = 200_000;
        (0..n).map(|k| (k as f64 + 0.5) / n as f64).map(|mu| 2.0 * mu * fresnel_inside(eta, mu)).sum::<f64>() / n as f64
    }

    /// The relative indices a stack can produce (layer indices in `IOR_RANGE`, air above: [1/2, 2]) are where the
    /// polynomial fits hold: A within 0.5 % of the exact integral's. Just outside they fail (the reason for the range).
    #[test]
    fn fits_hold_on_the_accepted_range_only() {
        let (lo, hi) = crate::layer::IOR_RANGE;
        let a_exact = |eta: f64| {
            let f = fdr_exact(eta);
            (1.0 + f) / (1.0 - f)
        };
        let mut worst: f64 = 0.0;
        for k in 0..=60 {
            let eta = (lo / hi) * (hi * hi / lo).powf(k as f64 / 60.0); // log-spaced over [1/2, 2]
            worst = worst.max((internal_reflection_a(eta) / a_exact(eta) - 1.0).abs());
        }
        assert!(worst < 0.005, "worst relative error of A on [1/2, 2]: {worst}");
        for eta in [0.4, 2.5] {
            assert!((internal_reflection_a(eta) / a_exact(eta) - 1.0).abs() > 0.04, "eta {eta}");
        }
    }
}
