//! Boundary conditions of the diffusion approximation: diffuse Fresnel reflectance and the extrapolation distance.

/// `F_dr(eta)`: average diffuse Fresnel reflectance for relative index eta = n_inside / n_outside
/// (Egan & Hilgeman polynomial fits as used by Jensen et al. 2001 and DJ05; model.md section 5.1, pitfall 13).
pub fn fdr(eta: f64) -> f64 {
    if eta >= 1.0 {
        -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
    } else {
        -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta)
    }
}

/// `A(eta) = (1 + F_dr) / (1 - F_dr)`: internal-reflection parameter of the boundary (Jensen et al. 2001 eq. 6).
pub fn internal_reflection_a(eta: f64) -> f64 {
    let f = fdr(eta);
    (1.0 + f) / (1.0 - f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// model.md section 5.1 examples.
    #[test]
    fn spec_values() {
        assert!((fdr(1.4) - 0.52949).abs() < 5e-5);
        assert!((internal_reflection_a(1.4) - 3.2507).abs() < 5e-4);
        assert!((fdr(1.0) - 0.0016).abs() < 1e-4);
        assert!((internal_reflection_a(1.0) - 1.0032).abs() < 2e-4);
        // pitfall 13: eta = 1/1.4 would give 0.078
        assert!((fdr(1.0 / 1.4) - 0.078).abs() < 2e-3);
    }
}
