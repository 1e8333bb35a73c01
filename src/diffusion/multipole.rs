//! The multipole model of one slab (Donner & Jensen 2005) and its semi-infinite limit, the dipole (Jensen et al. 2001),
//! in real space and in closed form in the Hankel (2-D Fourier) domain (docs/model.md, section Multipole).
//!
//! Conventions: z points into the slab from its entry face; the 2-D transform is F(s) = 2 pi int_0^inf f(r) J0(s r) r dr,
//! so F(0) is the total (hemispherical) reflectance or transmittance per unit flux entering the slab.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::boundary::internal_reflection_a;
use crate::numeric::expm1_ratio;

/// How many image-source pairs the multipole sums.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MultipoleTerms {
    /// The whole infinite series: in the Hankel domain the images form geometric series, summed in closed form.
    All,
    /// The pairs i = -n..=n of DJ05 eq. 8 (YW uses n = 5, the spec's reference numbers n = 10).
    Pairs(u32),
}

/// Cap on image pairs for real-space sums of the whole series (reached only for near-zero absorption).
const MAX_REAL_SPACE_PAIRS: i64 = 20_000;
/// Relative size of an image pair below which the real-space series is considered converged.
const REAL_SPACE_TOLERANCE: f64 = 1e-13;

/// One homogeneous slab between two boundaries, reduced to the quantities the multipole needs (docs/model.md, section Multipole).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slab {
    /// `d`: thickness, mm (`f64::INFINITY` for a semi-infinite medium).
    pub thickness_mm: f64,
    /// `alpha'`: reduced single-scattering albedo, sigma_s' / sigma_t'.
    pub alpha_prime: f64,
    /// `sigma_tr = sqrt(3 sigma_a sigma_t')`: effective transport coefficient, mm^-1.
    pub sigma_tr_per_mm: f64,
    /// `l`: depth of the real source, mm: one reduced mean free path 1/sigma_t' (see `Slab::new` for thin slabs).
    pub source_depth_mm: f64,
    /// `b`: fraction of the light entering the slab that crosses it without interacting (0 unless the slab is
    /// thinner than one reduced mean free path; see `Slab::new`). The multipole carries the other 1 - b.
    pub ballistic_fraction: f64,
    /// `z_b,0 = 2 A(eta_top) D`: extrapolation distance above the entry face, mm.
    pub zb_top_mm: f64,
    /// `z_b,d = 2 A(eta_bottom) D`: extrapolation distance below the far face, mm.
    pub zb_bottom_mm: f64,
}

impl Slab {
    /// A slab with absorption and reduced scattering in mm^-1, thickness in mm and the relative indices
    /// (n_inside / n_outside) of its entry face and of its far face. Callers validate the inputs (see `layered`).
    ///
    /// Thin slabs (optical thickness tau = sigma_t' d < 1). DJ05 places all light entering a slab at one source, a
    /// reduced mean free path deep; in a slab thinner than that the source would lie at or past the far face, and a
    /// vanishing slab would still reflect a fixed share (its extrapolated boundaries do not vanish with it). Below
    /// tau = 1 a share b = (1 - tau)^2 of the light crosses the slab without interacting, and the multipole carries the
    /// rest with its source at l = d (1 + tau) / 2, mid-slab as tau -> 0. Both meet DJ05 at tau = 1 with matching
    /// slope in b (b = 0, l = 1/sigma_t' = d), so nothing changes for tau >= 1; as d -> 0, R -> 0 and T -> 1 (a
    /// vanishing layer vanishes). 1 - b = tau (2 - tau) is the diffuse-light interaction probability 1 - 2 E3(tau) to
    /// first order (light crossing a slab diffusely travels 2 d on average).
    pub fn new(
        sigma_a_per_mm: f64,
        sigma_s_reduced_per_mm: f64,
        thickness_mm: f64,
        eta_top: f64,
        eta_bottom: f64,
    ) -> Slab {
        let sigma_t_reduced = sigma_a_per_mm + sigma_s_reduced_per_mm;
        let diffusion_mm = 1.0 / (3.0 * sigma_t_reduced); // D = 1/(3 sigma_t'), Jensen et al. 2001
        let ballistic_fraction = ballistic_fraction(sigma_a_per_mm, sigma_s_reduced_per_mm, thickness_mm);
        let tau = sigma_t_reduced * thickness_mm;
        let source_depth_mm = if tau < 1.0 { 0.5 * thickness_mm * (1.0 + tau) } else { 1.0 / sigma_t_reduced };
        Slab {
            thickness_mm,
            alpha_prime: sigma_s_reduced_per_mm / sigma_t_reduced,
            sigma_tr_per_mm: (3.0 * sigma_a_per_mm * sigma_t_reduced).sqrt(),
            source_depth_mm,
            ballistic_fraction,
            zb_top_mm: 2.0 * internal_reflection_a(eta_top) * diffusion_mm,
            zb_bottom_mm: 2.0 * internal_reflection_a(eta_bottom) * diffusion_mm,
        }
    }

