//! The exact shape of the skin's radial profile, tabulated once (docs/model.md, Exact radial profile).
//!
//! Adding-doubling gives the exact total; the shape (where the light leaves) needs transport in three dimensions.
//! In the skin model scattering is isotropic with the reduced coefficient, the dermis scatters a fixed fraction of
//! what the epidermis does and both share one index; measured in the epidermis' mean free paths (1/sigma_s' of the top
//! layer), a stack is then three numbers: the epidermis' optical thickness and each layer's absorption per mean free
//! path. The table holds, on a grid of those three, the normalised transform N(k) = R~(k) / R~(0) and the encircled
//! energy per logarithmic radius, from a Monte Carlo of photons that do not absorb ("white"), each exit weighted
//! afterwards by exp(-a_top L_top - a_bottom L_bottom) with its path length in each layer: exact in absorption, with
//! only the photon noise and the interpolation over the grid as errors (Jacques & Prahl's separation of variables;
//! Yoshida & Nishidate 2014). The walk and the table's build are `examples/profile_table.rs`; the table is
//! `data/profile_table.bin`, checked against fresh walks by `tests/physics/exact_profile.rs`.
//!
//! This module holds the table's format, its build from a walk's moments (pure arithmetic) and its lookup; it knows
//! nothing of skin, only of the dimensionless stack.

use std::f64::consts::{LN_10, PI};
use std::sync::OnceLock;

use half::f16;

use crate::error::SkinError;
use crate::layer::Layer;

/// Absorption nodes per layer: log-spaced from [`ABSORPTION_MIN`] to [`ABSORPTION_MAX`] per mean free path.
pub const ABSORPTION_NODES: usize = 24;
/// Smallest tabulated absorption per top-layer mean free path; below it the table's value there is used (a bias in
/// the far tail only: the walk's paths are cut at [`MAX_PATH_MFP`], where exp(-3e-4 x 6e4) = 1.5e-8).
pub const ABSORPTION_MIN: f64 = 3e-4;
/// Largest tabulated absorption per top-layer mean free path (an epidermis absorbing 1000 times what it scatters);
/// above it the table's value there is used.
pub const ABSORPTION_MAX: f64 = 1e3;
/// Top-layer optical thicknesses (in its mean free paths) of the two-layer slices: log-spaced, [`TAU_MIN`] to
/// [`TAU_MAX`]; the skin model's epidermis spans 0.04 (0.01 mm at 780 nm) to 7.3 (0.5 mm at 380 nm).
pub const TAU_NODES: usize = 14;
pub const TAU_MIN: f64 = 0.03;
pub const TAU_MAX: f64 = 10.0;
/// Slices: the two-layer ones, then one of a single semi-infinite layer.
pub const SLICES: usize = TAU_NODES + 1;
/// Photon paths longer than this (in top-layer mean free paths) are cut off by the walk.
pub const MAX_PATH_MFP: f64 = 6e4;
/// Transform nodes: k = 10^(-5 + m/10) per mean free path, m = 0..=90.
pub const K_NODES: usize = 91;
const K_LOG10_MIN: f64 = -5.0;
const NODES_PER_DECADE: f64 = 10.0;
/// Encircled-energy bins: edges r = 10^(-5 + c/10) mean free paths, c = 0..=90.
pub const R_BINS: usize = 90;
const R_LOG10_MIN: f64 = -5.0;
/// Fine radial bins per coarse bin in the walk's tally (the transform's J0 is averaged over each fine bin).
pub const FINE_PER_COARSE: usize = 4;
/// The walk's fine bins: the R_BINS x FINE_PER_COARSE log bins, then one below r = 1e-5 and one beyond r = 1e4.
pub const FINE_BINS: usize = R_BINS * FINE_PER_COARSE + 2;
/// Values stored per table entry: the total, N at every k node, the encircled energy per ln r in every bin.
const ENTRY_LEN: usize = 1 + K_NODES + R_BINS;
const MAGIC: &[u8; 8] = b"SSPRTAB1";

/// The absorption nodes, per top-layer mean free path.
pub fn absorption_nodes() -> Vec<f64> {
    log_nodes(ABSORPTION_MIN, ABSORPTION_MAX, ABSORPTION_NODES)
}

