//! Monte Carlo reference for light transport in a layered slab (a test utility, not product code).
//!
//! An independent check of the diffusion solver (`spectral_skin::diffusion`): it shares no code
//! with it. The model:
//!
//! * Layers top to bottom, air (n = 1) above. The last layer may be semi-infinite; a finite last
//!   layer rests on a medium of its own index, so light that reaches its bottom leaves (transmittance).
//! * Photons start just below the top surface, at the origin, travelling straight down: normal
//!   incidence, already transmitted. Reflectance is therefore per unit flux *entering* the medium,
//!   which is what the diffusion total diffuse reflectance means.
//! * Isotropic scattering, so `sigma_s` here equals the reduced scattering `sigma_s'` of diffusion.
//! * Exponential free flights sampled in optical depth; a flight that reaches a boundary stops
//!   there, and the rest of its optical depth is spent with the next layer's coefficients.
//! * Unpolarised Fresnel reflection and Snell refraction (with total internal reflection) at every
//!   boundary with an index change, chosen at random with the Fresnel probability (analog, unbiased).
//! * Absorption by weight: at each collision the weight is multiplied by the single-scattering
//!   albedo; below a threshold, Russian roulette (unbiased).
//! * Deterministic for a given seed and photon count, whatever the number of threads: photons are
//!   split into fixed chunks, each with its own `Pcg64` seeded from (seed, chunk index), and the
//!   chunk tallies are added in chunk order.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// One homogeneous layer. Lengths in mm, coefficients in mm^-1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McLayer {
    /// Thickness, mm; `f64::INFINITY` is allowed for the last layer only.
    pub thickness_mm: f64,
    /// Absorption coefficient, mm^-1.
    pub sigma_a_per_mm: f64,
    /// Scattering coefficient (isotropic phase function), mm^-1.
    pub sigma_s_per_mm: f64,
    /// Refractive index.
    pub ior: f64,
}

impl McLayer {
    /// The Monte Carlo layers of the diffusion core's stack: the same thickness, absorption and index, with isotropic
    /// scattering at sigma_s = sigma_s' (the transport problem the diffusion model approximates).
    pub fn isotropic_stack(layers: &[spectral_skin::layer::Layer]) -> Vec<McLayer> {
        layers
            .iter()
            .map(|l| McLayer {
                thickness_mm: l.thickness_mm,
                sigma_a_per_mm: l.sigma_a_per_mm,
                sigma_s_per_mm: l.sigma_s_reduced_per_mm,
                ior: l.ior,
            })
            .collect()
    }
}

/// Run settings.
#[derive(Debug, Clone)]
pub struct McConfig {
    /// Number of photons launched.
    pub photons: u64,
    /// Seed; the same seed and photon count give bit-identical results.
    pub seed: u64,
    /// Radial bin edges in mm, strictly increasing, first >= 0 (e.g. [`log_edges`]).
    pub radial_edges_mm: Vec<f64>,
    /// Russian roulette starts when the weight drops below this.
    pub roulette_threshold: f64,
    /// Survival probability in Russian roulette (the survivor's weight is divided by it).
    pub roulette_survival: f64,
    /// Photons per chunk (each chunk has its own RNG stream). Part of the determinism contract.
    pub chunk_photons: u64,
    /// A photon about to make collision number `max_collisions_per_photon + 1` is stopped there and
    /// its weight tallied as `unfinished`. Needed for non-absorbing semi-infinite media, where the
    /// number of collisions before escape has an infinite mean (its tail falls like n^-1/2); with 1,
    /// the reflectance is the single-scattering reflectance alone.
    pub max_collisions_per_photon: u64,
}

impl McConfig {
    pub fn new(photons: u64, seed: u64, radial_edges_mm: Vec<f64>) -> Self {
        McConfig {
            photons,
            seed,
            radial_edges_mm,
            roulette_threshold: 1e-3,
            roulette_survival: 0.1,
            chunk_photons: 4096,
            max_collisions_per_photon: u64::MAX,
        }
    }
}

