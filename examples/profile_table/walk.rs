//! The white Monte Carlo behind `data/profile_table.bin` (docs/model.md, Exact radial profile): photons walk a
//! stack that scatters but does not absorb, and each exit is weighted afterwards by exp(-a_top L_top - a_bottom
//! L_bottom) with its path length in each layer, for every pair of absorptions asked, in the exit radius' fine bin.
//!
//! Lengths are in the top layer's mean free paths (its scattering is 1). Isotropic scattering; one index throughout,
//! air above: at the top a photon is reflected with the Fresnel probability (every time it reaches it) or leaves;
//! the photons start at the origin going straight down (a normal beam, already refracted: per unit refracted power,
//! as the adding-doubling total). A path longer than `max_path` is cut (counted in `cut`). Deterministic for a seed
//! and photon count, whatever the thread count: fixed chunks, each with its own generator, summed in chunk order.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use spectral_skin::transport::profile_table::{fine_bin, SliceMoments, FINE_BINS};

/// The stack and the run.
#[derive(Debug, Clone)]
pub struct WhiteWalk {
    /// Top layer's thickness in its mean free paths; infinity for one semi-infinite layer.
    pub tau: f64,
    /// Scattering of the (semi-infinite) bottom layer over the top layer's.
    pub bottom_scattering: f64,
    pub ior: f64,
    pub photons: u64,
    pub seed: u64,
    pub max_path: f64,
}

/// What a run gives: the moments, and the photons cut at `max_path` and the collisions, for the provenance.
pub struct WalkResult {
    pub moments: SliceMoments,
    pub cut: u64,
    pub collisions: u64,
}

const CHUNK: u64 = 8192;

fn chunk_seed(seed: u64, chunk: u64) -> u64 {
    let mut z = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ chunk.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[inline(always)]
fn uniform(rng: &mut Pcg64Mcg) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Unpolarised Fresnel reflectance from inside (index `n` to air) at cosine `c`; 1 beyond the critical angle.
fn fresnel_out(n: f64, c: f64) -> f64 {
    let sin_t2 = n * n * (1.0 - c * c);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - sin_t2).sqrt();
    let rs = (n * c - ct) / (n * c + ct);
    let rp = (n * ct - c) / (n * ct + c);
    0.5 * (rs * rs + rp * rp)
}

/// One photon: its exit radius and path lengths per layer, or None if cut.
fn photon(w: &WhiteWalk, rng: &mut Pcg64Mcg, collisions: &mut u64) -> Option<(f64, f64, f64)> {
    let (mut x, mut y, mut z) = (0.0f64, 0.0f64, 0.0f64);
    let (mut ux, mut uy, mut uz) = (0.0f64, 0.0f64, 1.0f64);
    let (mut l_top, mut l_bottom) = (0.0f64, 0.0f64);
    let mut top = true;
    loop {
        let mut depth = -(1.0 - uniform(rng)).ln();
        loop {
            let sigma = if top { 1.0 } else { w.bottom_scattering };
            let to_boundary = if top {
                if uz > 0.0 {
                    (w.tau - z) / uz
                } else if uz < 0.0 {
                    -z / uz
                } else {
                    f64::INFINITY
                }
            } else if uz < 0.0 {
                (w.tau - z) / uz
            } else {
                f64::INFINITY
            };
            let step = depth / sigma;
            if step < to_boundary {
                x += step * ux;
                y += step * uy;
                z += step * uz;
                if top {
                    l_top += step;
                } else {
                    l_bottom += step;
                }
                break;
            }
            x += to_boundary * ux;
            y += to_boundary * uy;
            depth = (depth - to_boundary * sigma).max(0.0);
            if top {
                l_top += to_boundary;
            } else {
                l_bottom += to_boundary;
            }
            if top && uz < 0.0 {
                z = 0.0;
                if uniform(rng) < fresnel_out(w.ior, -uz) {
                    uz = -uz;
                    continue;
                }
                return Some(((x * x + y * y).sqrt(), l_top, l_bottom));
            }
            z = w.tau;
            top = !top;
        }
        if l_top + l_bottom > w.max_path {
            return None;
        }
        *collisions += 1;
        // Marsaglia (1972): a uniform direction from a point in the unit disc.
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

/// Chunk `c` of the run: its tallies, photons cut and collisions.
fn chunk(w: &WhiteWalk, a_top: &[f64], a_bottom: &[f64], c: u64) -> (Vec<f64>, u64, u64) {
    let (ni, nj) = (a_top.len(), a_bottom.len());
    let mut rng = Pcg64Mcg::seed_from_u64(chunk_seed(w.seed, c));
    let mut sums = vec![0.0f64; FINE_BINS * ni * nj];
    let (mut cut, mut collisions) = (0u64, 0u64);
    let (mut ei, mut ej) = (vec![0.0; ni], vec![0.0; nj]);
    for _ in 0..CHUNK.min(w.photons - c * CHUNK) {
        let Some((r, lt, lb)) = photon(w, &mut rng, &mut collisions) else {
            cut += 1;
            continue;
        };
        ei.iter_mut().zip(a_top).for_each(|(e, a)| *e = (-a * lt).exp());
        ej.iter_mut().zip(a_bottom).for_each(|(e, a)| *e = (-a * lb).exp());
        let row = &mut sums[fine_bin(r) * ni * nj..][..ni * nj];
        for (i, &e) in ei.iter().enumerate() {
            if e != 0.0 {
                row[i * nj..(i + 1) * nj].iter_mut().zip(&ej).for_each(|(s, f)| *s += e * f);
            }
        }
    }
    (sums, cut, collisions)
}

/// Run the walk and tally the moments for every pair of `a_top` x `a_bottom`.
pub fn run(w: &WhiteWalk, a_top: &[f64], a_bottom: &[f64]) -> WalkResult {
    let (ni, nj) = (a_top.len(), a_bottom.len());
    let chunks = w.photons.div_ceil(CHUNK);
    let mut sums = vec![0.0f64; FINE_BINS * ni * nj];
    let (mut cut, mut collisions) = (0, 0);
    // Batches of chunks in parallel, each batch's tallies added in chunk order (bounded memory, same sums for any
    // thread count).
    const BATCH: u64 = 16;
    for first in (0..chunks).step_by(BATCH as usize) {
        let batch: Vec<(Vec<f64>, u64, u64)> =
            (first..(first + BATCH).min(chunks)).into_par_iter().map(|c| chunk(w, a_top, a_bottom, c)).collect();
        for (s, c, n) in batch {
            sums.iter_mut().zip(&s).for_each(|(a, b)| *a += b);
            cut += c;
            collisions += n;
        }
    }
    WalkResult {
        moments: SliceMoments { photons: w.photons, a_top: a_top.to_vec(), a_bottom: a_bottom.to_vec(), sums },
        cut,
        collisions,
    }
}