/// The top-layer thicknesses of the two-layer slices, in its mean free paths.
pub fn tau_nodes() -> Vec<f64> {
    log_nodes(TAU_MIN, TAU_MAX, TAU_NODES)
}

/// The transform's nodes k, per mean free path.
pub fn k_nodes() -> Vec<f64> {
    (0..K_NODES).map(|m| 10f64.powf(K_LOG10_MIN + m as f64 / NODES_PER_DECADE)).collect()
}

/// Edge `f` of the fine radial bins (f = 0..=R_BINS * FINE_PER_COARSE), in mean free paths.
pub fn fine_edge(f: usize) -> f64 {
    10f64.powf(R_LOG10_MIN + f as f64 / (NODES_PER_DECADE * FINE_PER_COARSE as f64))
}

/// The fine bin of an exit radius `r` (mean free paths): 0 below the first edge, FINE_BINS - 1 beyond the last.
pub fn fine_bin(r: f64) -> usize {
    // NaN and radii below the first edge go to bin 0.
    if r.is_nan() || r < fine_edge(0) {
        return 0;
    }
    let f = ((r.log10() - R_LOG10_MIN) * NODES_PER_DECADE * FINE_PER_COARSE as f64).floor();
    if f >= (R_BINS * FINE_PER_COARSE) as f64 {
        FINE_BINS - 1
    } else {
        f as usize + 1
    }
}

fn log_nodes(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64)).collect()
}

/// What a walk tallied for one slice: per fine radial bin, the summed weights exp(-a_top L_top - a_bottom L_bottom)
/// of the photons that left there, for every pair of the absorptions it was given.
#[derive(Debug, Clone)]
pub struct SliceMoments {
    pub photons: u64,
    /// Absorptions of the top layer the weights were summed for (per mean free path).
    pub a_top: Vec<f64>,
    /// Absorptions of the bottom layer.
    pub a_bottom: Vec<f64>,
    /// `[bin][i][j]`, FINE_BINS x a_top.len() x a_bottom.len().
    pub sums: Vec<f64>,
}

/// One stack's entry: the total reflectance the walk found, N(k) at the k nodes and the encircled energy per ln r.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeEntry {
    pub total: f64,
    pub transform: Vec<f64>,
    pub energy_per_ln_r: Vec<f64>,
}

/// The entries of every absorption pair of `m` (`[i][j]` order): the walk's moments turned into the table's values.
pub fn entries_from_moments(m: &SliceMoments) -> Vec<ShapeEntry> {
    let (ni, nj) = (m.a_top.len(), m.a_bottom.len());
    let mean_j0 = mean_j0_per_fine_bin();
    let width = LN_10 / NODES_PER_DECADE;
    let mut out = Vec::with_capacity(ni * nj);
    for ij in 0..ni * nj {
        let at = |b: usize| m.sums[b * ni * nj + ij];
        let sum: f64 = (0..FINE_BINS).map(at).sum();
        let total = sum / m.photons as f64;
        let transform = (0..K_NODES)
            .map(|q| if sum > 0.0 { (0..FINE_BINS).map(|b| at(b) * mean_j0[b][q]).sum::<f64>() / sum } else { 1.0 })
            .collect();
        let energy_per_ln_r = (0..R_BINS)
            .map(|c| {
                let inside: f64 = (0..FINE_PER_COARSE).map(|f| at(1 + c * FINE_PER_COARSE + f)).sum();
                if sum > 0.0 {
                    inside / sum / width
                } else {
                    0.0
                }
            })
            .collect();
        out.push(ShapeEntry { total, transform, energy_per_ln_r });
    }
    out
}

/// J0(k r) averaged over each fine bin (r uniform in the bin: a 1/r profile, the near field's; 8-point
/// Gauss-Legendre), at every k node. The bin below the first edge is [0, edge 0]; the one beyond the last is taken at
/// 1.5 times the last edge (no walk of MAX_PATH_MFP reaches it).
fn mean_j0_per_fine_bin() -> Vec<Vec<f64>> {
    let (x, w) = crate::numeric::gauss_legendre(8);
    let k = k_nodes();
    let last = R_BINS * FINE_PER_COARSE;
    (0..FINE_BINS)
        .map(|b| {
            if b == FINE_BINS - 1 {
                let r = 1.5 * fine_edge(last);
                return k.iter().map(|&kq| libm::j0(kq * r)).collect();
            }
            let (lo, hi) = if b == 0 { (0.0, fine_edge(0)) } else { (fine_edge(b - 1), fine_edge(b)) };
            k.iter()
                .map(|&kq| {
                    x.iter().zip(&w).map(|(xi, wi)| 0.5 * wi * libm::j0(kq * (lo + 0.5 * (hi - lo) * (xi + 1.0)))).sum()
                })
                .collect()
        })
        .collect()
}