/// Tallies of one run. All reflectances and transmittances are per launched photon.
#[derive(Debug, Clone)]
pub struct McResult {
    pub photons: u64,
    /// Total diffuse reflectance: weight leaving through the top surface, per photon.
    pub reflectance: f64,
    /// Standard error of `reflectance` (from the per-photon variance).
    pub reflectance_se: f64,
    /// Weight leaving through the bottom of a finite stack (or lost to infinite depth), per photon.
    pub transmittance: f64,
    /// Standard error of `transmittance`.
    pub transmittance_se: f64,
    /// The bin edges the profile uses, mm.
    pub radial_edges_mm: Vec<f64>,
    /// Reflected weight per photon per unit area in each annulus [edge_i, edge_i+1), mm^-2:
    /// directly comparable with a diffusion profile R(r) averaged over the annulus.
    pub profile_per_mm2: Vec<f64>,
    /// Standard error of each profile bin, mm^-2.
    pub profile_se_per_mm2: Vec<f64>,
    /// Weight absorbed, per photon (including the net weight removed or added by Russian
    /// roulette, so that reflectance + transmittance + absorbed + unfinished = 1 for every photon).
    pub absorbed: f64,
    /// Weight of photons stopped by `max_collisions_per_photon`, per photon.
    pub unfinished: f64,
    /// Reflected weight per photon that left at r < the first edge.
    pub reflectance_below_first_edge: f64,
    /// Reflected weight per photon that left at r >= the last edge.
    pub reflectance_beyond_last_edge: f64,
    /// Number of scattering (collision) events simulated, for speed reports.
    pub scattering_events: u64,
}

impl McResult {
    /// Reflected weight per photon that left within radius `edges[k]`, for each edge:
    /// the unnormalised radial CDF of the reflectance (divide by `reflectance` to normalise).
    pub fn cumulative_reflectance_at_edges(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.radial_edges_mm.len());
        let mut acc = self.reflectance_below_first_edge;
        out.push(acc);
        for (k, v) in self.profile_per_mm2.iter().enumerate() {
            acc += v * annulus_area(self.radial_edges_mm[k], self.radial_edges_mm[k + 1]);
            out.push(acc);
        }
        out
    }
}

/// Area of the annulus r0 <= r < r1, mm^2.
pub fn annulus_area(r0: f64, r1: f64) -> f64 {
    std::f64::consts::PI * (r1 * r1 - r0 * r0)
}

/// `n + 1` log-spaced edges from `r_min` to `r_max` (both > 0), with `0` prepended when
/// `with_zero` (so the first bin is the disc r < r_min).
pub fn log_edges(r_min: f64, r_max: f64, n: usize, with_zero: bool) -> Vec<f64> {
    assert!(r_min > 0.0 && r_max > r_min && n >= 1, "r_min {r_min}, r_max {r_max}, n {n}");
    let mut v = Vec::with_capacity(n + 2);
    if with_zero {
        v.push(0.0);
    }
    let ratio = (r_max / r_min).ln();
    for k in 0..=n {
        v.push(r_min * (ratio * k as f64 / n as f64).exp());
    }
    v
}