    /// The slab with each extrapolation distance capped at the thickness plus the other one: z_b,0 <= d + z_b,d and
    /// z_b,d <= d + z_b,0 (at most one cap acts; none for a semi-infinite slab). Unchanged, bit for bit, where neither
    /// cap acts, and continuous across them (`layered::Boundaries::Capped` uses it).
    ///
    /// Why: the multipole is the Green's function G of the slab extended to Dirichlet planes z_b,0 above its entry face
    /// and z_b,d below its far face (L = d + z_b,0 + z_b,d), and the reflectance is the flux D dG/dz at the real face
    /// z = 0. By moving planes, dG/dz >= 0 at every r on every plane between the upper Dirichlet plane and both the
    /// source (depth l > 0) and the extended slab's mid-plane: on the upper side of such a plane, G's mirror image
    /// about it is >= G (maximum principle: the difference has only the mirrored source there and is >= 0 on the
    /// boundary, as the mirror of the upper side stays inside the extended slab), so G rises through the plane. The
    /// face z = 0 is one iff z_b,0 <= d + z_b,d; the far face likewise iff z_b,d <= d + z_b,0 (l <= d). So with the caps
    /// R(r) >= 0 and T(r) >= 0 from either side, for the whole image series (`MultipoleTerms::All`; a truncated sum of
    /// pairs is not the Green's function) and for the thin-slab source l = d (1 + tau) / 2 in (d/2, d]. Beyond a cap
    /// the fundamental mode sin(pi (z + z_b,0) / L) peaks above the face and the flux through it turns inward at r of
    /// the order of L: R(r), and T(r) entered from below, have negative far tails (leading term ~ cos(pi z_b,0 / L)).
    pub fn capped(self) -> Slab {
        let (top, bottom, d) = (self.zb_top_mm, self.zb_bottom_mm, self.thickness_mm);
        Slab { zb_top_mm: top.min(d + bottom), zb_bottom_mm: bottom.min(d + top), ..self }
    }

    /// The share of the entering light the multipole carries, 1 - b (computed without cancellation).
    fn scattered_fraction(&self) -> f64 {
        let b = self.ballistic_fraction;
        if b == 0.0 {
            return 1.0;
        }
        let one_minus_sqrt_b = 1.0 - b.sqrt(); // tau
        one_minus_sqrt_b * (2.0 - one_minus_sqrt_b)
    }

    /// The same slab entered from its far face (boundaries swapped), for R-, T- of the layer combination.
    pub fn flipped(&self) -> Slab {
        Slab { zb_top_mm: self.zb_bottom_mm, zb_bottom_mm: self.zb_top_mm, ..*self }
    }

    fn is_semi_infinite(&self) -> bool {
        self.thickness_mm.is_infinite()
    }

    /// Half the image period, `L = d + z_b,0 + z_b,d` (the images repeat every 2L).
    fn half_period_mm(&self) -> f64 {
        self.thickness_mm + self.zb_top_mm + self.zb_bottom_mm
    }

    /// `q = sqrt(sigma_tr^2 + s^2)`, the decay rate of every image term at spatial frequency s (mm^-1).
    fn q(&self, s_per_mm: f64) -> f64 {
        // Plain sqrt, not hypot: both terms are far from overflow, and this is the hottest line of the table build.
        (self.sigma_tr_per_mm * self.sigma_tr_per_mm + s_per_mm * s_per_mm).sqrt()
    }