/// Provenance of a table: how it was built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableProvenance {
    /// Photons per slice.
    pub photons: u64,
    pub seed: u64,
    /// The index of every layer (and of the medium under a finite stack), air above.
    pub ior: f64,
    /// Scattering of the bottom layer over the top layer's.
    pub bottom_scattering_ratio: f64,
}

/// The table: every slice's entries for every absorption pair, decoded.
#[derive(Debug, Clone)]
pub struct ProfileTable {
    pub provenance: TableProvenance,
    /// SLICES x ABSORPTION_NODES^2 x ENTRY_LEN values.
    values: Vec<f32>,
    id: String,
}

/// Serialise a table: header, then for each slice, each (a_top, a_bottom) pair, the total as f32 and the rest as f16.
pub fn encode_table(provenance: &TableProvenance, slices: &[Vec<ShapeEntry>]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    for v in
        [SLICES as u64, ABSORPTION_NODES as u64, K_NODES as u64, R_BINS as u64, provenance.photons, provenance.seed]
    {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&provenance.ior.to_le_bytes());
    out.extend_from_slice(&provenance.bottom_scattering_ratio.to_le_bytes());
    for slice in slices {
        for e in slice {
            out.extend_from_slice(&(e.total as f32).to_le_bytes());
            for v in e.transform.iter().chain(&e.energy_per_ln_r) {
                out.extend_from_slice(&f16::from_f64(*v).to_le_bytes());
            }
        }
    }
    out
}