/// Unpolarised Fresnel reflectance for light in medium `n1` hitting medium `n2` with
/// `cos_i` = cosine of the angle of incidence (0..=1). Returns (R, cos_t); total internal
/// reflection gives (1, 0).
#[inline]
pub fn fresnel_unpolarized(n1: f64, n2: f64, cos_i: f64) -> (f64, f64) {
    let eta = n1 / n2;
    let sin_t2 = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin_t2 >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Precomputed per-layer data.
#[derive(Debug, Clone, Copy)]
struct Slab {
    z_top: f64,
    z_bottom: f64,
    sigma_t: f64,
    albedo: f64,
    ior: f64,
    /// Index of the medium above (air for the first layer).
    ior_above: f64,
    /// Index of the medium below (the layer's own index below the last layer).
    ior_below: f64,
}

#[derive(Debug, Clone, Default)]
struct Tally {
    r_sum: f64,
    r_sum2: f64,
    t_sum: f64,
    t_sum2: f64,
    absorbed: f64,
    unfinished: f64,
    under: f64,
    over: f64,
    bins: Vec<f64>,
    bins2: Vec<f64>,
    events: u64,
}

impl Tally {
    fn new(nbins: usize) -> Self {
        Tally { bins: vec![0.0; nbins], bins2: vec![0.0; nbins], ..Default::default() }
    }
    fn add(&mut self, o: &Tally) {
        self.r_sum += o.r_sum;
        self.r_sum2 += o.r_sum2;
        self.t_sum += o.t_sum;
        self.t_sum2 += o.t_sum2;
        self.absorbed += o.absorbed;
        self.unfinished += o.unfinished;
        self.under += o.under;
        self.over += o.over;
        for (a, b) in self.bins.iter_mut().zip(&o.bins) {
            *a += b;
        }
        for (a, b) in self.bins2.iter_mut().zip(&o.bins2) {
            *a += b;
        }
        self.events += o.events;
    }
}

/// Uniform in (0, 1].
#[inline(always)]
fn uniform_open0(rng: &mut Pcg64) -> f64 {
    ((rng.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Uniform in [0, 1).
#[inline(always)]
fn uniform(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Seed of chunk `chunk` of a run with seed `seed`: mixed so that runs with nearby seeds do not share streams.
fn chunk_seed(seed: u64, chunk: u64) -> u64 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ chunk.wrapping_mul(0xD1B5_4A32_D192_ED03);
    // splitmix64 finaliser
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

struct Walker<'a> {
    slabs: &'a [Slab],
    edges: &'a [f64],
    roulette_threshold: f64,
    roulette_survival: f64,
    max_collisions: u64,
}

impl Walker<'_> {
    fn tally_reflect(&self, t: &mut Tally, x: f64, y: f64, w: f64) {
        t.r_sum += w;
        t.r_sum2 += w * w;
        let r = (x * x + y * y).sqrt();
        let e = self.edges;
        if e.is_empty() || r < e[0] {
            t.under += w;
        } else if r >= e[e.len() - 1] {
            t.over += w;
        } else {
            // first edge > r, minus one
            let k = e.partition_point(|&edge| edge <= r) - 1;
            t.bins[k] += w;
            t.bins2[k] += w * w;
        }
    }

    fn run_photon(&self, rng: &mut Pcg64, t: &mut Tally) {
        let slabs = self.slabs;
        let last = slabs.len() - 1;
        let (mut x, mut y, mut z) = (0.0f64, 0.0f64, 0.0f64);
        let (mut ux, mut uy, mut uz) = (0.0f64, 0.0f64, 1.0f64);
        let mut layer = 0usize;
        let mut w = 1.0f64;
        let mut collisions = 0u64;
        loop {
            // Free flight: optical depth to the next collision.
            let mut tau = -uniform_open0(rng).ln();
            loop {
                let s = &slabs[layer];
                let dist_b = if uz > 0.0 {
                    (s.z_bottom - z) / uz
                } else if uz < 0.0 {
                    (s.z_top - z) / uz
                } else {
                    f64::INFINITY
                };
                let step = if s.sigma_t > 0.0 { tau / s.sigma_t } else { f64::INFINITY };
                if step < dist_b {
                    x += step * ux;
                    y += step * uy;
                    z += step * uz;
                    break;
                }
                if !dist_b.is_finite() {
                    // Flying forever down a semi-infinite, non-interacting layer (or parallel to it).
                    t.t_sum += w;
                    t.t_sum2 += w * w;
                    return;
                }
                // Move to the boundary and spend that part of the optical depth.
                x += dist_b * ux;
                y += dist_b * uy;
                tau -= dist_b * s.sigma_t;
                if tau < 0.0 {
                    tau = 0.0;
                }
                let down = uz > 0.0;
                let (z_b, n2) = if down { (s.z_bottom, s.ior_below) } else { (s.z_top, s.ior_above) };
                z = z_b;
                if n2 != s.ior {
                    let (refl, cos_t) = fresnel_unpolarized(s.ior, n2, uz.abs());
                    if refl >= 1.0 || uniform(rng) < refl {
                        uz = -uz;
                        continue;
                    }
                    let eta = s.ior / n2;
                    ux *= eta;
                    uy *= eta;
                    uz = if down { cos_t } else { -cos_t };
                }
                if down {
                    if layer == last {
                        t.t_sum += w;
                        t.t_sum2 += w * w;
                        return;
                    }
                    layer += 1;
                } else {
                    if layer == 0 {
                        self.tally_reflect(t, x, y, w);
                        return;
                    }
                    layer -= 1;
                }
            }
            // Collision: absorb by weight, then scatter isotropically.
            collisions += 1;
            if collisions > self.max_collisions {
                t.unfinished += w;
                return;
            }
            t.events += 1;
            let albedo = slabs[layer].albedo;
            t.absorbed += w * (1.0 - albedo);
            w *= albedo;
            if w < self.roulette_threshold {
                if w <= 0.0 || uniform(rng) >= self.roulette_survival {
                    t.absorbed += w;
                    return;
                }
                let boosted = w / self.roulette_survival;
                t.absorbed -= boosted - w;
                w = boosted;
            }
            // Marsaglia (1972): uniform direction on the sphere from a point in the unit disc.
            loop {
                let a = 2.0 * uniform(rng) - 1.0;
                let b = 2.0 * uniform(rng) - 1.0;
                let q = a * a + b * b;
                if q < 1.0 {
                    let f = 2.0 * (1.0 - q).sqrt();
                    ux = a * f;
                    uy = b * f;
                    uz = 1.0 - 2.0 * q;
                    break;
                }
            }
        }
    }
}

/// Run the simulation. Panics on an invalid stack or configuration.
pub fn simulate(layers: &[McLayer], cfg: &McConfig) -> McResult {
    assert!(!layers.is_empty(), "no layers: {layers:?}");
    let edges = &cfg.radial_edges_mm;
    assert!(edges.windows(2).all(|p| p[1] > p[0]), "radial edges must increase strictly: {edges:?}");
    assert!(edges.first().map_or(true, |&e| e >= 0.0), "radial edges must be >= 0: {edges:?}");
    assert!(
        cfg.roulette_survival > 0.0 && cfg.roulette_survival <= 1.0,
        "roulette survival {} outside (0, 1]",
        cfg.roulette_survival
    );
    assert!(cfg.chunk_photons > 0, "chunk_photons {}", cfg.chunk_photons);
    let mut slabs = Vec::with_capacity(layers.len());
    let mut z = 0.0;
    for (i, l) in layers.iter().enumerate() {
        let last = i + 1 == layers.len();
        assert!(
            l.thickness_mm > 0.0 && (l.thickness_mm.is_finite() || last),
            "layer {i}: thickness {} must be > 0 and finite except for the last layer",
            l.thickness_mm
        );
        assert!(l.sigma_a_per_mm >= 0.0 && l.sigma_s_per_mm >= 0.0, "layer {i}: negative coefficient: {l:?}");
        assert!(l.ior.is_finite() && l.ior > 0.0, "layer {i}: bad ior {}", l.ior);
        let sigma_t = l.sigma_a_per_mm + l.sigma_s_per_mm;
        slabs.push(Slab {
            z_top: z,
            z_bottom: z + l.thickness_mm,
            sigma_t,
            albedo: if sigma_t > 0.0 { l.sigma_s_per_mm / sigma_t } else { 0.0 },
            ior: l.ior,
            ior_above: if i == 0 { 1.0 } else { layers[i - 1].ior },
            ior_below: if last { l.ior } else { layers[i + 1].ior },
        });
        z += l.thickness_mm;
    }
    let nbins = edges.len().saturating_sub(1);
    let walker = Walker {
        slabs: &slabs,
        edges,
        roulette_threshold: cfg.roulette_threshold,
        roulette_survival: cfg.roulette_survival,
        max_collisions: cfg.max_collisions_per_photon,
    };
    let chunks = cfg.photons.div_ceil(cfg.chunk_photons);
    let tallies: Vec<Tally> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = Pcg64::seed_from_u64(chunk_seed(cfg.seed, c));
            let mut t = Tally::new(nbins);
            let n = cfg.chunk_photons.min(cfg.photons - c * cfg.chunk_photons);
            for _ in 0..n {
                walker.run_photon(&mut rng, &mut t);
            }
            t
        })
        .collect();
    let mut total = Tally::new(nbins);
    for t in &tallies {
        total.add(t);
    }
    let n = cfg.photons as f64;
    let se = |sum: f64, sum2: f64| {
        let mean = sum / n;
        ((sum2 / n - mean * mean).max(0.0) / (n - 1.0).max(1.0)).sqrt()
    };
    let mut profile = Vec::with_capacity(nbins);
    let mut profile_se = Vec::with_capacity(nbins);
    for k in 0..nbins {
        let area = annulus_area(edges[k], edges[k + 1]);
        profile.push(total.bins[k] / n / area);
        profile_se.push(se(total.bins[k], total.bins2[k]) / area);
    }
    McResult {
        photons: cfg.photons,
        reflectance: total.r_sum / n,
        reflectance_se: se(total.r_sum, total.r_sum2),
        transmittance: total.t_sum / n,
        transmittance_se: se(total.t_sum, total.t_sum2),
        radial_edges_mm: edges.clone(),
        profile_per_mm2: profile,
        profile_se_per_mm2: profile_se,
        absorbed: total.absorbed / n,
        unfinished: total.unfinished / n,
        reflectance_below_first_edge: total.under / n,
        reflectance_beyond_last_edge: total.over / n,
        scattering_events: total.events,
    }
}