    /// Depths of the real and virtual source of image pair i (DJ05; docs/model.md, Multipole), measured from the entry face.
    fn image_depths_mm(&self, i: i64) -> (f64, f64) {
        let shift = if i == 0 { 0.0 } else { 2.0 * i as f64 * self.half_period_mm() };
        let l = self.source_depth_mm;
        (shift + l, shift - l - 2.0 * self.zb_top_mm)
    }

    /// `R~(s)`: Hankel transform of the reflectance profile (docs/model.md, Multipole). `R~(0)` is the total diffuse reflectance.
    pub fn reflectance_hat(&self, s_per_mm: f64, terms: MultipoleTerms) -> f64 {
        self.scattered_fraction() * self.multipole_reflectance_hat(s_per_mm, terms)
    }

    /// `R~(s)` of the multipole alone, per unit light it carries.
    fn multipole_reflectance_hat(&self, s_per_mm: f64, terms: MultipoleTerms) -> f64 {
        let q = self.q(s_per_mm);
        let (l, zb0) = (self.source_depth_mm, self.zb_top_mm);
        // The dipole i = 0: real source at l, negative virtual source at -(l + 2 z_b,0).
        let dipole = (-l * q).exp() + (-(l + 2.0 * zb0) * q).exp();
        if self.is_semi_infinite() {
            return 0.5 * self.alpha_prime * dipole;
        }
        match terms {
            MultipoleTerms::All => self.closed_form(q, zb0, self.zb_bottom_mm).0,
            MultipoleTerms::Pairs(n) => {
                let images: f64 = (1..=n as i64)
                    .flat_map(|i| [i, -i])
                    .map(|i| {
                        let (zr, zv) = self.image_depths_mm(i);
                        signed_exp(zr, q) - signed_exp(zv, q)
                    })
                    .sum();
                0.5 * self.alpha_prime * (dipole + images)
            }
        }
    }

    /// `T~(s)`: Hankel transform of the transmittance profile through the far face (docs/model.md, Multipole); 0 if semi-infinite.
    /// The light crossing without interacting adds b at every s (a point at r = 0).
    pub fn transmittance_hat(&self, s_per_mm: f64, terms: MultipoleTerms) -> f64 {
        if self.is_semi_infinite() {
            return 0.0;
        }
        self.ballistic_fraction + self.scattered_fraction() * self.multipole_transmittance_hat(s_per_mm, terms)
    }

    /// `T~(s)` of the multipole alone, per unit light it carries.
    fn multipole_transmittance_hat(&self, s_per_mm: f64, terms: MultipoleTerms) -> f64 {
        let q = self.q(s_per_mm);
        let d = self.thickness_mm;
        match terms {
            MultipoleTerms::All => self.closed_form(q, self.zb_top_mm, self.zb_bottom_mm).1,
            MultipoleTerms::Pairs(n) => {
                let n = n as i64;
                let sum: f64 = (-n..=n)
                    .map(|i| {
                        let (zr, zv) = self.image_depths_mm(i);
                        signed_exp(d - zr, q) - signed_exp(d - zv, q)
                    })
                    .sum();
                0.5 * self.alpha_prime * sum
            }
        }
    }

    /// `[R~+, T~+, R~-, T~-](s)`: the slab's transforms entered from its top and from its bottom at once, sharing every
    /// exponential the four have in common (half the work of four separate calls; the hot path of the layer adding).
    pub fn hats_both_ways(&self, s_per_mm: f64, terms: MultipoleTerms) -> [f64; 4] {
        if self.is_semi_infinite() || terms != MultipoleTerms::All {
            let up = self.flipped();
            return [
                self.reflectance_hat(s_per_mm, terms),
                self.transmittance_hat(s_per_mm, terms),
                up.reflectance_hat(s_per_mm, terms),
                up.transmittance_hat(s_per_mm, terms),
            ];
        }
        let q = self.q(s_per_mm);
        let (r_down, t_down) = self.closed_form(q, self.zb_top_mm, self.zb_bottom_mm);
        let (r_up, t_up) = self.closed_form(q, self.zb_bottom_mm, self.zb_top_mm);
        let (w, b) = (self.scattered_fraction(), self.ballistic_fraction);
        [w * r_down, b + w * t_down, w * r_up, b + w * t_up]
    }