impl ProfileTable {
    /// The table compiled into the crate (`data/profile_table.bin`), decoded once per process.
    pub fn shipped() -> &'static ProfileTable {
        static TABLE: OnceLock<ProfileTable> = OnceLock::new();
        TABLE.get_or_init(|| {
            ProfileTable::decode(include_bytes!("../../data/profile_table.bin"))
                .expect("data/profile_table.bin is the format this build reads (examples/profile_table.rs writes it)")
        })
    }

    /// A table from the bytes [`encode_table`] writes.
    pub fn decode(bytes: &[u8]) -> Result<ProfileTable, SkinError> {
        let bad = |why: &str| SkinError::invalid("profile table", why.to_string());
        let header = MAGIC.len() + 6 * 8 + 2 * 8;
        if bytes.len() < header || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad("not a profile table (magic)"));
        }
        let word = |i: usize| {
            let at = MAGIC.len() + 8 * i;
            u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
        };
        let dims = [SLICES, ABSORPTION_NODES, K_NODES, R_BINS].map(|d| d as u64);
        if (0..4).any(|i| word(i) != dims[i]) {
            return Err(bad("grid dimensions differ from this build's"));
        }
        let provenance = TableProvenance {
            photons: word(4),
            seed: word(5),
            ior: f64::from_bits(word(6)),
            bottom_scattering_ratio: f64::from_bits(word(7)),
        };
        let entries = SLICES * ABSORPTION_NODES * ABSORPTION_NODES;
        let entry_bytes = 4 + 2 * (ENTRY_LEN - 1);
        if bytes.len() != header + entries * entry_bytes {
            return Err(bad("length differs from the grid's"));
        }
        let mut values = Vec::with_capacity(entries * ENTRY_LEN);
        for e in bytes[header..].chunks_exact(entry_bytes) {
            values.push(f32::from_le_bytes(e[..4].try_into().expect("4 bytes")));
            values.extend(e[4..].chunks_exact(2).map(|h| f16::from_le_bytes([h[0], h[1]]).to_f32()));
        }
        let mut hasher = fnv::FnvHasher::default();
        std::hash::Hasher::write(&mut hasher, bytes);
        let id = format!(
            "{} photons seed {} fnv1a {:016x}",
            provenance.photons,
            provenance.seed,
            std::hash::Hasher::finish(&hasher)
        );
        Ok(ProfileTable { provenance, values, id })
    }

    /// The table's identity for cache keys: its provenance and the FNV-1a hash of its bytes.
    pub fn id(&self) -> &str {
        &self.id
    }

    fn entry(&self, slice: usize, i: usize, j: usize) -> &[f32] {
        let at = ((slice * ABSORPTION_NODES + i) * ABSORPTION_NODES + j) * ENTRY_LEN;
        &self.values[at..at + ENTRY_LEN]
    }

    /// The stored entry of node (slice, i, j), for checks against fresh walks.
    pub fn node(&self, slice: usize, i: usize, j: usize) -> ShapeEntry {
        let e = self.entry(slice, i, j);
        ShapeEntry {
            total: e[0] as f64,
            transform: e[1..1 + K_NODES].iter().map(|&v| v as f64).collect(),
            energy_per_ln_r: e[1 + K_NODES..].iter().map(|&v| v as f64).collect(),
        }
    }

    /// The dimensionless stack of `layers` if the table holds it: one semi-infinite layer, or two with the second
    /// semi-infinite, scattering [`TableProvenance::bottom_scattering_ratio`] times the first, the first at most
    /// [`TAU_MAX`] mean free paths thick, every index the table's.
    pub fn stack_of(&self, layers: &[Layer]) -> Option<TableStack> {
        let p = &self.provenance;
        let top = layers.first()?;
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        if !layers.iter().all(|l| same(l.ior, p.ior))
            || top.sigma_s_reduced_per_mm.is_nan()
            || top.sigma_s_reduced_per_mm <= 0.0
        {
            return None;
        }
        let mfp_mm = 1.0 / top.sigma_s_reduced_per_mm;
        let a_top = top.sigma_a_per_mm * mfp_mm;
        match layers {
            [one] if one.thickness_mm.is_infinite() => Some(TableStack { tau: None, a_top, a_bottom: a_top, mfp_mm }),
            [_, bottom]
                if bottom.thickness_mm.is_infinite()
                    && same(bottom.sigma_s_reduced_per_mm, p.bottom_scattering_ratio * top.sigma_s_reduced_per_mm) =>
            {
                let tau = top.thickness_mm / mfp_mm;
                (tau <= TAU_MAX).then_some(TableStack {
                    tau: Some(tau),
                    a_top,
                    a_bottom: bottom.sigma_a_per_mm * mfp_mm,
                    mfp_mm,
                })
            }
            _ => None,
        }
    }

    /// The interpolated entry of a stack (Catmull-Rom in the logarithms of thickness and absorptions, clamped to
    /// the grid).
    pub fn shape(&'static self, stack: &TableStack) -> Shape {
        let a_axis =
            |a: f64| axis_weights(log_position(a, ABSORPTION_MIN, ABSORPTION_MAX, ABSORPTION_NODES), ABSORPTION_NODES);
        let wi = a_axis(stack.a_top);
        let wj = match stack.tau {
            Some(_) => a_axis(stack.a_bottom),
            None => [(0, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)],
        };
        let ws = match stack.tau {
            Some(t) => axis_weights(log_position(t, TAU_MIN, TAU_MAX, TAU_NODES), TAU_NODES),
            None => [(TAU_NODES, 1.0), (TAU_NODES, 0.0), (TAU_NODES, 0.0), (TAU_NODES, 0.0)],
        };
        let mut weights = Vec::with_capacity(64);
        for &(sl, a) in &ws {
            for &(i, b) in &wi {
                for &(j, c) in &wj {
                    let w = a * b * c;
                    if w != 0.0 {
                        weights.push((((sl * ABSORPTION_NODES + i) * ABSORPTION_NODES + j) * ENTRY_LEN, w));
                    }
                }
            }
        }
        Shape { mfp_mm: stack.mfp_mm, values: &self.values, weights, profile_integral: OnceLock::new() }
    }
}

/// A stack in the table's terms: the top layer's thickness in its mean free paths (None: one semi-infinite layer),
/// each layer's absorption per top-layer mean free path, and that mean free path in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableStack {
    pub tau: Option<f64>,
    pub a_top: f64,
    pub a_bottom: f64,
    pub mfp_mm: f64,
}

