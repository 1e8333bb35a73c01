//! Exact total reflectance of a layered slab: the adding-doubling solution of the radiative transfer equation
//! (Prahl, "The adding-doubling method", 1995; docs/model.md, section Exact transport).
//!
//! Light is carried in `n` streams per hemisphere (quadrature directions with cosines `nu_i`). A layer is a pair of
//! operators on the streams' fluxes: `R` (flux reflected into each upward stream per unit flux in each downward
//! stream) and `T`. A layer thin enough for single-step differencing starts from the diamond-difference solution
//! (Wiscombe 1976); doubling gives twice the thickness; adding stacks two layers; the Fresnel boundary at the top
//! reflects each upward stream by its Fresnel reflectance (totally below the critical cosine). In flux form these are
//! ordinary matrix products, so the operators of this module are plain `n x n` matrices.

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, OnceLock};

use super::matrix::Matrix;
use crate::error::SkinError;
use crate::layer::Layer;
use crate::surface::oil_layer::fresnel_dielectric;

/// Streams (quadrature directions per hemisphere) of the default accuracy level. docs/accuracy-vs-time.md: 8
/// streams put every Monte Carlo check within 0.6 %, always above it; 16 within 0.14 %.
pub const DEFAULT_STREAMS: usize = 10;
/// Stream counts accepted (even, the quadrature's rule). Not 2: one stream on each side of the critical angle erred
/// by 12-47 % for every index above 1 (15 % at skin's 1.4; issue 38).
pub const STREAMS_RANGE: (usize, usize) = (4, 64);
/// A thin layer starts at an optical thickness no larger than this fraction of the smallest stream cosine (Prahl
/// 1995 uses the whole cosine). With the extrapolated start ([`extrapolated_thin_layer`]) a layer cut anywhere then
/// gives the whole layer's total within 1e-10 (tests/physics/transport_properties.rs; at half the cosine, up to 1.2e-10).
const START_FRACTION_OF_NU_MIN: f64 = 0.25;
/// A semi-infinite layer is doubled until no element of its reflection operator changes by more than this.
const SEMI_INFINITE_TOLERANCE: f64 = 1e-13;
/// ... or until its optical thickness passes this (a non-absorbing layer converges like 1/tau and its doubling grows
/// ill-conditioned with tau: 1e9 leaves about 1e-9 either way).
const SEMI_INFINITE_MAX_OPTICAL_THICKNESS: f64 = 1e9;

/// One homogeneous layer in optical units: single-scattering albedo, optical thickness (infinite for a semi-infinite
/// layer) and Henyey-Greenstein asymmetry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpticalSlab {
    pub albedo: f64,
    pub optical_thickness: f64,
    pub g: f64,
}

impl OpticalSlab {
    /// The model's layer: isotropic scattering with the reduced coefficient (the model's optics are reduced
    /// coefficients, so the similarity relation sigma_s' = sigma_s (1 - g) with g = 0 is the transport it describes).
    pub fn of_layer(layer: &Layer) -> OpticalSlab {
        let sigma_t_per_mm = layer.sigma_a_per_mm + layer.sigma_s_reduced_per_mm;
        OpticalSlab {
            albedo: layer.sigma_s_reduced_per_mm / sigma_t_per_mm,
            optical_thickness: sigma_t_per_mm * layer.thickness_mm,
            g: 0.0,
        }
    }
}

/// The total diffuse reflectance of `layers` (top to bottom, under air; the last may be semi-infinite; a finite last
/// layer rests on a non-scattering medium of its own index, as in the diffusion model) for a normally incident beam,
/// per unit power refracted into the top layer: the same quantity as the multipole's R(k = 0). Scattering is
/// isotropic with the reduced coefficient. Every layer must have the same index of refraction (the streams are the
/// same directions in every layer; internal index steps would need refraction between stream sets): a stack with
/// index steps is refused, naming the layers (`transport="diffusion"` takes it).
pub fn total_diffuse_reflectance(layers: &[Layer], streams: usize) -> Result<f64, SkinError> {
    total_diffuse_reflectance_cancellable(layers, streams, &AtomicBool::new(false))
}

/// [`total_diffuse_reflectance`] that stops once `cancel` is set (read before each layer's operators: at 64 streams a
/// layer is a few tens of milliseconds), with [`SkinError::interrupted`].
pub fn total_diffuse_reflectance_cancellable(
    layers: &[Layer],
    streams: usize,
    cancel: &AtomicBool,
) -> Result<f64, SkinError> {
    crate::layer::validate_layers(layers)?;
    let ior = layers[0].ior;
    if let Some((i, l)) = layers.iter().enumerate().find(|(_, l)| l.ior != ior) {
        return Err(SkinError::invalid(
            format!("layer {i}"),
            format!(
                "adding-doubling transport needs one index of refraction for every layer; layer 0 has {ior}, layer \
                 {i} has {} (use transport \"diffusion\" for stacks with index steps)",
                l.ior
            ),
        ));
    }
    let slabs: Vec<OpticalSlab> = layers.iter().map(OpticalSlab::of_layer).collect();
    slab_reflectance_cancellable(&slabs, ior, streams, cancel)
}

/// The total reflectance of a stack of optical slabs of index `ior` under air (a finite last slab over a medium of
/// the same index), normal incidence, per unit refracted power; `streams` quadrature directions per hemisphere.
pub fn slab_reflectance(slabs: &[OpticalSlab], ior: f64, streams: usize) -> Result<f64, SkinError> {
    slab_reflectance_cancellable(slabs, ior, streams, &AtomicBool::new(false))
}

/// [`slab_reflectance`] that stops once `cancel` is set (read before each slab's operators).
pub fn slab_reflectance_cancellable(
    slabs: &[OpticalSlab],
    ior: f64,
    streams: usize,
    cancel: &AtomicBool,
) -> Result<f64, SkinError> {
    validate_streams(streams)?;
    if slabs.is_empty() {
        return Err(SkinError::invalid("layers", "need at least one layer"));
    }
    let (upper, last) = slabs.split_at(slabs.len() - 1);
    with_quadrature(streams, ior, |q| {
        let above = UpperSystem::cached(q, upper, ior, cancel)?;
        SkinError::check_cancel(cancel, "adding-doubling transport")?;
        Ok(above.total_over(&Operators::of_slab(q, &last[0]).r_down))
    })
}