    /// `(R~, T~)` of a finite slab for the whole image series at decay rate q, entered through the face whose
    /// extrapolation distance is `z_in` (the far face's is `z_out`). The images i >= 1 and i <= -1 form geometric
    /// series in x = e^(-2Lq), summed with E(a, b) = (1 - e^(-aq)) / (1 - e^(-bq)) (docs/model.md, Multipole):
    ///   R~ = alpha'/2 [e^(-lq) + e^(-(l+2z_in)q) - e^(-(2L-l)q) E(2l, 2L) - e^(-(2L-l-2z_in)q) E(2l+4z_in, 2L)]
    ///   T~ = alpha'/2 E(2l+2z_in, 2L) [e^(-(d-l)q) + e^(-(d-l+2z_out)q)]
    fn closed_form(&self, q: f64, z_in: f64, z_out: f64) -> (f64, f64) {
        let (d, l) = (self.thickness_mm, self.source_depth_mm);
        let two_l = 2.0 * self.half_period_mm();
        let e_l = (-l * q).exp();
        let e_far = (-(d - l) * q).exp();
        let r = e_l + e_l * (-2.0 * z_in * q).exp()
            - (-(two_l - l) * q).exp() * expm1_ratio(2.0 * l, two_l, q)
            - (-(two_l - l - 2.0 * z_in) * q).exp() * expm1_ratio(2.0 * l + 4.0 * z_in, two_l, q);
        let t = expm1_ratio(2.0 * l + 2.0 * z_in, two_l, q) * (e_far + e_far * (-2.0 * z_out * q).exp());
        (0.5 * self.alpha_prime * r, 0.5 * self.alpha_prime * t)
    }

    /// `R(r)`: reflectance profile at distance r (mm) from the point of entry, mm^-2 (DJ05 eq. 8; Jensen 2001 for d = inf).
    pub fn reflectance(&self, r_mm: f64, terms: MultipoleTerms) -> f64 {
        self.scattered_fraction()
            * self.real_space_sum(terms, |zr, zv| {
                pole(zr, r_mm, self.sigma_tr_per_mm) - pole(zv, r_mm, self.sigma_tr_per_mm)
            })
    }

    /// `T(r)`: transmittance profile through the far face at distance r (mm), mm^-2; 0 if semi-infinite.
    /// The light crossing a thin slab without interacting is a point mass at r = 0 that no point value can carry; it
    /// is present in `transmittance_hat`.
    pub fn transmittance(&self, r_mm: f64, terms: MultipoleTerms) -> f64 {
        if self.is_semi_infinite() {
            return 0.0;
        }
        let d = self.thickness_mm;
        let s = self.sigma_tr_per_mm;
        self.scattered_fraction() * self.real_space_sum(terms, |zr, zv| pole(d - zr, r_mm, s) - pole(d - zv, r_mm, s))
    }

    /// alpha'/(4 pi) times the sum over image pairs of `pair(z_r,i, z_v,i)`: pairs i = -n..=n, or, for the whole
    /// series, pairs until they stop contributing.
    fn real_space_sum(&self, terms: MultipoleTerms, pair: impl Fn(f64, f64) -> f64) -> f64 {
        let term = |i: i64| {
            let (zr, zv) = self.image_depths_mm(i);
            pair(zr, zv)
        };
        let mut sum = term(0);
        if !self.is_semi_infinite() {
            let (max_pairs, adaptive) = match terms {
                MultipoleTerms::All => (MAX_REAL_SPACE_PAIRS, true),
                MultipoleTerms::Pairs(n) => (n as i64, false),
            };
            let mut magnitude = sum.abs();
            for i in 1..=max_pairs {
                let add = term(i) + term(-i);
                sum += add;
                magnitude += add.abs();
                if adaptive && add.abs() <= REAL_SPACE_TOLERANCE * magnitude {
                    break;
                }
            }
        }
        self.alpha_prime / (4.0 * PI) * sum
    }
}