/// One stack's interpolated shape, read at any frequency or radius in mm: the table's entries around the stack and
/// their interpolation weights, combined only at the nodes a value needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    mfp_mm: f64,
    values: &'static [f32],
    /// (offset of an entry in `values`, its weight).
    weights: Vec<(usize, f64)>,
    /// The integral of the interpolated encircled energy per ln r over ln r, computed on first use
    /// ([`Shape::profile_integral`]).
    profile_integral: OnceLock<f64>,
}

impl Shape {
    /// Value `v` of the interpolated entry (0: total, then the transform, then the encircled energy).
    fn value(&self, v: usize) -> f64 {
        self.weights.iter().map(|&(at, w)| w * self.values[at + v] as f64).sum()
    }

    /// Values `first..first + len` of the interpolated entry: for each value the weighted sum over the entries in the
    /// order of `weights` (the same sums, to the bit, as adding entry after entry into the whole range), formed
    /// [`COMBINE_CHUNK`] values at a time in registers. Measured on the exact_speed bench (evaluate albedo + radius):
    /// entry after entry over the whole range loaded and stored every partial sum, 28 % of the time.
    fn combined(&self, first: usize, len: usize) -> Vec<f64> {
        let mut out = vec![0.0; len];
        let mut chunks = out.chunks_exact_mut(COMBINE_CHUNK);
        for (c, chunk) in chunks.by_ref().enumerate() {
            let start = first + c * COMBINE_CHUNK;
            let mut sum = [0.0; COMBINE_CHUNK];
            for &(at, w) in &self.weights {
                let entry: &[f32; COMBINE_CHUNK] =
                    self.values[at + start..at + start + COMBINE_CHUNK].try_into().expect("a chunk");
                sum.iter_mut().zip(entry).for_each(|(v, &e)| *v += w * e as f64);
            }
            chunk.copy_from_slice(&sum);
        }
        let rest = chunks.into_remainder();
        let start = first + len - rest.len();
        for &(at, w) in &self.weights {
            rest.iter_mut().zip(&self.values[at + start..]).for_each(|(v, &e)| *v += w * e as f64);
        }
        out
    }

    /// The encircled energy per ln r of bin `c`, >= 0.
    fn q(&self, c: usize) -> f64 {
        self.value(1 + K_NODES + c).max(0.0)
    }

    /// N(s) = R~(s) / R~(0) at `s_per_mm` (radians per mm): linear in log k between the nodes; below the first node
    /// 1 - c k^2 (the second moment's term), above the last N ~ 1/k (the single scattering's 1/r near field).
    pub fn normalized_transform(&self, s_per_mm: f64) -> f64 {
        self.normalized_transforms(&[s_per_mm])[0]
    }