/// Reflection operators of semi-infinite isotropic layers, one per albedo, at one quadrature (index and streams): the
/// last layers that a table of totals puts under many upper stacks ([`totals_over_semi_infinite`];
/// `transport::total_table`), each doubled once.
#[derive(Debug)]
pub struct SemiInfiniteLayers {
    streams: usize,
    ior: f64,
    reflection: Vec<Matrix>,
}

impl SemiInfiniteLayers {
    /// The layers of single-scattering albedo `albedos` (each in [0, 1]) under index `ior`, in `streams` streams.
    pub fn new(albedos: &[f64], ior: f64, streams: usize) -> Result<SemiInfiniteLayers, SkinError> {
        validate_streams(streams)?;
        if let Some(a) = albedos.iter().find(|a| !(0.0..=1.0).contains(*a)) {
            return Err(SkinError::invalid("albedos", format!("each albedo must be in [0, 1]; got {a}")));
        }
        let reflection = with_quadrature(streams, ior, |q| {
            albedos
                .iter()
                .map(|&albedo| {
                    Operators::of_slab(q, &OpticalSlab { albedo, optical_thickness: f64::INFINITY, g: 0.0 }).r_down
                })
                .collect()
        });
        Ok(SemiInfiniteLayers { streams, ior, reflection })
    }
}

/// The total reflectance (as [`slab_reflectance`]) of `upper` over each of `lower`'s semi-infinite layers, in
/// `lower`'s order: the upper stack's operators computed once for all of them.
pub fn totals_over_semi_infinite(upper: &[OpticalSlab], lower: &SemiInfiniteLayers) -> Result<Vec<f64>, SkinError> {
    let never = AtomicBool::new(false);
    with_quadrature(lower.streams, lower.ior, |q| {
        let above = UpperSystem::of(q, upper, &never)?;
        Ok(lower.reflection.iter().map(|r| above.total_over(r)).collect())
    })
}

/// What the top boundary and every layer above the last do to the light, seen from the last layer's top face: the
/// part of a stack that many evaluations share (a table varies the dermis's blood under one epidermis; a fit's
/// derivative in the blood keeps the epidermis), so it is kept per thread, keyed by those layers' bits.
#[derive(Debug)]
struct UpperSystem {
    /// Flux that leaves through the top without reaching the last layer (per unit refracted into the normal stream).
    escaped: f64,
    /// Downward flux per stream arriving at the last layer.
    down: Vec<f64>,
    /// Reflection of light arriving from below (from the last layer).
    r_from_below: Matrix,
    /// Share of each upward stream, arriving from below, that leaves through the top.
    escape_from_below: Vec<f64>,
}

/// Upper systems kept per thread before the cache is cleared (a table row of one epidermis over every wavelength
/// fits many times over).
const UPPER_CACHE_ENTRIES: usize = 1024;

impl UpperSystem {
    /// With `E` the upper layers' operators and `F` the streams' Fresnel reflectance under the boundary:
    /// `d = (I - F R_E)^-1 e_N` goes down at E's top, `(1 - F) . R_E d` escapes, `T_E d` reaches the last layer;
    /// from below, `R = R_E' + T_E (I - F R_E)^-1 F T_E'` and the escaping share is
    /// `(1 - F)^T (I - R_E F)^-1 T_E'` (primes: the operators for light from below). No upper layers: `d = e_N`,
    /// `R = F`, share `1 - F`.
    /// Stops once `cancel` is set (read before each layer's operators).
    fn of(q: &Quadrature, upper: &[OpticalSlab], cancel: &AtomicBool) -> Result<UpperSystem, SkinError> {
        let n = q.n();
        let normal: Vec<f64> = (0..n).map(|i| if i == n - 1 { 1.0 } else { 0.0 }).collect();
        let not_reflected: Vec<f64> = q.fresnel.iter().map(|f| 1.0 - f).collect();
        let mut combined: Option<Operators> = None;
        for slab in upper {
            SkinError::check_cancel(cancel, "adding-doubling transport")?;
            let below = Operators::of_slab(q, slab);
            combined = Some(match combined {
                Some(above) => above.add(&below),
                None => below,
            });
        }
        let Some(e) = combined else {
            return Ok(UpperSystem {
                escaped: 0.0,
                down: normal,
                r_from_below: Matrix::diagonal(&q.fresnel),
                escape_from_below: not_reflected,
            });
        };
        let i_minus_f_r = Matrix::identity(n).minus(&e.r_down.scale_rows(&q.fresnel));
        let d = i_minus_f_r.solve_vector(&normal);
        let escaped = dot(&not_reflected, &e.r_down.mul_vector(&d));
        let down = e.t_down.mul_vector(&d);
        let r_from_below = e.r_up.plus(&e.t_down.mul(&i_minus_f_r.solve(&e.t_up.scale_rows(&q.fresnel))));
        // (1 - F)^T (I - R_E F)^-1 T_E' = ((I - R_E F)^-T (1 - F))^T T_E', and (I - R_E F)^T = I - F R_E^T.
        let y = Matrix::identity(n).minus(&e.r_down.transpose().scale_rows(&q.fresnel)).solve_vector(&not_reflected);
        let escape_from_below = e.t_up.transpose().mul_vector(&y);
        Ok(UpperSystem { escaped, down, r_from_below, escape_from_below })
    }

    /// [`UpperSystem::of`], from this thread's cache when the same layers were seen before.
    fn cached(
        q: &Quadrature,
        upper: &[OpticalSlab],
        ior: f64,
        cancel: &AtomicBool,
    ) -> Result<Rc<UpperSystem>, SkinError> {
        thread_local! {
            static CACHE: RefCell<HashMap<Vec<u64>, Rc<UpperSystem>>> = RefCell::new(HashMap::new());
        }
        let mut key = vec![q.n() as u64, ior.to_bits()];
        key.extend(upper.iter().flat_map(|s| [s.albedo.to_bits(), s.optical_thickness.to_bits(), s.g.to_bits()]));
        CACHE.with(|cache| {
            if let Some(hit) = cache.borrow().get(&key) {
                return Ok(Rc::clone(hit));
            }
            let fresh = Rc::new(UpperSystem::of(q, upper, cancel)?);
            let mut cache = cache.borrow_mut();
            if cache.len() >= UPPER_CACHE_ENTRIES {
                cache.clear();
            }
            cache.insert(key, Rc::clone(&fresh));
            Ok(fresh)
        })
    }