/// `b`, the share of light entering a slab that crosses it without interacting: (1 - tau)^2 below an optical
/// thickness tau = sigma_t' d of 1, else 0 (see `Slab::new`).
pub fn ballistic_fraction(sigma_a_per_mm: f64, sigma_s_reduced_per_mm: f64, thickness_mm: f64) -> f64 {
    let tau = (sigma_a_per_mm + sigma_s_reduced_per_mm) * thickness_mm;
    if tau < 1.0 {
        (1.0 - tau) * (1.0 - tau)
    } else {
        0.0
    }
}

/// `sign(z) e^(-|z| q)`, with sign(0) = +1 (the limit from inside the slab).
fn signed_exp(z: f64, q: f64) -> f64 {
    let e = (-z.abs() * q).exp();
    if z < 0.0 {
        -e
    } else {
        e
    }
}

/// One image source seen at distance r on the surface: `z (1 + sigma_tr rho) e^(-sigma_tr rho) / rho^3`,
/// rho = sqrt(r^2 + z^2) (the flux term of Jensen et al. 2001 eq. 4). Zero where rho = 0 (a point mass, see `transmittance`).
fn pole(z_mm: f64, r_mm: f64, sigma_tr_per_mm: f64) -> f64 {
    let rho = r_mm.hypot(z_mm);
    if rho == 0.0 {
        return 0.0;
    }
    z_mm * (1.0 + sigma_tr_per_mm * rho) * (-sigma_tr_per_mm * rho).exp() / (rho * rho * rho)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn epidermis_550() -> Slab {
        // Caucasian epidermis at 550 nm (docs/model.md, Reference numbers): sigma_a = 0.26062, sigma_s' = 6.0823.
        Slab::new(0.26062, 6.0823, 0.25, 1.4, 1.0)
    }

    /// Independently computed derived quantities (docs/model.md, Reference numbers).
    #[test]
    fn derived_quantities() {
        let s = epidermis_550();
        assert!((s.alpha_prime - 0.95891).abs() < 2e-5, "alpha' = {}", s.alpha_prime);
        assert!((s.sigma_tr_per_mm - 2.22694).abs() < 2e-4, "sigma_tr = {}", s.sigma_tr_per_mm);
        assert!((s.source_depth_mm - 0.15766).abs() < 2e-5, "source depth = {}", s.source_depth_mm);
        assert!((s.zb_top_mm - 0.34166).abs() < 2e-4, "zb_top = {}", s.zb_top_mm);
        assert!((s.zb_bottom_mm - 0.10544).abs() < 2e-4, "zb_bottom = {}", s.zb_bottom_mm);
    }

    /// docs/model.md, Adding layers: R1+ = 0.252, T1+ = 0.592, R1- = 0.491, T1- = 0.344 at 550 nm, Caucasian.
    #[test]
    fn directional_layer_totals() {
        let s = epidermis_550();
        let t = MultipoleTerms::All;
        assert!((s.reflectance_hat(0.0, t) - 0.252).abs() < 1e-3, "R1+ = {}", s.reflectance_hat(0.0, t));
        assert!((s.transmittance_hat(0.0, t) - 0.592).abs() < 1e-3, "T1+ = {}", s.transmittance_hat(0.0, t));
        assert!(
            (s.flipped().reflectance_hat(0.0, t) - 0.491).abs() < 1e-3,
            "R1- = {}",
            s.flipped().reflectance_hat(0.0, t)
        );
        assert!(
            (s.flipped().transmittance_hat(0.0, t) - 0.344).abs() < 1e-3,
            "T1- = {}",
            s.flipped().transmittance_hat(0.0, t)
        );
    }

    /// The closed-form series equals the explicit sum of many pairs.
    #[test]
    fn closed_form_series_equals_explicit_sum() {
        for slab in [epidermis_550(), Slab::new(0.01, 1.0, 0.5, 1.4, 1.3), Slab::new(2.0, 0.5, 0.05, 1.0, 1.4)] {
            for s in [0.0, 0.3, 2.0, 17.0] {
                for f in [Slab::reflectance_hat, Slab::transmittance_hat] {
                    let all = f(&slab, s, MultipoleTerms::All);
                    let sum = f(&slab, s, MultipoleTerms::Pairs(400));
                    assert!((all - sum).abs() < 1e-12 * all.abs().max(1e-3), "s={s}: {all} vs {sum}");
                }
            }
        }
    }

    /// The shared-exponential evaluation equals the four separate transforms.
    #[test]
    fn hats_both_ways_equal_separate_calls() {
        for slab in [epidermis_550(), Slab::new(0.01, 1.0, 0.5, 1.4, 1.3), Slab::new(0.0, 3.0, 0.4, 1.4, 1.0)] {
            for s in [0.0, 0.3, 2.0, 17.0, 3000.0] {
                let t = MultipoleTerms::All;
                let up = slab.flipped();
                let separate = [
                    slab.reflectance_hat(s, t),
                    slab.transmittance_hat(s, t),
                    up.reflectance_hat(s, t),
                    up.transmittance_hat(s, t),
                ];
                let shared = slab.hats_both_ways(s, t);
                for k in 0..4 {
                    assert!(
                        (shared[k] - separate[k]).abs() <= 1e-14 * separate[k].abs().max(1e-300),
                        "{k} s={s}: {shared:?} {separate:?}"
                    );
                }
            }
        }
    }

    /// Without absorption, everything that enters leaves: R + T = alpha' = 1, and R is the linear-flux result.
    #[test]
    fn non_absorbing_slab_conserves_energy() {
        let slab = Slab::new(0.0, 3.0, 0.4, 1.4, 1.0);
        let r = slab.reflectance_hat(0.0, MultipoleTerms::All);
        let t = slab.transmittance_hat(0.0, MultipoleTerms::All);
        assert!((r + t - 1.0).abs() < 1e-14, "{r} + {t}");
        let (l, zb0, zbd, d) = (slab.source_depth_mm, slab.zb_top_mm, slab.zb_bottom_mm, slab.thickness_mm);
        assert!((r - (d + zbd - l) / (d + zb0 + zbd)).abs() < 1e-14, "{r} vs {}", (d + zbd - l) / (d + zb0 + zbd));
    }

    /// The semi-infinite total is Jensen et al. 2001's closed form.
    #[test]
    fn dipole_total_matches_jensen_2001() {
        for (sa, ss) in [(0.01, 1.0), (0.2, 6.0), (5.0, 1.0)] {
            let slab = Slab::new(sa, ss, f64::INFINITY, 1.4, 1.0);
            let ap: f64 = ss / (sa + ss);
            let a = internal_reflection_a(1.4);
            let root = (3.0 * (1.0 - ap)).sqrt();
            let jensen = 0.5 * ap * (1.0 + (-(4.0 / 3.0) * a * root).exp()) * (-root).exp();
            assert!(
                (slab.reflectance_hat(0.0, MultipoleTerms::All) - jensen).abs() < 1e-14,
                "sigma_a {sa} sigma_s' {ss}: {} vs {jensen}",
                slab.reflectance_hat(0.0, MultipoleTerms::All)
            );
        }
    }

    /// The thin-slab guard is continuous across l = d and keeps energy bounded.
    #[test]
    fn thin_slab_guard_is_continuous() {
        let d = 0.25;
        let at = |ss: f64| {
            let slab = Slab::new(0.1, ss, d, 1.4, 1.0);
            (slab.reflectance_hat(0.0, MultipoleTerms::All), slab.transmittance_hat(0.0, MultipoleTerms::All))
        };
        let sigma_t_at_cap = 1.0 / d;
        let (r_lo, t_lo) = at(sigma_t_at_cap - 0.1 - 1e-9);
        let (r_hi, t_hi) = at(sigma_t_at_cap - 0.1 + 1e-9);
        assert!((r_lo - r_hi).abs() < 1e-7 && (t_lo - t_hi).abs() < 1e-7, "R {r_lo} vs {r_hi}, T {t_lo} vs {t_hi}");
        for ss in [1e-6, 0.01, 0.5, 3.0, 3.9, 4.0, 100.0] {
            let (r, t) = at(ss);
            assert!(r.is_finite() && t.is_finite() && r >= 0.0 && t >= 0.0 && r + t <= 1.0, "ss={ss}: {r} {t}");
        }
    }
}