    /// [`Shape::normalized_transform`] at each of `s_per_mm`: the nodes they need interpolated once, entry by entry
    /// over contiguous values (a radius fit reads 33 frequencies: 5 times faster than node by node).
    pub fn normalized_transforms(&self, s_per_mm: &[f64]) -> Vec<f64> {
        let positions: Vec<f64> =
            s_per_mm.iter().map(|&s| ((s * self.mfp_mm).log10() - K_LOG10_MIN) * NODES_PER_DECADE).collect();
        let last = K_NODES - 1;
        // x > 0 wherever it is truncated below, so `as usize` is its floor (without the libm call that `floor` is
        // on plain x86-64, which has no SSE4.1 rounding instruction).
        let node = |x: f64| if x.is_nan() || x <= 0.0 { 0 } else { (x as usize).min(last) };
        let lo = positions.iter().map(|&x| node(x)).min().unwrap_or(0);
        let hi = positions.iter().map(|&x| (node(x) + 1).min(last)).max().unwrap_or(0);
        let mut n = self.combined(1 + lo, hi + 1 - lo);
        n.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0));
        let n_at = |m: usize| n[m - lo];
        positions
            .iter()
            .zip(s_per_mm)
            .map(|(&x, &s)| {
                if x.is_nan() || x <= 0.0 {
                    let k0 = 10f64.powf(K_LOG10_MIN);
                    return 1.0 - (1.0 - n_at(0)) * (s * self.mfp_mm / k0).powi(2);
                }
                if x >= last as f64 {
                    return n_at(last) * 10f64.powf((x - last as f64) / NODES_PER_DECADE).recip();
                }
                let i = x as usize;
                let t = x - i as f64;
                let (a, b) = (n_at(i), n_at(i + 1));
                a + t * (b - a)
            })
            .collect()
    }

    /// The integral over ln r of the encircled energy per ln r as [`Shape::normalized_profile_per_mm2`]
    /// interpolates it: q0 for the disc below the first centre, then each log-linear piece exactly. The bins hold a
    /// unit total, but a log-linear piece under a peak falls below its chord, so the interpolant holds about 0.3 %
    /// less (measured 0.25-0.37 % on the presets' stacks): dividing by this makes the profile integrate to the total.
    fn profile_integral(&self) -> f64 {
        *self.profile_integral.get_or_init(|| {
            let step = LN_10 / NODES_PER_DECADE;
            let q: Vec<f64> = (0..R_BINS).map(|c| self.q(c)).collect();
            q[0] + q.windows(2).map(|w| step * log_linear_piece(w[0], w[1])).sum::<f64>()
        })
    }

    /// The encircled energy at each of `r_mm`: the fraction of the total that leaves within that distance of where
    /// the light entered, the integral (2 pi r dr) of [`Shape::normalized_profile_per_mm2`] from 0 as it interpolates
    /// (q0 r / r0 below the first centre, each log-linear piece in closed form): 0 at 0, rising to 1 at the last
    /// bin's centre. The bins are combined once for all radii.
    pub fn encircled_energy(&self, r_mm: &[f64]) -> Vec<f64> {
        let q: Vec<f64> = self.combined(1 + K_NODES, R_BINS).into_iter().map(|v| v.max(0.0)).collect();
        let step = LN_10 / NODES_PER_DECADE;
        let mut at_centre = Vec::with_capacity(R_BINS);
        let mut sum = q[0];
        at_centre.push(sum);
        for w in q.windows(2) {
            sum += step * log_linear_piece(w[0], w[1]);
            at_centre.push(sum);
        }
        if sum <= 0.0 {
            return vec![0.0; r_mm.len()];
        }
        let r0 = 10f64.powf(R_LOG10_MIN + 0.5 / NODES_PER_DECADE);
        r_mm.iter()
            .map(|&r_mm| {
                // NaN and negative radii count as 0.
                let r = (r_mm / self.mfp_mm).max(0.0);
                let x = (r.log10() - R_LOG10_MIN) * NODES_PER_DECADE - 0.5;
                let inside = if x <= 0.0 {
                    q[0] * r / r0
                } else if x >= (R_BINS - 1) as f64 {
                    sum
                } else {
                    let i = x as usize;
                    at_centre[i] + step * log_linear_integral(q[i], q[i + 1], x - i as f64)
                };
                (inside / sum).min(1.0)
            })
            .collect()
    }

    /// The profile normalised to a unit total, per mm^2, at `r_mm`: the encircled energy per ln r over 2 pi r^2,
    /// interpolated log-linearly between bin centres; below the first centre it follows 1/r (single scattering),
    /// and r = 0 gets the mean over the first centre's disc; beyond the last bin it is 0. Divided by the
    /// interpolant's own integral ([`Shape::profile_integral`]), so it integrates (2 pi r dr) to exactly 1.
    pub fn normalized_profile_per_mm2(&self, r_mm: f64) -> f64 {
        let centre = |c: f64| 10f64.powf(R_LOG10_MIN + (c + 0.5) / NODES_PER_DECADE);
        let r = (r_mm / self.mfp_mm).max(0.0);
        let x = (r.log10() - R_LOG10_MIN) * NODES_PER_DECADE - 0.5;
        let per_mfp2 = if x.is_nan() || x <= 0.0 {
            // q ~ r below the first centre: p = q0 / (2 pi r0 r); the disc r < r0 holds q0 of energy.
            let (r0, q0) = (centre(0.0), self.q(0));
            if r > 0.0 {
                q0 / (2.0 * PI * r0 * r)
            } else {
                q0 / (PI * r0 * r0)
            }
        } else if x >= (R_BINS - 1) as f64 {
            0.0
        } else {
            let (i, t) = (x.floor() as usize, x - x.floor());
            let (a, b) = (self.q(i), self.q(i + 1));
            let value = if a > 0.0 && b > 0.0 { (a.ln() + t * (b.ln() - a.ln())).exp() } else { a + t * (b - a) };
            value / (2.0 * PI * r * r)
        };
        let integral = self.profile_integral();
        if integral > 0.0 {
            per_mfp2 / (self.mfp_mm * self.mfp_mm) / integral
        } else {
            0.0
        }
    }
}