    /// The total leaving through the top over a last layer that reflects `r_last` (from above): the flux going down
    /// onto it is `v = (I - R r_last)^-1 down`, and of what it sends back up, `escape_from_below` leaves.
    fn total_over(&self, r_last: &Matrix) -> f64 {
        let n = r_last.n();
        let v = Matrix::identity(n).minus(&self.r_from_below.mul(r_last)).solve_vector(&self.down);
        let total = self.escaped + dot(&self.escape_from_below, &r_last.mul_vector(&v));
        total.clamp(0.0, 1.0)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Reflection and transmission of the whole slab stack and their mirror images, as flux operators (see the module
/// doc). `down` operators act on light arriving from above, `up` on light arriving from below.
#[derive(Debug, Clone)]
struct Operators {
    r_down: Matrix,
    t_down: Matrix,
    r_up: Matrix,
    t_up: Matrix,
}

impl Operators {
    /// A homogeneous slab: a thin layer by diamond difference, doubled to the thickness (or until a semi-infinite
    /// slab no longer changes).
    fn of_slab(q: &Quadrature, slab: &OpticalSlab) -> Operators {
        if slab.optical_thickness.is_infinite() && slab.g == 0.0 {
            if let Some(r) = q.semi_infinite_isotropic(slab.albedo) {
                let zero = Matrix::zeros(q.n());
                return Operators { r_down: r.clone(), t_down: zero.clone(), r_up: r, t_up: zero };
            }
        }
        Operators::doubled(q, slab)
    }

    /// [`Operators::of_slab`] by doubling from a thin layer, whatever the slab.
    fn doubled(q: &Quadrature, slab: &OpticalSlab) -> Operators {
        let (albedo, tau, hpp, hpm) = delta_m(q, slab);
        let semi_infinite = tau.is_infinite();
        let start = START_FRACTION_OF_NU_MIN * q.nu[0];
        // Finite: dtau = tau / 2^k, the largest such that dtau <= start (so that a slab split in two halves starts
        // both halves from the same thin layer and doubles to the same operators).
        let (mut dtau, doublings) = if semi_infinite {
            (start, usize::MAX)
        } else {
            let mut k = 0usize;
            let mut d = tau;
            while d > start {
                d *= 0.5;
                k += 1;
            }
            (d, k)
        };
        let (mut r, mut t, mut absorbed) = extrapolated_thin_layer(q, albedo, dtau, &hpp, &hpm);
        let mut step = 0usize;
        while step < doublings {
            let (r2, t2) = double(&r, &t, &mut absorbed);
            let change = r2.max_abs_difference(&r);
            r = r2;
            t = t2;
            dtau *= 2.0;
            step += 1;
            if semi_infinite && (change < SEMI_INFINITE_TOLERANCE || dtau > SEMI_INFINITE_MAX_OPTICAL_THICKNESS) {
                t = Matrix::zeros(q.n());
                break;
            }
        }
        Operators { r_down: r.clone(), t_down: t.clone(), r_up: r, t_up: t }
    }

    /// This stack over `lower` (Prahl 1995, eqs. 2.62-2.65 in flux form):
    /// `T02 = T12 (I - R10 R12)^-1 T01`, `R02 = R01 + T10 R12 (I - R10 R12)^-1 T01`, and the mirror pair.
    fn add(&self, lower: &Operators) -> Operators {
        let n = self.r_down.n();
        // Light going down between the layers: (I - R10 R12)^-1 applied to what the upper layer lets down.
        let x_down = Matrix::identity(n).minus(&self.r_up.mul(&lower.r_down)).solve(&self.t_down);
        let t_down = lower.t_down.mul(&x_down);
        let r_down = self.r_down.plus(&self.t_up.mul(&lower.r_down.mul(&x_down)));
        // Light going up between the layers: (I - R12 R10)^-1 applied to what the lower layer lets up.
        let x_up = Matrix::identity(n).minus(&lower.r_down.mul(&self.r_up)).solve(&lower.t_up);
        let t_up = self.t_up.mul(&x_up);
        let r_up = lower.r_up.plus(&lower.t_down.mul(&self.r_up.mul(&x_up)));
        Operators { r_down, t_down, r_up, t_up }
    }
}

/// Delta-M scaling of a Henyey-Greenstein slab to the streams' Legendre order (Wiscombe 1977): the forward peak
/// `f = g^n` moves into the unscattered beam, giving the scaled albedo, optical thickness and the azimuth-averaged
/// redistribution matrices `h(nu_i, nu_j)` (`hpp`: same hemisphere, `hpm`: opposite), renormalised so that the
/// discrete scattering conserves energy (Prahl 1995, section 2.4.3).
fn delta_m(q: &Quadrature, slab: &OpticalSlab) -> (f64, f64, Matrix, Matrix) {
    let n = q.n();
    let g = slab.g;
    let f = if g == 0.0 { 0.0 } else { g.powi(n as i32) };
    let albedo = slab.albedo * (1.0 - f) / (1.0 - slab.albedo * f);
    let tau = slab.optical_thickness * (1.0 - slab.albedo * f);
    let mut hpp = Matrix::zeros(n);
    let mut hpm = Matrix::zeros(n);
    if g == 0.0 {
        hpp.fill(1.0);
        hpm.fill(1.0);
    } else {
        // h(mu, mu') = sum_l (2l + 1) chi_l P_l(mu) P_l(mu'), chi_l = (g^l - f) / (1 - f), l < n.
        let legendre = crate::numeric::legendre_table(n, &q.nu);
        for (l, p_l) in legendre.iter().enumerate() {
            let chi = (g.powi(l as i32) - f) / (1.0 - f);
            let c = (2 * l + 1) as f64 * chi;
            let sign = if l % 2 == 0 { 1.0 } else { -1.0 };
            for i in 0..n {
                for j in 0..n {
                    let pp = c * p_l[i] * p_l[j];
                    hpp[(i, j)] += pp;
                    hpm[(i, j)] += sign * pp;
                }
            }
        }
        // Energy: sum_i w_i (hpp_ij + hpm_ij) = 2 for every j, mended on the diagonal (hpp is symmetric).
        for j in 0..n {
            let sum: f64 = (0..n).map(|i| q.w[i] * (hpp[(i, j)] + hpm[(i, j)])).sum();
            hpp[(j, j)] += (2.0 - sum) / q.w[j];
        }
    }
    (albedo, tau, hpp, hpm)
}

/// Flux operators `(R, T)` of a thin homogeneous layer by diamond difference (Wiscombe 1976): the transfer equation
/// `nu dL/dtau = -L + (a/2) int h L` differenced across the layer with the mean of its two faces gives, with
/// `K = diag(nu) / dtau`, `B = (I - P) / 2`, `D = Q / 2`, `P = (a/2) hpp W`, `Q = (a/2) hpm W`, `G = K + B`:
/// `(G - D)(T + R) = K - B + D` and `(G + D)(T - R) = K - B - D` for the radiance operators, which the stream
/// fluxes `c_i = 2 nu_i w_i` turn into flux operators `c R c^-1`.
fn thin_layer(q: &Quadrature, albedo: f64, dtau: f64, hpp: &Matrix, hpm: &Matrix) -> (Matrix, Matrix) {
    let n = q.n();
    let half_a = 0.5 * albedo;
    let mut b = Matrix::zeros(n);
    let mut d = Matrix::zeros(n);
    for i in 0..n {
        for j in 0..n {
            b[(i, j)] = -0.5 * half_a * hpp[(i, j)] * q.w[j];
            d[(i, j)] = 0.5 * half_a * hpm[(i, j)] * q.w[j];
        }
        b[(i, i)] += 0.5;
    }
    let mut g_minus_d = Matrix::zeros(n);
    let mut g_plus_d = Matrix::zeros(n);
    let mut sum_rhs = Matrix::zeros(n);
    let mut diff_rhs = Matrix::zeros(n);
    for i in 0..n {
        for j in 0..n {
            let kij = if i == j { q.nu[i] / dtau } else { 0.0 };
            g_minus_d[(i, j)] = kij + b[(i, j)] - d[(i, j)];
            g_plus_d[(i, j)] = kij + b[(i, j)] + d[(i, j)];
            sum_rhs[(i, j)] = kij - b[(i, j)] + d[(i, j)];
            diff_rhs[(i, j)] = kij - b[(i, j)] - d[(i, j)];
        }
    }
    let t_plus_r = g_minus_d.solve(&sum_rhs);
    let t_minus_r = g_plus_d.solve(&diff_rhs);
    let mut r = Matrix::zeros(n);
    let mut t = Matrix::zeros(n);
    for i in 0..n {
        for j in 0..n {
            let flux = q.flux[i] / q.flux[j];
            r[(i, j)] = 0.5 * (t_plus_r[(i, j)] - t_minus_r[(i, j)]) * flux;
            t[(i, j)] = 0.5 * (t_plus_r[(i, j)] + t_minus_r[(i, j)]) * flux;
        }
    }
    (r, t)
}

/// The thin layer of optical thickness `dtau` from three diamond-difference layers, of `dtau`, of `dtau / 2` doubled
/// once and of `dtau / 4` doubled twice, extrapolated to zero step: the diamond scheme (a (1,1) Pade step) errs by
/// even powers of the step, so two Romberg eliminations leave an error of sixth order. Measured (8 streams): a layer
/// cut at a random place gave up to 7.6e-4 of the total apart with the plain start, 1.5e-6 with one elimination, and
/// within 1e-10 with two (and the start at a quarter of the smallest cosine).
fn extrapolated_thin_layer(
    q: &Quadrature,
    albedo: f64,
    dtau: f64,
    hpp: &Matrix,
    hpm: &Matrix,
) -> (Matrix, Matrix, Vec<f64>) {
    // D(h) of the layer dtau in steps h: D(dtau), D(dtau/2) doubled once, D(dtau/4) doubled twice.
    let (r1, t1) = thin_layer(q, albedo, dtau, hpp, hpm);
    let a1 = thin_layer_absorbed(q, albedo, dtau, &r1, &t1);
    let (rq, tq) = thin_layer(q, albedo, 0.25 * dtau, hpp, hpm);
    let mut a4 = thin_layer_absorbed(q, albedo, 0.25 * dtau, &rq, &tq);
    let (rh, th) = double(&rq, &tq, &mut a4);
    let (r4, t4) = double(&rh, &th, &mut a4);
    let (rh, th) = thin_layer(q, albedo, 0.5 * dtau, hpp, hpm);
    let mut a2 = thin_layer_absorbed(q, albedo, 0.5 * dtau, &rh, &th);
    let (r2, t2) = double(&rh, &th, &mut a2);
    // Romberg: errors c2 h^2 + c4 h^4 + ...; two eliminations leave O(h^6).
    let romberg = |coarse: &Matrix, middle: &Matrix, fine: &Matrix| {
        let mut first = middle.clone();
        first.add_scaled(&middle.minus(coarse), 1.0 / 3.0);
        let mut second = fine.clone();
        second.add_scaled(&fine.minus(middle), 1.0 / 3.0);
        let mut m = second.clone();
        m.add_scaled(&second.minus(&first), 1.0 / 15.0);
        m
    };
    // The absorbed flux is linear in the operators (1 - column sums), so it extrapolates with the same weights.
    let absorbed = (0..q.n())
        .map(|j| {
            let first = a2[j] + (a2[j] - a1[j]) / 3.0;
            let second = a4[j] + (a4[j] - a2[j]) / 3.0;
            second + (second - first) / 15.0
        })
        .collect();
    (romberg(&r1, &r2, &r4), romberg(&t1, &t2, &t4), absorbed)
}

/// The flux a diamond-difference layer absorbs per unit flux arriving in stream `j`: the scheme's own balance,
/// `(1 - a) dtau sum_i 2 w_i L_mid,i`, with each stream's radiance at mid-layer the mean of its two faces; in flux
/// terms `(1 - a) (dtau / 2) (1 / nu_j + sum_i (R_ij + T_ij) / nu_i)` (the redistribution matrices conserve energy,
/// `delta_m`). Proportional to `1 - a`, so exactly 0 without absorption and accurate however little there is, where
/// `1 - (column sums of R + T)` is round-off.
fn thin_layer_absorbed(q: &Quadrature, albedo: f64, dtau: f64, r: &Matrix, t: &Matrix) -> Vec<f64> {
    let n = q.n();
    (0..n)
        .map(|j| {
            let out: f64 = (0..n).map(|i| (r[(i, j)] + t[(i, j)]) / q.nu[i]).sum();
            (1.0 - albedo) * 0.5 * dtau * (1.0 / q.nu[j] + out)
        })
        .collect()
}

/// A homogeneous layer doubled, `R' = R + T R (I - R R)^-1 T`, `T' = T (I - R R)^-1 T` (the layer is the same from
/// both sides), keeping its energy balance: `absorbed` (the flux absorbed per unit flux arriving in each stream)
/// becomes `a' = a + a^T (I + R) (I - R R)^-1 T` (what each half absorbs of the light between them: non-negative
/// terms, as accurate as `a`), and each column of `R'` is scaled so that `R' + T'` returns the rest. Without the
/// balance the column sums of a thick, nearly non-absorbing layer drifted by each near-singular solve's round-off
/// (2.8e-6 of the flux at optical thickness 1e7): a spurious absorption that the later doublings multiplied, so that
/// its transmission went negative and a layer cut in two reflected up to 1.1e-3 less than whole (issue 38).
fn double(r: &Matrix, t: &Matrix, absorbed: &mut [f64]) -> (Matrix, Matrix) {
    let n = r.n();
    let z = Matrix::identity(n).minus(&r.mul(r)).solve(t);
    let t2 = t.mul(&z);
    let mut r2 = r.plus(&t.mul(r).mul(&z));
    let weights: Vec<f64> =
        (0..n).map(|k| absorbed[k] + (0..n).map(|i| absorbed[i] * r[(i, k)]).sum::<f64>()).collect();
    for (j, a) in absorbed.iter_mut().enumerate() {
        *a += (0..n).map(|k| weights[k] * z[(k, j)]).sum::<f64>().max(0.0);
        let reflected: f64 = (0..n).map(|i| r2[(i, j)]).sum();
        let transmitted: f64 = (0..n).map(|i| t2[(i, j)]).sum();
        let returned = 1.0 - *a - transmitted;
        if reflected > 0.0 && returned > 0.0 {
            let scale = returned / reflected;
            for i in 0..n {
                r2[(i, j)] *= scale;
            }
        }
    }
    (r2, t2)
}

/// The streams: cosines `nu` (ascending, the last = 1, where the refracted normal beam travels), weights `w` on
/// [0, 1] (sum 1), the flux factors `2 nu w` and each stream's internal Fresnel reflectance at the top boundary.
#[derive(Debug, Clone)]
struct Quadrature {
    streams: usize,
    nu: Vec<f64>,
    w: Vec<f64>,
    flux: Vec<f64>,
    fresnel: Vec<f64>,
    /// The reflection operator of a semi-infinite isotropic layer on the nodes of [`SEMI_INFINITE_TABLE_NODES`]
    /// (built on first use, for at most [`SEMI_INFINITE_TABLE_MAX_STREAMS`] streams).
    semi_infinite: OnceLock<Vec<Matrix>>,
}

/// Intervals of the table of semi-infinite reflection operators, uniform in `s = sqrt(1 - albedo)` on [0, 1]: the
/// operator is smooth in s (its expansion near conservative scattering is in powers of the diffusion exponent,
/// proportional to s; van de Hulst 1980, ch. 15), so 6-point Lagrange interpolation is within 1e-11 of the doubled
/// operator's elements for albedos up to [`SEMI_INFINITE_TABLE_MAX_ALBEDO`] (tests).
const SEMI_INFINITE_TABLE_NODES: usize = 256;
/// Points of the Lagrange interpolation between the table's nodes (4 points left 5e-10 of the doubled operator: a
/// layer split off a semi-infinite one then changed the total by 3.6e-10, against the 1e-10 of
/// tests/physics/transport_properties.rs).
const LAGRANGE_POINTS: usize = 6;
/// Above this albedo (far beyond skin's, whose largest is about 0.99) the table's first interval, next to the
/// ill-conditioned conservative node, was up to 2.4e-7 from doubling, which under a strong internal reflection moved a
/// total by 1.8e-5: such layers are doubled.
const SEMI_INFINITE_TABLE_MAX_ALBEDO: f64 = 0.9999;
/// Above this many streams the table (257 doublings to convergence) would cost more than the evaluations it saves.
const SEMI_INFINITE_TABLE_MAX_STREAMS: usize = 16;

impl Quadrature {
    /// After Prahl 1995 (section 2.3): Gauss points on [0, nu_c] and right-Radau points above it, ending at nu = 1,
    /// with `nu_c` the cosine of the critical angle inside the slab; the Radau points are placed in s with
    /// nu = nu_c + (1 - nu_c) s^2 (see below; Prahl spaces them linearly in nu). Prahl puts half the streams below
    /// nu_c; here that is so from index 1.155 up, and a narrower critical cone gets its share of the cosine range
    /// ([`streams_below_critical`]). Radau points on the whole of [0, 1] when the slab is index-matched.
    fn new(streams: usize, ior: f64) -> Quadrature {
        let nu_c = if ior > 1.0 { (1.0 - 1.0 / (ior * ior)).sqrt() } else { 0.0 };
        let (mut nu, mut w) = (Vec::with_capacity(streams), Vec::with_capacity(streams));
        let below = if nu_c > 0.0 { streams_below_critical(streams, nu_c) } else { 0 };
        let radau_count = streams - below;
        if below > 0 {
            let (x, wx) = crate::numeric::gauss_legendre(below);
            for (xi, wi) in x.iter().zip(&wx) {
                nu.push(0.5 * nu_c * (xi + 1.0));
                w.push(0.5 * nu_c * wi);
            }
        }
        let (x, wx) = right_radau(radau_count);
        for (xi, wi) in x.iter().zip(&wx) {
            if nu_c > 0.0 && radau_count > 1 {
                // Above the critical angle the streams leave through the boundary with the Fresnel transmittance, which
                // rises from the critical cosine like sqrt(nu - nu_c): in nu a square-root edge, which caps any rule at
                // algebraic convergence (measured: the total's error fell like streams^-3, 0.65 % at 8 streams on dark
                // skin). In s, with nu = nu_c + (1 - nu_c) s^2, the integrand is smooth and the Radau rule converges
                // spectrally (4e-4 at 8 streams, 2e-6 at 12, 1e-8 at 16).
                let s = 0.5 * (xi + 1.0);
                nu.push(nu_c + (1.0 - nu_c) * s * s);
                w.push(wi * (1.0 - nu_c) * s);
            } else {
                // Index-matched (nu_c = 0), or a single Radau point (at nu = 1, weight 1 - nu_c).
                nu.push(nu_c + 0.5 * (1.0 - nu_c) * (xi + 1.0));
                w.push(0.5 * (1.0 - nu_c) * wi);
            }
        }
        let flux = nu.iter().zip(&w).map(|(n, w)| 2.0 * n * w).collect();
        // Inside the slab looking out: relative index air / slab.
        let fresnel = nu.iter().map(|&n| fresnel_dielectric(n, 1.0 / ior)).collect();
        Quadrature { streams, nu, w, flux, fresnel, semi_infinite: Default::default() }
    }

    /// The reflection operator of a semi-infinite isotropic layer of single-scattering albedo `albedo`: a semi-infinite
    /// layer has no length scale, so the albedo alone fixes it, and it is interpolated from a table over the albedo
    /// (`None` above [`SEMI_INFINITE_TABLE_MAX_STREAMS`] streams: the caller doubles).
    fn semi_infinite_isotropic(&self, albedo: f64) -> Option<Matrix> {
        if self.streams > SEMI_INFINITE_TABLE_MAX_STREAMS || albedo > SEMI_INFINITE_TABLE_MAX_ALBEDO {
            return None;
        }
        let table = self.semi_infinite.get_or_init(|| {
            (0..=SEMI_INFINITE_TABLE_NODES)
                .map(|k| {
                    let s = k as f64 / SEMI_INFINITE_TABLE_NODES as f64;
                    let slab = OpticalSlab { albedo: 1.0 - s * s, optical_thickness: f64::INFINITY, g: 0.0 };
                    Operators::doubled(self, &slab).r_down
                })
                .collect()
        });
        // 6-point Lagrange interpolation in s on the uniform nodes (the end intervals use the nearest 6 nodes).
        let s = (1.0 - albedo).max(0.0).sqrt() * SEMI_INFINITE_TABLE_NODES as f64;
        let first = (s.floor() as usize).saturating_sub(2).min(SEMI_INFINITE_TABLE_NODES + 1 - LAGRANGE_POINTS);
        let x = s - first as f64;
        let mut r = Matrix::zeros(self.streams);
        for k in 0..LAGRANGE_POINTS {
            let weight: f64 =
                (0..LAGRANGE_POINTS).filter(|&j| j != k).map(|j| (x - j as f64) / (k as f64 - j as f64)).product();
            r.add_scaled(&table[first + k], weight);
        }
        Some(r)
    }

    fn n(&self) -> usize {
        self.streams
    }
}

/// Streams on [0, nu_c] (Gauss points) for `streams` in all and the critical cosine `nu_c > 0`: their share of the
/// cosine range, rounded, at least 1 and at most half. Half, as Prahl places them, for indices above 1.155
/// (nu_c >= 0.5: skin's 1.4 and water's 1.33 keep the split they always had); for an index just above 1 the critical
/// cone is narrow, and half the streams inside it left the other half to span the rest: 4 streams erred by 2.1 % at
/// index 1.0001 where index 1 gave 0.01 %, and 2 streams by up to 47 % (issue 38).
fn streams_below_critical(streams: usize, nu_c: f64) -> usize {
    ((streams as f64 * nu_c).round() as usize).clamp(1, streams / 2)
}

/// Right Gauss-Radau rule on [-1, 1] with `m` points, the last at +1: the others are the roots of
/// `(P_{m-1}(x) - P_m(x)) / (1 - x)`, with weights `(1 + x) / (m P_{m-1}(x))^2`, and `2 / m^2` at +1 (Abramowitz &
/// Stegun 25.4.31, reflected). Exact for polynomials of degree 2m - 2.
fn right_radau(m: usize) -> (Vec<f64>, Vec<f64>) {
    let legendre = |x: f64| -> (f64, f64) {
        // (P_{m-1}(x), P_m(x))
        let (mut p_prev, mut p) = (1.0, x);
        if m == 1 {
            return (1.0, x);
        }
        for k in 1..m {
            let next = ((2 * k + 1) as f64 * x * p - k as f64 * p_prev) / (k + 1) as f64;
            p_prev = p;
            p = next;
        }
        (p_prev, p)
    };
    let f = |x: f64| {
        let (pm1, pm) = legendre(x);
        (pm1 - pm) / (1.0 - x)
    };
    let mut nodes = Vec::with_capacity(m);
    // Bracket the m - 1 interior roots on a Chebyshev grid, then bisect.
    let samples = 64 * m.max(2) * m.max(2);
    let grid: Vec<f64> = (0..=samples).map(|k| -(std::f64::consts::PI * k as f64 / samples as f64).cos()).collect();
    let mut prev = (grid[0], f(grid[0]));
    for &x in &grid[1..samples] {
        let fx = f(x);
        if fx == 0.0 || (fx < 0.0) != (prev.1 < 0.0) {
            let (mut lo, mut hi, flo) = (prev.0, x, prev.1);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if (f(mid) < 0.0) == (flo < 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            nodes.push(0.5 * (lo + hi));
        }
        prev = (x, fx);
    }
    let mut weights: Vec<f64> = nodes
        .iter()
        .map(|&x| {
            let (pm1, _) = legendre(x);
            (1.0 + x) / ((m as f64) * pm1).powi(2)
        })
        .collect();
    nodes.push(1.0);
    weights.push(2.0 / (m * m) as f64);
    (nodes, weights)
}

/// Run `f` with the quadrature for `streams` and `ior`, built once per process (with its semi-infinite table) and
/// shared by every thread: a request evaluates every wavelength with the same streams and index.
fn with_quadrature<T>(streams: usize, ior: f64, f: impl FnOnce(&Quadrature) -> T) -> T {
    type Cache = Mutex<HashMap<(usize, u64), Arc<Quadrature>>>;
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let quadrature = {
        let mut cache = CACHE.get_or_init(Default::default).lock().unwrap_or_else(|e| e.into_inner());
        Arc::clone(cache.entry((streams, ior.to_bits())).or_insert_with(|| Arc::new(Quadrature::new(streams, ior))))
    };
    f(&quadrature)
}

/// Streams must be even and within [`STREAMS_RANGE`].
pub fn validate_streams(streams: usize) -> Result<(), SkinError> {
    let (lo, hi) = STREAMS_RANGE;
    if !(lo..=hi).contains(&streams) || streams % 2 != 0 {
        return Err(SkinError::invalid(
            "streams",
            format!("the adding-doubling stream count must be even and in [{lo}, {hi}]; got {streams}"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slab(albedo: f64, optical_thickness: f64, g: f64) -> OpticalSlab {
        OpticalSlab { albedo, optical_thickness, g }
    }

    /// Total reflectance and transmittance (flux summed over the streams) of slabs stacked without boundaries, for
    /// unit flux in the normal stream.
    fn unbounded(slabs: &[OpticalSlab], ior: f64, streams: usize) -> (f64, f64) {
        with_quadrature(streams, ior, |q| {
            let ops = slabs.iter().map(|s| Operators::of_slab(q, s)).reduce(|upper, lower| upper.add(&lower)).unwrap();
            let n = q.n();
            let column_sum = |m: &Matrix| (0..n).map(|i| m[(i, n - 1)]).sum::<f64>();
            (column_sum(&ops.r_down), column_sum(&ops.t_down))
        })
    }

    /// van de Hulst (1980), the slab of albedo 0.9, optical thickness 2, g = 0.75, index-matched: Rd 0.09739, Tt
    /// 0.66096 (total transmission, the unscattered beam included).
    #[test]
    fn van_de_hulst_slab() {
        for (streams, tolerance) in [(8, 2e-4), (16, 1e-4), (32, 1e-4)] {
            let (r, t) = unbounded(&[slab(0.9, 2.0, 0.75)], 1.0, streams);
            assert!((r - 0.09739).abs() < tolerance, "{streams} streams: Rd {r} vs 0.09739");
            assert!((t - 0.66096).abs() < tolerance, "{streams} streams: Tt {t} vs 0.66096");
        }
    }

    /// Index-matched, isotropic, semi-infinite: R = 1 - H(1; a) sqrt(1 - a) (Chandrasekhar 1950, the plane albedo),
    /// with H from `half_space` (another solver: the H equation on 168 nodes).
    #[test]
    fn chandrasekhar_plane_albedo() {
        for a in [0.3, 0.8, 0.95, 0.99, 0.999] {
            let exact = 1.0 - crate::transport::half_space::chandrasekhar_h(1.0, a) * (1.0 - a).sqrt();
            for (streams, tolerance) in [(8, 2e-3), (16, 5e-4), (32, 2e-4)] {
                let r = slab_reflectance(&[slab(a, f64::INFINITY, 0.0)], 1.0, streams).unwrap();
                assert!((r / exact - 1.0).abs() < tolerance, "a {a}, {streams} streams: {r} vs {exact}");
            }
        }
    }

    /// No scattering: nothing is reflected, and the normal stream is attenuated by exp(-tau) (the diamond start's
    /// attenuation `(1 - x/2)/(1 + x/2)` per thin layer, doubled up).
    #[test]
    fn non_scattering_slab() {
        for tau in [0.01, 0.5, 3.0] {
            let (r, t) = unbounded(&[slab(0.0, tau, 0.0)], 1.4, 8);
            assert!(r.abs() < 1e-15, "tau {tau}: R {r}");
            assert!((t / (-tau).exp() - 1.0).abs() < 1e-3, "tau {tau}: T {t} vs {}", (-tau).exp());
            assert_eq!(slab_reflectance(&[slab(0.0, tau, 0.0)], 1.4, 8).unwrap(), 0.0);
        }
    }

    /// The top boundary: each stream's Fresnel reflectance from inside, total below the critical cosine (0.700 for
    /// n = 1.4), and F0 = ((n - 1)/(n + 1))^2 = 0.027778 for the normal stream.
    #[test]
    fn boundary_streams() {
        let q = Quadrature::new(8, 1.4);
        let nu_c = (1.0 - 1.0 / (1.4f64 * 1.4)).sqrt();
        for (nu, f) in q.nu.iter().zip(&q.fresnel) {
            if *nu < nu_c {
                assert_eq!(*f, 1.0, "nu {nu}");
            } else {
                assert!(*f < 1.0, "nu {nu}: {f}");
            }
        }
        assert!((q.fresnel[7] - 0.0277778).abs() < 1e-7, "{}", q.fresnel[7]);
    }

    /// Energy: a non-absorbing slab reflects or transmits everything (R + T = 1), with or without a phase function; an
    /// absorbing one less; a non-absorbing semi-infinite layer under the Fresnel boundary returns everything.
    #[test]
    fn energy_is_conserved() {
        for g in [0.0, 0.5, 0.9] {
            for tau in [0.1, 1.0, 10.0] {
                let (r, t) = unbounded(&[slab(1.0, tau, g)], 1.4, 8);
                assert!((r + t - 1.0).abs() < 1e-10, "g {g} tau {tau}: R {r} + T {t}");
                let (ra, ta) = unbounded(&[slab(0.9, tau, g)], 1.4, 8);
                assert!(ra + ta < 1.0 - 1e-3 && ra >= 0.0 && ta >= 0.0, "g {g} tau {tau}: R {ra} T {ta}");
            }
        }
        for streams in [4, 8, 16, 32] {
            let r = slab_reflectance(&[slab(1.0, f64::INFINITY, 0.0)], 1.4, streams).unwrap();
            // The doubling stops at optical thickness 1e9 and drops what that layer still transmits (2.4e-9 at 4
            // streams); round-off of the near-singular solves took 5e-6 before the doubling kept its energy balance.
            assert!((r - 1.0).abs() < 5e-9, "{streams} streams: {r}");
        }
    }

    /// The semi-infinite table against doubling at albedos between its nodes; above its largest albedo there is no
    /// table (the caller doubles).
    #[test]
    fn semi_infinite_table_matches_doubling() {
        for streams in [4, 8, 16] {
            with_quadrature(streams, 1.4, |q| {
                for a in [0.0, 0.013, 0.5, 0.8817, 0.97, 0.99931, 0.99985] {
                    let slab = slab(a, f64::INFINITY, 0.0);
                    let table = q.semi_infinite_isotropic(a).unwrap();
                    let doubled = Operators::doubled(q, &slab).r_down;
                    let d = table.max_abs_difference(&doubled);
                    assert!(d < 1e-11, "{streams} streams, a {a}: {d:e}");
                }
                for a in [0.99991, 0.9999997, 1.0] {
                    assert!(q.semi_infinite_isotropic(a).is_none(), "{streams} streams, a {a}");
                }
            });
        }
    }

    /// A layer cut in halves is the same layer (both halves start from the thin layer the whole one starts from);
    /// cut anywhere else, the halves' thin starts differ, within 1e-10 here (tests/physics/transport_properties.rs tries random
    /// stacks).
    #[test]
    fn splitting_a_layer_changes_nothing() {
        let dermis = slab(0.97, f64::INFINITY, 0.0);
        for (a, tau) in [(0.6, 0.5), (0.9, 2.0), (0.99, 7.0)] {
            let whole = slab_reflectance(&[slab(a, tau, 0.0), dermis], 1.4, 8).unwrap();
            let halves = slab_reflectance(&[slab(a, tau / 2.0, 0.0), slab(a, tau / 2.0, 0.0), dermis], 1.4, 8).unwrap();
            assert!((halves / whole - 1.0).abs() < 1e-12, "halves {halves} vs {whole}");
            let uneven = slab_reflectance(&[slab(a, 0.3 * tau, 0.0), slab(a, 0.7 * tau, 0.0), dermis], 1.4, 8).unwrap();
            assert!((uneven - whole).abs() < 1e-10, "0.3/0.7 split {uneven} vs {whole}");
        }
    }

    #[test]
    fn bad_streams_and_index_steps_are_refused() {
        let layer = Layer { thickness_mm: f64::INFINITY, sigma_a_per_mm: 0.1, sigma_s_reduced_per_mm: 1.0, ior: 1.4 };
        for streams in [0, 3, 66, 1000] {
            let e = total_diffuse_reflectance(&[layer], streams).unwrap_err().to_string();
            assert!(e.contains("streams") && e.contains("even"), "{streams}: {e}");
        }
        let top = Layer { thickness_mm: 0.1, ior: 1.3, ..layer };
        let e = total_diffuse_reflectance(&[top, layer], 8).unwrap_err().to_string();
        assert!(e.contains("layer 1") && e.contains("diffusion"), "{e}");
    }

    /// The whole stack added into one set of operators, then the boundary: `u = (I - R F)^-1 R e_N` leaves as
    /// `(1 - F) . u`. Another order of the same algebra than `UpperSystem`'s, which the solver uses.
    fn total_by_whole_stack(slabs: &[OpticalSlab], ior: f64, streams: usize) -> f64 {
        with_quadrature(streams, ior, |q| {
            let n = q.n();
            let r = slabs.iter().map(|s| Operators::of_slab(q, s)).reduce(|u, l| u.add(&l)).unwrap().r_down;
            let a = Matrix::identity(n).minus(&r.transpose().scale_rows(&q.fresnel).transpose());
            let u = a.solve_vector(&(0..n).map(|i| r[(i, n - 1)]).collect::<Vec<_>>());
            u.iter().zip(&q.fresnel).map(|(ui, fi)| ui * (1.0 - fi)).sum()
        })
    }

    #[test]
    fn upper_system_is_the_whole_stack() {
        let stacks = [
            vec![slab(0.8, f64::INFINITY, 0.0)],
            vec![slab(0.5, 3.0, 0.0)],
            vec![slab(0.4, 1.5, 0.0), slab(0.97, f64::INFINITY, 0.0)],
            vec![slab(0.9, 0.2, 0.7), slab(0.3, 4.0, 0.0), slab(0.99, 30.0, 0.5)],
            vec![slab(0.6, 0.5, 0.0), slab(0.95, 2.0, 0.0), slab(0.2, 0.1, 0.0), slab(0.9, f64::INFINITY, 0.0)],
        ];
        for stack in &stacks {
            for (ior, streams) in [(1.4, 8), (1.0, 6), (1.33, 16)] {
                let a = slab_reflectance(stack, ior, streams).unwrap();
                let b = total_by_whole_stack(stack, ior, streams);
                assert!((a - b).abs() < 1e-12 * b.max(1e-3), "{stack:?} n {ior} {streams}: {a} vs {b}");
                // A second call is served by the cache and gives the same bits.
                assert_eq!(slab_reflectance(stack, ior, streams).unwrap(), a);
            }
        }
    }

    #[test]
    fn radau_rule_integrates_polynomials() {
        for m in 1..=16 {
            let (x, w) = right_radau(m);
            assert_eq!(x.len(), m, "m = {m}");
            for degree in 0..=(2 * m - 2) {
                let sum: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(degree as i32)).sum();
                let exact = if degree % 2 == 0 { 2.0 / (degree + 1) as f64 } else { 0.0 };
                assert!((sum - exact).abs() < 1e-12, "m {m} degree {degree}: {sum} vs {exact}");
            }
        }
    }

    #[test]
    fn quadrature_weights_sum_to_one_and_end_at_normal() {
        for ior in [1.0, 1.33, 1.4, 2.0] {
            for streams in [2, 4, 8, 16, 32] {
                let q = Quadrature::new(streams, ior);
                let sum: f64 = q.w.iter().sum();
                assert!((sum - 1.0).abs() < 1e-13, "{streams} {ior}: {sum}");
                assert_eq!(*q.nu.last().unwrap(), 1.0);
                assert!(q.nu.windows(2).all(|p| p[0] < p[1]), "{:?}", q.nu);
            }
        }
    }
}