/// The integral over s in [0, t] (t in [0, 1]) of the interpolant between `a` (s = 0) and `b` (s = 1) that
/// [`Shape::normalized_profile_per_mm2`] uses: log-linear where both are positive, linear otherwise.
fn log_linear_integral(a: f64, b: f64, t: f64) -> f64 {
    if a > 0.0 && b > 0.0 && (a - b).abs() > 1e-12 * a.max(b) {
        let ln_ratio = (b / a).ln();
        a * ((t * ln_ratio).exp() - 1.0) / ln_ratio
    } else {
        a * t + 0.5 * (b - a) * t * t
    }
}

/// [`log_linear_integral`] over the whole piece (t = 1), without its exponential: (b - a) / ln(b / a) (the profile's
/// integral and the encircled energy's bins).
fn log_linear_piece(a: f64, b: f64) -> f64 {
    if a > 0.0 && b > 0.0 && (a - b).abs() > 1e-12 * a.max(b) {
        (b - a) / (b / a).ln()
    } else {
        0.5 * (a + b)
    }
}

/// Position of `v` on a log grid of `n` nodes from `lo` to `hi`, in node units, clamped to [0, n - 1].
fn log_position(v: f64, lo: f64, hi: f64, n: usize) -> f64 {
    let x = (v.max(f64::MIN_POSITIVE).ln() - lo.ln()) / (hi / lo).ln() * (n - 1) as f64;
    x.clamp(0.0, (n - 1) as f64)
}

/// Catmull-Rom weights of the four nodes around position `x` on an axis of `n` nodes (n >= 2): the node indices
/// are clamped to the axis, so the end intervals repeat their end node.
fn axis_weights(x: f64, n: usize) -> [(usize, f64); 4] {
    let i = x.floor() as isize;
    let t = x - i as f64;
    let (t2, t3) = (t * t, t * t * t);
    let w = [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ];
    let last = n.saturating_sub(1) as isize;
    [0, 1, 2, 3].map(|o| ((i - 1 + o).clamp(0, last) as usize, w[o as usize]))
}

/// Values [`Shape::combined`] sums at a time: eight f64 partial sums stay in registers (four SSE2 registers).
const COMBINE_CHUNK: usize = 8;

/// The exact shape of `layers` from the shipped table, if it holds the stack ([`ProfileTable::stack_of`]).
pub fn exact_shape(layers: &[Layer]) -> Option<Shape> {
    let table = ProfileTable::shipped();
    table.stack_of(layers).map(|s| table.shape(&s))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Shape::combined`] gives, to the bit, the sums of adding the weighted entries one after another over the whole
    /// range (what `normalized_transforms` did before it), for stacks inside, at and beyond the grid's ends, over
    /// ranges of every length from 0 to the whole transform.
    #[test]
    fn combined_is_entry_after_entry_to_the_bit() {
        let table = ProfileTable::shipped();
        let stacks = [
            TableStack { tau: Some(0.7), a_top: 0.02, a_bottom: 0.004, mfp_mm: 0.05 },
            TableStack { tau: Some(TAU_MAX), a_top: ABSORPTION_MIN, a_bottom: 5.0, mfp_mm: 0.1 },
            TableStack { tau: Some(0.01), a_top: 2e3, a_bottom: 1e-6, mfp_mm: 0.02 },
            TableStack { tau: None, a_top: 0.3, a_bottom: 0.3, mfp_mm: 1.0 },
        ];
        for stack in &stacks {
            let shape = table.shape(stack);
            for (first, len) in (0..=K_NODES).map(|len| (1, len)).chain([(5, 80), (38, 17), (1 + K_NODES - 9, 9)]) {
                let mut plain = vec![0.0; len];
                for &(at, w) in &shape.weights {
                    let entry = &shape.values[at + first..at + first + len];
                    plain.iter_mut().zip(entry).for_each(|(v, &e)| *v += w * e as f64);
                }
                let combined = shape.combined(first, len);
                assert!(
                    combined.iter().zip(&plain).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{stack:?} {first} {len}"
                );
            }
        }
    }
}
