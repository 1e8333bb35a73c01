//! A lookup table of the material outputs over (C_m, beta_m, C_h), built once in parallel and interpolated per texel.
//!
//! Axes are warped so that equal steps mean similar changes in colour: cube roots for the two concentrations (the
//! optical effect of a chromophore saturates: from 0.005 to 0.05 changes skin more than from 0.45 to 0.5; Jimenez et
//! al. 2010 sample C_m and C_h on cube-root axes too), linear for the melanin blend. The table stores the natural
//! logarithm of each output (all positive, spanning decades) and interpolates trilinearly. Its error against direct
//! evaluation is measured, not assumed: see `measure_error` and `tests/maps/maps_pipeline.rs`.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;
use serde::Serialize;

use super::io::write_atomic;
use crate::error::SkinError;
use crate::evaluate::{Material, Prepared, Request};
use crate::fit::SubsurfaceMethod;
use crate::skin::params::{EXTENDED_DEFAULTS, EXTENDED_PARAMS, HEMOGLOBIN, MELANIN, MELANIN_BLEND};
use crate::skin::SkinParams;
use crate::surface::lobes::SurfaceModel;

/// Outputs per texel that depend on (C_m, beta_m, C_h), for one subsurface method on the request's target: the
/// model's albedo, and the method's Base Color and Subsurface Radius there (for EEVEE the radius is compensated per
/// texel, from that texel's albedo, before it is tabulated).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TexelMaterial {
    pub albedo: [f32; 3],
    pub base_color: [f32; 3],
    pub radius_mm: [f32; 3],
}

/// Values stored per table node.
const STORED: usize = 9;

impl TexelMaterial {
    /// `method`'s part of a material; an error if the material's target does not offer it.
    pub fn of(m: &Material, method: SubsurfaceMethod) -> Result<Self, SkinError> {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        let p = m.methods.get(method).ok_or_else(|| {
            SkinError::invalid("subsurface method", format!("{} is not offered by this target", method.name()))
        })?;
        Ok(TexelMaterial { albedo: f(m.albedo), base_color: f(p.base_color), radius_mm: f(p.subsurface_radius_mm) })
    }

    /// A material computed without its radius (`Prepared::albedo`): Base Color is the albedo (that of a material
    /// without subsurface, whatever the method) and the radius is zero (not computed).
    pub fn albedo_only(albedo: [f64; 3]) -> Self {
        let a = albedo.map(|x| x as f32);
        TexelMaterial { albedo: a, base_color: a, radius_mm: [0.0; 3] }
    }

    fn to_array(self) -> [f32; STORED] {
        let mut a = [0.0; STORED];
        a[0..3].copy_from_slice(&self.albedo);
        a[3..6].copy_from_slice(&self.base_color);
        a[6..9].copy_from_slice(&self.radius_mm);
        a
    }

    fn from_array(a: [f32; STORED]) -> Self {
        TexelMaterial { albedo: [a[0], a[1], a[2]], base_color: [a[3], a[4], a[5]], radius_mm: [a[6], a[7], a[8]] }
    }
}

/// Smallest value stored before taking the logarithm (outputs are positive; this guards underflow).
const MIN_STORED: f32 = 1e-30;
/// Largest value stored (outputs are reflectances near 1 and radii of millimetres; this keeps exp() of every
/// interpolated logarithm a finite f32, whatever a cache file holds).
const MAX_STORED: f32 = 1e30;

/// The stored form of an output: its logarithm, clamped into [ln MIN_STORED, ln MAX_STORED].
fn stored_log(value: f32) -> f32 {
    value.clamp(MIN_STORED, MAX_STORED).ln()
}

/// True for a value [`stored_log`] can give (a cache file holding anything else is damaged).
fn is_stored_log(x: f32) -> bool {
    (MIN_STORED.ln()..=MAX_STORED.ln()).contains(&x)
}

/// Nodes per axis: melanin, melanin blend, haemoglobin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct TableResolution {
    pub melanin: usize,
    pub melanin_blend: usize,
    pub hemoglobin: usize,
}

impl Default for TableResolution {
    /// Chosen by measurement (docs/maps-performance.md): the smallest grid whose worst error over the domain is below
    /// 0.5 % in albedo and 1 % in radius. The exact profile shapes bend the radius more along the melanin blend
    /// than the multipole did: 7 blend nodes gave 1.13 % (Burley, C_m 0.39, beta_m 0.08), 9 give 0.74 %.
    fn default() -> Self {
        TableResolution { melanin: 33, melanin_blend: 9, hemoglobin: 17 }
    }
}

/// Most nodes a table may have: 10^6 (48 MB, minutes to build on a few cores; the default has 5049). Past it a build
/// would run for hours: refused before any allocation.
pub const MAX_TABLE_NODES: usize = 1_000_000;
/// Most points `measure_error` evaluates (each is one direct evaluation, about a millisecond).
pub const MAX_TABLE_CHECK_SAMPLES: usize = 1_000_000;

impl TableResolution {
    pub fn node_count(&self) -> usize {
        self.melanin.saturating_mul(self.melanin_blend).saturating_mul(self.hemoglobin)
    }

    /// At least 2 nodes per axis, at most `MAX_TABLE_NODES` in all.
    pub fn validate(&self) -> Result<(), SkinError> {
        let r = self;
        if r.melanin < 2 || r.melanin_blend < 2 || r.hemoglobin < 2 || r.node_count() > MAX_TABLE_NODES {
            return Err(SkinError::invalid(
                "table resolution",
                format!("need 2 or more nodes per axis and at most {MAX_TABLE_NODES} in all; got {r:?}"),
            ));
        }
        Ok(())
    }
}

/// The warp of a concentration axis (melanin, haemoglobin), shared by the maps' tables and the albedo fit's: the
/// cube root of the share of the maximum, u = (C / C_max)^(1/3), clamped to [0, 1]. Inverse: [`unwarp`].
pub(crate) fn warp(value: f64, max: f64) -> f64 {
    cbrt_unit(share(value, 1.0 / max))
}

/// The share C / C_max of a concentration, clamped to [0, 1], as C * (1 / C_max): a multiplication by a constant
/// instead of a division (the row lookup does two per texel; a division costs as much as eight multiplications).
/// It may differ from C / C_max in the last bit, the same way wherever the table is read.
#[inline(always)]
fn share(value: f64, inverse_max: f64) -> f64 {
    (value * inverse_max).clamp(0.0, 1.0)
}

/// Cube root of `x` in [0, 1] (NaN passes through), within two ulps of `f64::cbrt` (the result places a texel in
/// the table's cells; nothing needs more). A bit-level first guess (Kahan's, on the f32 bits: relative error below
/// 4 %) is refined by three Halley steps in f64, each of which cubes the relative error (4e-2 -> 6e-5 -> 2e-13 ->
/// round-off). It replaces the libm call, which perf showed taking a quarter of a 4096² table run's CPU time
/// (docs/maps-performance.md).
#[inline]
fn cbrt_unit(x: f64) -> f64 {
    if x.is_nan() || x < CBRT_NORMAL_MIN {
        return x.cbrt(); // zero, tiny values, NaN
    }
    cbrt_normal(x)
}

/// The least `x` [`cbrt_normal`] takes: f32's least normal, so that its first guess is made from a normal f32.
const CBRT_NORMAL_MIN: f64 = f32::MIN_POSITIVE as f64;

/// [`cbrt_unit`] of `x` in [[`CBRT_NORMAL_MIN`], 1], without the branch, so that [`MaterialTable::lookup_method_rows`]'s
/// loop over a run of texels vectorises (any other input gives some finite or NaN value, never a trap). The first
/// guess divides the f32 bits by 3: a u32 division by a constant, which vectorises (the f64 bits' u64 division did
/// not: a sixth of the row lookup's time went to it, one lane at a time).
#[inline(always)]
fn cbrt_normal(x: f64) -> f64 {
    // fdlibm's cbrtf constant B1 (709958130 = 0x2A5137A0): (127 - 127/3 - 0.03306235651) * 2^23.
    let x_f32 = x as f32;
    let guess = f32::from_bits(x_f32.to_bits() / 3 + 0x2A51_37A0);
    let guess3 = guess * guess * guess;
    let mut y = f64::from(guess * ((guess3 + 2.0 * x_f32) / (2.0 * guess3 + x_f32)));
    for _ in 0..2 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

/// Texels [`MaterialTable::lookup_method_rows`] works on at once (its scratch lives on the stack: 4 KiB).
const RUN: usize = 64;

/// e^x for the interpolated logarithms, x in [ln 1e-30, ln 1e30] (weighted means of stored values), within 2 ulps
/// of `f32::exp` there (unit test below); NaN passes through. Cephes' `expf`: x = n ln 2 + r with n the nearest
/// integer to x / ln 2 (found by adding 1.5 * 2^23, which rounds to an integer, instead of a libm call) and ln 2 in
/// two parts, e^r by its degree-7 polynomial, 2^n put into the exponent bits. Written without branches or calls so
/// that the compiler vectorises [`MaterialTable::lookup_method`]'s six at once: the libm calls were a fifth of that
/// function's time.
#[inline(always)]
fn exp_stored(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0; // 1.5 * 2^23
    const LN2_HI: f32 = 0.693_359_4; // Cephes C1: ln 2 to 9 bits, so n * LN2_HI is exact for |n| < 2^15
    const LN2_LO: f32 = -2.121_944_4e-4; // Cephes C2: ln 2 - C1
    let shifted = x * std::f32::consts::LOG2_E + ROUND;
    let n = shifted - ROUND;
    let r = x - n * LN2_HI - n * LN2_LO;
    let p = ((((((1.987_569_1e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r + 0.166_666_65)
        * r
        + 0.5)
        * r
        * r)
        + r
        + 1.0;
    // |n| <= 100 here, so 2^n is a normal float: its exponent field is n + 127.
    let n_bits = shifted.to_bits().wrapping_sub(ROUND.to_bits()) as i32;
    p * f32::from_bits(((n_bits + 127) as u32) << 23)
}

/// The concentration at warped coordinate `u` of an axis of maximum `max` (the inverse of [`warp`]).
pub(crate) fn unwarp(u: f64, max: f64) -> f64 {
    max * u.powi(3)
}

/// The table, for one subsurface method on the request's target.
#[derive(Debug, Clone)]
pub struct MaterialTable {
    resolution: TableResolution,
    method: SubsurfaceMethod,
    /// Whether the nodes hold the method's radius and Base Color; false: an albedo-only table (no radius fit at any
    /// node; Base Color is the albedo, the radius zero: [`TexelMaterial::albedo_only`]).
    radius: bool,
    /// The extended physiology every node is evaluated with (epidermis thickness, baseline absorption scale, blood
    /// oxygenation, `crate::skin::params::EXTENDED_PARAMS` order): the table is over the paper's three concentrations,
    /// with these baked in.
    extended: [f64; 3],
    /// ln of the 9 outputs per node; node (i, j, k) at ((i * nb) + j) * nh + k.
    log_values: Vec<[f32; STORED]>,
    /// The method's part of `log_values` (ln Base Color in lanes 0..3, ln radius in 3..6, two lanes of padding), laid
    /// out as one 8-lane row per node so that [`MaterialTable::lookup_method`] adds a corner with one vector
    /// multiply-add.
    method_logs: Vec<[f32; 8]>,
}

impl MaterialTable {
    /// Evaluate every node (in parallel) with `prepared`, for `method` on the request's target.
    pub fn build(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
    ) -> Result<MaterialTable, SkinError> {
        MaterialTable::build_cancellable(prepared, method, resolution, &AtomicBool::new(false), None)
    }

    /// [`MaterialTable::build`] that stops once `cancel` is set: each node reads the flag before it is evaluated,
    /// so the build ends within about one node's evaluation per thread (a millisecond or so), with the error
    /// an error. `tick`, if given, is called about once per percent of the nodes (from the worker threads), so that
    /// a front whose progress callback decides whether to cancel (and sets `cancel`) is asked during a long build
    /// too.
    pub fn build_cancellable(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<MaterialTable, SkinError> {
        MaterialTable::build_outputs(prepared, method, resolution, true, EXTENDED_DEFAULTS, cancel, tick)
    }

    /// [`MaterialTable::build_cancellable`] of a full table (`radius`) or of an albedo-only one, whose nodes cost
    /// one transform value per wavelength each and no radius fit, with the extended physiology `extended`
    /// (`EXTENDED_PARAMS` order, each checked against its range) at every node.
    pub fn build_outputs(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        radius: bool,
        extended: [f64; 3],
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<MaterialTable, SkinError> {
        resolution.validate()?;
        prepared.request().target.method_entry(method)?;
        for (spec, value) in EXTENDED_PARAMS.iter().zip(extended) {
            spec.check(value)?;
        }
        let r = resolution;
        let nodes = r.node_count();
        let every = (nodes / 100).max(1);
        let log_values = (0..nodes)
            .into_par_iter()
            .map(|n| {
                SkinError::check_cancel(cancel, "table build")?;
                if let Some(tick) = tick.filter(|_| n % every == 0) {
                    tick();
                }
                let p = with_extended(node_params(r, n), extended);
                Ok(texel_material(prepared, &p, method, radius, cancel)?.to_array().map(stored_log))
            })
            .collect::<Result<Vec<_>, SkinError>>()?;
        Ok(MaterialTable::new(resolution, method, radius, extended, log_values))
    }

    fn new(
        resolution: TableResolution,
        method: SubsurfaceMethod,
        radius: bool,
        extended: [f64; 3],
        log_values: Vec<[f32; STORED]>,
    ) -> MaterialTable {
        let method_logs =
            log_values.iter().map(|v| std::array::from_fn(|q| if q < 6 { v[3 + q] } else { 0.0 })).collect();
        MaterialTable { resolution, method, radius, extended, log_values, method_logs }
    }

    /// The extended physiology baked into every node (`crate::skin::params::EXTENDED_PARAMS` order).
    pub fn extended(&self) -> [f64; 3] {
        self.extended
    }

    /// Whether the table holds the method's radius (false: an albedo-only table).
    pub fn has_radius(&self) -> bool {
        self.radius
    }

    /// The method the table holds.
    pub fn method(&self) -> SubsurfaceMethod {
        self.method
    }

    pub fn resolution(&self) -> TableResolution {
        self.resolution
    }

    /// How many nodes the table has.
    pub fn node_count(&self) -> usize {
        self.log_values.len()
    }

    /// The warped coordinates (u_m, melanin blend share, u_h), each in [0, 1], of node `n` (node (i, j, k) is
    /// `n = ((i * nb) + j) * nh + k`).
    pub fn node_warped(&self, n: usize) -> [f64; 3] {
        let r = self.resolution;
        let at = |idx: usize, count: usize| idx as f64 / (count - 1) as f64;
        [
            at(n / (r.hemoglobin * r.melanin_blend), r.melanin),
            at((n / r.hemoglobin) % r.melanin_blend, r.melanin_blend),
            at(n % r.hemoglobin, r.hemoglobin),
        ]
    }

    /// The albedo (the model's total diffuse reflectance, working-space RGB) stored at node `n`.
    pub fn node_albedo(&self, n: usize) -> [f64; 3] {
        let v = &self.log_values[n];
        [v[0], v[1], v[2]].map(|l| (l as f64).exp())
    }

    /// The albedo at warped coordinates `u` = (u_m, melanin blend share, u_h) (each clamped to [0, 1]): the stored
    /// logarithms interpolated trilinearly in f64 and exponentiated. The albedo fit differentiates this by finite
    /// differences of 1e-4 in `u`, which the f32 cell weights of the texture lookups ([`MaterialTable::lookup`])
    /// would quantise.
    pub fn albedo_at_warped(&self, u: [f64; 3]) -> [f64; 3] {
        let r = self.resolution;
        let axis = |u: f64, n: usize| {
            let x = u.clamp(0.0, 1.0) * (n - 1) as f64;
            let i = (x as usize).min(n - 2);
            (i, x - i as f64)
        };
        let (i, ti) = axis(u[0], r.melanin);
        let (j, tj) = axis(u[1], r.melanin_blend);
        let (k, tk) = axis(u[2], r.hemoglobin);
        let (di, dj) = (r.melanin_blend * r.hemoglobin, r.hemoglobin);
        let corner = (i * r.melanin_blend + j) * r.hemoglobin + k;
        let mut out = [0.0f64; 3];
        for (oi, wi) in [(0, 1.0 - ti), (di, ti)] {
            for (oj, wj) in [(0, 1.0 - tj), (dj, tj)] {
                for (ok, wk) in [(0, 1.0 - tk), (1, tk)] {
                    let v = &self.log_values[corner + oi + oj + ok];
                    for c in 0..3 {
                        out[c] += wi * wj * wk * v[c] as f64;
                    }
                }
            }
        }
        out.map(f64::exp)
    }

    /// ln of Base Color and of radius (mm) at node (i, j, k) = (melanin, melanin blend, haemoglobin) indices.
    pub fn node_log_method(&self, i: usize, j: usize, k: usize) -> ([f32; 3], [f32; 3]) {
        let r = self.resolution;
        let v = &self.log_values[(i * r.melanin_blend + j) * r.hemoglobin + k];
        ([v[3], v[4], v[5]], [v[6], v[7], v[8]])
    }

    /// Base Color and radius (mm) of the table's method: the part of [`MaterialTable::lookup`] a texture needs, the
    /// same interpolation on the 8-lane rows of `method_logs`.
    #[inline]
    pub fn lookup_method(&self, melanin: f32, melanin_blend: f32, hemoglobin: f32) -> ([f32; 3], [f32; 3]) {
        let (corner, [ti, tj, tk]) = self.cell(melanin, melanin_blend, hemoglobin);
        let r = self.resolution;
        let (di, dj) = (r.melanin_blend * r.hemoglobin, r.hemoglobin);
        let v = &self.method_logs;
        let out = trilinear_row(v, corner, di, dj, [ti, tj, tk]);
        let e = out.map(exp_stored);
        ([e[0], e[1], e[2]], [e[3], e[4], e[5]])
    }

    /// [`MaterialTable::lookup_method`] of a row of texels: the parameters in `melanin`, `melanin_blend`,
    /// `hemoglobin`, Base Color written into `base_color`'s three slices and the radius (mm) into `radius_mm`'s (all
    /// the same length; empty radius slices: not written). Bit for bit the same values, faster: the axis warps (the
    /// two cube roots), the interpolation and the exponentials each run as a loop over a run of texels, which the
    /// compiler vectorises (the texels' divisions overlap instead of waiting on each other), and a texel equal to its
    /// left neighbour is not looked up again.
    pub fn lookup_method_rows(
        &self,
        melanin: &[f32],
        melanin_blend: &[f32],
        hemoglobin: &[f32],
        base_color: [&mut [f32]; 3],
        radius_mm: [&mut [f32]; 3],
    ) {
        let n = melanin.len();
        assert!(melanin_blend.len() == n && hemoglobin.len() == n && base_color.iter().all(|c| c.len() == n));
        let with_radius = !radius_mm[0].is_empty();
        assert!(!with_radius || radius_mm.iter().all(|r| r.len() == n));
        let [c0, c1, c2] = base_color;
        let [r0, r1, r2] = radius_mm;
        let mut outputs: [&mut [f32]; 6] = [c0, c1, c2, r0, r1, r2];
        let planes = if with_radius { 6 } else { 3 };
        let mut logs = [[0f32; 8]; RUN];
        let same = |i: usize, j: usize| {
            (melanin[i].to_bits() == melanin[j].to_bits())
                & (melanin_blend[i].to_bits() == melanin_blend[j].to_bits())
                & (hemoglobin[i].to_bits() == hemoglobin[j].to_bits())
        };
        let repeats = (1..n).map(|i| usize::from(same(i, i - 1))).sum::<usize>();
        if repeats * 4 < n {
            // Few repeats: every texel looked up.
            for start in (0..n).step_by(RUN) {
                let end = n.min(start + RUN);
                self.lookup_run(&melanin[start..end], &melanin_blend[start..end], &hemoglobin[start..end], &mut logs);
                for (q, plane) in outputs.iter_mut().enumerate().take(planes) {
                    for (o, e) in plane[start..end].iter_mut().zip(&logs) {
                        *o = e[q];
                    }
                }
            }
            return;
        }
        // Each texel that repeats its left neighbour's (C_m, beta_m, C_h) exactly (smooth maps stored at a coarse
        // precision have runs of them) is not looked up again: runs of equal tuples are found first, and the values
        // of each run's first texel filled in over the run.
        let (mut m, mut b, mut h) = ([0f32; RUN], [0f32; RUN], [0f32; RUN]);
        let mut runs = [(0usize, 0usize); RUN];
        let mut next = 0;
        while next < n {
            let mut len = 0;
            while len < RUN && next < n {
                let mut end = next + 1;
                while end < n && same(end, next) {
                    end += 1;
                }
                (m[len], b[len], h[len]) = (melanin[next], melanin_blend[next], hemoglobin[next]);
                runs[len] = (next, end);
                len += 1;
                next = end;
            }
            self.lookup_run(&m[..len], &b[..len], &h[..len], &mut logs);
            for (q, plane) in outputs.iter_mut().enumerate().take(planes) {
                for (&(first, end), e) in runs[..len].iter().zip(&logs[..len]) {
                    plane[first..end].fill(e[q]);
                }
            }
        }
    }

    /// The exponentials of the interpolated logarithms (Base Color in lanes 0..3, radius in 3..6) of up to [`RUN`]
    /// texels into `logs`, as [`MaterialTable::lookup_method`] computes them.
    #[inline]
    fn lookup_run(&self, m: &[f32], b: &[f32], h: &[f32], logs: &mut [[f32; 8]; RUN]) {
        lookup_run(&self.method_logs, self.resolution, [m, b, h], logs)
    }

    /// Trilinear interpolation in the warped coordinates of the logarithms. Inputs are clamped to the domain.
    pub fn lookup(&self, melanin: f32, melanin_blend: f32, hemoglobin: f32) -> TexelMaterial {
        let mut out = [0.0f32; STORED];
        self.interpolate(melanin, melanin_blend, hemoglobin, |w, v| {
            for q in 0..STORED {
                out[q] += w * v[q];
            }
        });
        TexelMaterial::from_array(out.map(exp_stored))
    }

    /// Calls `add(weight, node_values)` for the eight corners of the cell around the point.
    #[inline]
    fn interpolate(&self, melanin: f32, melanin_blend: f32, hemoglobin: f32, mut add: impl FnMut(f32, &[f32; STORED])) {
        let r = self.resolution;
        let (corner, [ti, tj, tk]) = self.cell(melanin, melanin_blend, hemoglobin);
        let (di, dj) = (r.melanin_blend * r.hemoglobin, r.hemoglobin);
        for (oi, wi) in [(0, 1.0 - ti), (di, ti)] {
            for (oj, wj) in [(0, 1.0 - tj), (dj, tj)] {
                for (ok, wk) in [(0, 1.0 - tk), (1, tk)] {
                    add(wi * wj * wk, &self.log_values[corner + oi + oj + ok]);
                }
            }
        }
    }

    /// The index of the cell's first corner (the node (i, j, k) at the low end of each axis) and the point's position
    /// in the cell, 0..1 per axis, in the warped coordinates. Inputs are clamped to the domain.
    #[inline]
    fn cell(&self, melanin: f32, melanin_blend: f32, hemoglobin: f32) -> (usize, [f32; 3]) {
        self.cell_of_warped(
            warp(melanin as f64, MELANIN.max),
            (melanin_blend as f64 - MELANIN_BLEND.min) / MELANIN_BLEND.max,
            warp(hemoglobin as f64, HEMOGLOBIN.max),
        )
    }

    /// [`MaterialTable::cell`] from the warped coordinates (u_m, beta_m share, u_h), each clamped to [0, 1].
    #[inline]
    fn cell_of_warped(&self, u_m: f64, u_b: f64, u_h: f64) -> (usize, [f32; 3]) {
        cell_of_warped(self.resolution, u_m, u_b, u_h)
    }

    /// The table for `prepared` and `resolution`: read from `cache_dir` when a table with the same key is there,
    /// else built (and then stored there, best effort). Returns whether it came from the cache.
    pub fn load_or_build(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        cache_dir: Option<&Path>,
    ) -> Result<(MaterialTable, bool), SkinError> {
        MaterialTable::load_or_build_cancellable(prepared, method, resolution, cache_dir, &AtomicBool::new(false), None)
    }

    /// [`MaterialTable::load_or_build`] whose build stops once `cancel` is set (see
    /// [`MaterialTable::build_cancellable`]); a cancelled build is an error and stores nothing in the cache.
    pub fn load_or_build_cancellable(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        cache_dir: Option<&Path>,
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<(MaterialTable, bool), SkinError> {
        MaterialTable::load_or_build_outputs(
            prepared,
            method,
            resolution,
            true,
            EXTENDED_DEFAULTS,
            cache_dir,
            cancel,
            tick,
        )
    }

    /// [`MaterialTable::load_or_build_cancellable`] of a full table (`radius`) or of an albedo-only one, with the
    /// extended physiology `extended` at every node (see [`MaterialTable::build_outputs`]; tables for other outputs
    /// or other extended values are cached under other keys).
    #[allow(clippy::too_many_arguments)]
    pub fn load_or_build_outputs(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        radius: bool,
        extended: [f64; 3],
        cache_dir: Option<&Path>,
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<(MaterialTable, bool), SkinError> {
        let key = cache_key_text(prepared, method, resolution, radius, extended);
        let path = cache_dir.map(|d| d.join(format!("table-{:016x}.bin", fnv1a(key.as_bytes()))));
        if let Some(table) = path.as_deref().and_then(|p| MaterialTable::read(p, &key, method, resolution)) {
            return Ok((MaterialTable { radius, extended, ..table }, true));
        }
        let table = MaterialTable::build_outputs(prepared, method, resolution, radius, extended, cancel, tick)?;
        if let Some(p) = &path {
            // A cache that cannot be written is no error: the table is still good.
            if std::fs::create_dir_all(p.parent().unwrap_or(Path::new("."))).is_ok() {
                let _ = write_atomic(p, &table.to_cache_bytes(&key));
            }
        }
        Ok((table, false))
    }

    /// The cache file: magic, the length of the key (u32) and the key (the whole request that built the table,
    /// [`cache_key_text`]), the FNV-1a checksum of the body (8 bytes), then the body: the three axis sizes (u32) and
    /// the node values (f32); numbers little endian. The checksum covers the key too.
    pub fn to_cache_bytes(&self, key: &str) -> Vec<u8> {
        let r = self.resolution;
        let mut body = Vec::with_capacity(key.len() + 16 + self.log_values.len() * STORED * 4);
        body.extend_from_slice(&(key.len() as u32).to_le_bytes());
        body.extend_from_slice(key.as_bytes());
        for n in [r.melanin, r.melanin_blend, r.hemoglobin] {
            body.extend_from_slice(&(n as u32).to_le_bytes());
        }
        for v in &self.log_values {
            for x in v {
                body.extend_from_slice(&x.to_le_bytes());
            }
        }
        let mut bytes = Vec::with_capacity(CACHE_MAGIC.len() + 8 + body.len());
        bytes.extend_from_slice(CACHE_MAGIC);
        bytes.extend_from_slice(&fnv1a(&body).to_le_bytes());
        bytes.extend_from_slice(&body);
        bytes
    }

    /// A cached table, or None if the file is missing or not the table of `key` (see
    /// [`MaterialTable::from_cache_bytes`]), so that the caller rebuilds it.
    fn read(path: &Path, key: &str, method: SubsurfaceMethod, resolution: TableResolution) -> Option<MaterialTable> {
        MaterialTable::from_cache_bytes(&std::fs::read(path).ok()?, key, method, resolution)
    }

    /// The table in the bytes of a cache file (the format of [`MaterialTable::to_cache_bytes`]), or None if they are
    /// not a whole, undamaged table of the request `key` at `resolution`: another magic or size, a checksum mismatch
    /// (any flipped byte), a table another request built (its stored key differs: another method, boundaries,
    /// transport, accuracy or extended physiology, even under this request's file name), or a value a build cannot
    /// have stored (not finite, or a logarithm outside [ln 1e-30, ln 1e30]). A table it returns interpolates to
    /// finite positive values everywhere.
    pub fn from_cache_bytes(
        bytes: &[u8],
        key: &str,
        method: SubsurfaceMethod,
        resolution: TableResolution,
    ) -> Option<MaterialTable> {
        let rest = bytes.strip_prefix(CACHE_MAGIC)?;
        let checksum = u64::from_le_bytes(rest.get(..8)?.try_into().ok()?);
        let body = &rest[8..];
        if fnv1a(body) != checksum {
            return None;
        }
        let key_len = u32::from_le_bytes(body.get(..4)?.try_into().ok()?) as usize;
        if body.get(4..4 + key_len)? != key.as_bytes() {
            return None;
        }
        let body = &body[4 + key_len..];
        let header: Vec<usize> =
            body.get(..12)?.chunks(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize).collect();
        let r = resolution;
        if header != [r.melanin, r.melanin_blend, r.hemoglobin] || body.len() != 12 + r.node_count() * STORED * 4 {
            return None;
        }
        let floats: Vec<f32> = body[12..].chunks(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        if !floats.iter().all(|&x| is_stored_log(x)) {
            return None;
        }
        let log_values = floats.chunks(STORED).map(|c| std::array::from_fn(|q| c[q])).collect();
        Some(MaterialTable::new(resolution, method, true, EXTENDED_DEFAULTS, log_values))
    }
}

/// First bytes of a cached table file (v4: the file carries the whole request that built it, checked on reading;
/// v3 and older files are not read and get rebuilt).
pub const CACHE_MAGIC: &[u8] = b"spectral-skin table v4
";

/// 64-bit FNV-1a (Fowler, Noll & Vo; the `fnv` crate, the crate's one hasher): stable across runs, platforms and
/// versions, as a file's name and checksum need; detects any single flipped byte and, with probability 1 - 2^-64, any
/// other corruption.
fn fnv1a(bytes: &[u8]) -> u64 {
    use std::hash::Hasher;
    let mut hasher = fnv::FnvHasher::default();
    hasher.write(bytes);
    hasher.finish()
}

/// FNV-1a hash of everything the table depends on: crate version, request (accuracy, model, working space, target),
/// method (or "albedo only" for a table without radius, which no method changes), resolution and, when any differs
/// from its default, the extended physiology baked in (the paper's model keeps the key it had before the extended
/// physiology existed, so such caches stay valid). Stable across runs and platforms.
pub fn cache_key(
    prepared: &Prepared,
    method: SubsurfaceMethod,
    resolution: TableResolution,
    radius: bool,
    extended: [f64; 3],
) -> u64 {
    fnv1a(cache_key_text(prepared, method, resolution, radius, extended).as_bytes())
}

/// The text [`cache_key`] hashes: the whole request a table is built for. A cache file stores it and is read only
/// for the same text.
pub fn cache_key_text(
    prepared: &Prepared,
    method: SubsurfaceMethod,
    resolution: TableResolution,
    radius: bool,
    extended: [f64; 3],
) -> String {
    // The surface model changes only the specular inputs, which no table holds.
    let request = Request { surface: SurfaceModel::Paper, ..*prepared.request() };
    let mut text = format!(
        "{}|model {}|{}|{}|{:?}",
        env!("CARGO_PKG_VERSION"),
        crate::stamp::MODEL_VERSION,
        serde_json::to_string(&request).unwrap_or_default(),
        if radius { method.name() } else { "albedo only" },
        resolution
    );
    if extended != EXTENDED_DEFAULTS {
        // The exact bits: a table for 0.1 is not reused for the next double.
        let bits: Vec<String> = extended.iter().map(|v| format!("{:016x}", v.to_bits())).collect();
        text.push_str(&format!("|extended {}", bits.join(" ")));
    }
    if radius && prepared.request().transport.exact_shape() {
        // The radius comes from the exact shapes' table: a new table is a new key (an older cache held the multipole's).
        text.push_str(&format!("|shapes {}", crate::transport::profile_table::ProfileTable::shipped().id()));
    }
    text
}

/// `p` with the extended physiology `extended` (`EXTENDED_PARAMS` order).
pub(crate) fn with_extended(p: SkinParams, extended: [f64; 3]) -> SkinParams {
    SkinParams {
        epidermis_thickness_mm: extended[0],
        baseline_absorption_scale: extended[1],
        blood_oxygenation: extended[2],
        ..p
    }
}

/// The material at `p` for a table of `method`: the full material (`radius`), or the albedo alone; stops once
/// `cancel` is set.
fn texel_material(
    prepared: &Prepared,
    p: &SkinParams,
    method: SubsurfaceMethod,
    radius: bool,
    cancel: &AtomicBool,
) -> Result<TexelMaterial, SkinError> {
    if radius {
        TexelMaterial::of(&prepared.material_cancellable(p, cancel)?, method)
    } else {
        Ok(TexelMaterial::albedo_only(prepared.albedo_cancellable(p, cancel)?))
    }
}

/// The per-user cache folder: `$SPECTRAL_SKIN_CACHE_DIR` if set and not empty, else `spectral-skin` in the
/// platform's cache folder (the `dirs` crate: `$XDG_CACHE_HOME` or `~/.cache` on Linux, `~/Library/Caches` on macOS,
/// `%LOCALAPPDATA%` on Windows). None when neither exists.
pub fn default_cache_dir() -> Option<PathBuf> {
    std::env::var_os("SPECTRAL_SKIN_CACHE_DIR")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| dirs::cache_dir().map(|d| d.join("spectral-skin")))
}

/// [`MaterialTable::lookup_run`] over the rows `v` of a table of `resolution`. Compiled also for AVX-512 and AVX2
/// (x86_64) and NEON (aarch64), chosen at run time: the same operations in the same order (no fused multiply-add:
/// Rust does not contract `a * b + c`), so every clone gives the same bits; only the vector width differs (AVX2's 8
/// lanes of f32 instead of SSE2's 4: about twice the lookups per second, docs/maps-performance.md; AVX-512's 16 and
/// its gathers: 7-10 % fewer ns per texel than AVX2 on this project's 2-core Xeon, criterion medians interleaved).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn lookup_run(v: &[[f32; 8]], resolution: TableResolution, [m, b, h]: [&[f32]; 3], logs: &mut [[f32; 8]; RUN]) {
    let len = m.len();
    assert!(len <= RUN && b.len() == len && h.len() == len);
    let r = resolution;
    let (di, dj) = (r.melanin_blend * r.hemoglobin, r.hemoglobin);
    let (mut q_m, mut u_m) = ([0f64; RUN], [0f64; RUN]);
    let (mut q_h, mut u_h) = ([0f64; RUN], [0f64; RUN]);
    // The warps, as `warp` computes them: cube roots of the clamped shares of the maximum.
    for x in 0..len {
        q_m[x] = share(m[x] as f64, 1.0 / MELANIN.max);
        q_h[x] = share(h[x] as f64, 1.0 / HEMOGLOBIN.max);
    }
    for x in 0..len {
        u_m[x] = cbrt_normal(q_m[x]);
        u_h[x] = cbrt_normal(q_h[x]);
    }
    for x in 0..len {
        if q_m[x].is_nan() || q_m[x] < CBRT_NORMAL_MIN {
            u_m[x] = cbrt_unit(q_m[x]);
        }
        if q_h[x].is_nan() || q_h[x] < CBRT_NORMAL_MIN {
            u_h[x] = cbrt_unit(q_h[x]);
        }
    }
    // The cells first, in a loop of their own (it vectorises), then each texel's interpolation (a gather).
    let (mut corner, mut t) = ([0usize; RUN], [[0f32; 3]; RUN]);
    for x in 0..len {
        (corner[x], t[x]) = cell_of_warped(r, u_m[x], (b[x] as f64 - MELANIN_BLEND.min) / MELANIN_BLEND.max, u_h[x]);
    }
    for x in 0..len {
        logs[x] = trilinear_row(v, corner[x], di, dj, t[x]);
    }
    // The exponentials in a loop of their own over every lane of the run (two of each eight are padding), so that
    // independent exponentials overlap instead of each texel waiting on its own polynomial's chain.
    for lane in &mut logs.as_flattened_mut()[..8 * len] {
        *lane = exp_stored(*lane);
    }
}

/// The first corner and the fractions of the cell of a table of resolution `r` around the warped coordinates
/// (u_m, beta_m share, u_h), each clamped to [0, 1] (see [`MaterialTable::cell`]).
#[inline(always)]
fn cell_of_warped(r: TableResolution, u_m: f64, u_b: f64, u_h: f64) -> (usize, [f32; 3]) {
    let axis = |u: f64, n: usize| {
        let x = u.clamp(0.0, 1.0) * (n - 1) as f64;
        // x in [0, n - 1]: truncation is floor, without a libm call; through i32, which vectorises (u64 does not).
        let i = ((x as i32) as usize).min(n - 2);
        (i, (x - i as f64) as f32)
    };
    let (i, ti) = axis(u_m, r.melanin);
    let (j, tj) = axis(u_b, r.melanin_blend);
    let (k, tk) = axis(u_h, r.hemoglobin);
    ((i * r.melanin_blend + j) * r.hemoglobin + k, [ti, tj, tk])
}

/// Trilinear interpolation of the 8-lane rows `v` in the cell whose first node is `corner` (node strides `di` along
/// melanin, `dj` along the melanin blend, 1 along haemoglobin) at the cell fractions `t`.
#[inline(always)] // into each clone of `lookup_run`, with its vector width
fn trilinear_row(v: &[[f32; 8]], corner: usize, di: usize, dj: usize, t: [f32; 3]) -> [f32; 8] {
    let [ti, tj, tk] = t;
    let mut out = [0.0f32; 8];
    for (offset, w) in [
        (0, (1.0 - ti) * (1.0 - tj) * (1.0 - tk)),
        (1, (1.0 - ti) * (1.0 - tj) * tk),
        (dj, (1.0 - ti) * tj * (1.0 - tk)),
        (dj + 1, (1.0 - ti) * tj * tk),
        (di, ti * (1.0 - tj) * (1.0 - tk)),
        (di + 1, ti * (1.0 - tj) * tk),
        (di + dj, ti * tj * (1.0 - tk)),
        (di + dj + 1, ti * tj * tk),
    ] {
        let node = &v[corner + offset];
        for q in 0..8 {
            out[q] += w * node[q];
        }
    }
    out
}

/// The parameters at node n (oiliness does not enter the table).
fn node_params(r: TableResolution, n: usize) -> SkinParams {
    let k = n % r.hemoglobin;
    let j = (n / r.hemoglobin) % r.melanin_blend;
    let i = n / (r.hemoglobin * r.melanin_blend);
    let at = |idx: usize, count: usize| idx as f64 / (count - 1) as f64;
    SkinParams::paper(
        unwarp(at(i, r.melanin), MELANIN.max),
        MELANIN_BLEND.min + at(j, r.melanin_blend) * (MELANIN_BLEND.max - MELANIN_BLEND.min),
        unwarp(at(k, r.hemoglobin), HEMOGLOBIN.max),
        0.0,
    )
}

/// Worst relative error of the table against direct evaluation (an albedo-only table's radius error is 0: it has
/// none).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct TableError {
    pub samples: usize,
    pub max_albedo_relative: f64,
    pub max_radius_relative: f64,
    /// Base Color of the table's method (for Burley and EEVEE the albedo itself).
    pub max_base_color_relative: f64,
}

/// The points `measure_error` checks a table of resolution `r` at, in the warped coordinates (u_m, beta_m, u_h), each
/// in [0, 1]: every other point the centre of a cell (where interpolation error peaks), the others a fixed
/// low-discrepancy sequence (so the figure is reproducible).
pub fn check_points(r: TableResolution, samples: usize) -> Vec<[f64; 3]> {
    let cells = [r.melanin - 1, r.melanin_blend - 1, r.hemoglobin - 1];
    (0..samples)
        .map(|n| {
            // Additive recurrence with the plastic-number constants (R3 sequence), offset 0.5.
            const G: f64 = 1.220_744_084_605_759_5;
            let alpha = [1.0 / G, 1.0 / (G * G), 1.0 / (G * G * G)];
            let u = alpha.map(|a| (0.5 + a * (n + 1) as f64).fract());
            if n % 2 == 0 {
                // Snap every other point to the centre of its cell.
                [0, 1, 2].map(|d| ((u[d] * cells[d] as f64).floor().min(cells[d] as f64 - 1.0) + 0.5) / cells[d] as f64)
            } else {
                u
            }
        })
        .collect()
}

/// The parameters at warped point `u` of [`check_points`] (oiliness 0: it does not enter the table).
pub fn check_point_params(u: [f64; 3]) -> SkinParams {
    SkinParams::paper(
        unwarp(u[0], MELANIN.max),
        MELANIN_BLEND.min + u[1] * (MELANIN_BLEND.max - MELANIN_BLEND.min),
        unwarp(u[2], HEMOGLOBIN.max),
        0.0,
    )
}

/// Measure the table's error at `samples` points: cell centres (where trilinear error peaks) and pseudo-random points
/// (a fixed low-discrepancy sequence, so the figure is reproducible), against `prepared.material` evaluated directly.
pub fn measure_error(table: &MaterialTable, prepared: &Prepared, samples: usize) -> Result<TableError, SkinError> {
    measure_error_cancellable(table, prepared, samples, &AtomicBool::new(false))
}

/// [`measure_error`] that stops once `cancel` is set (read before each point), with an error.
pub fn measure_error_cancellable(
    table: &MaterialTable,
    prepared: &Prepared,
    samples: usize,
    cancel: &AtomicBool,
) -> Result<TableError, SkinError> {
    if samples > MAX_TABLE_CHECK_SAMPLES {
        return Err(SkinError::invalid(
            "table check samples",
            format!("at most {MAX_TABLE_CHECK_SAMPLES} points (each is a direct evaluation); got {samples}"),
        ));
    }
    let points = check_points(table.resolution, samples);
    let errors = points
        .par_iter()
        .map(|u| {
            SkinError::check_cancel(cancel, "table check")?;
            let p = with_extended(check_point_params(*u), table.extended);
            let exact = texel_material(prepared, &p, table.method, table.radius, cancel)?;
            let approx = table.lookup(p.melanin as f32, p.melanin_blend as f32, p.hemoglobin as f32);
            let rel =
                |a: [f32; 3], b: [f32; 3]| (0..3).map(|c| ((a[c] - b[c]) / b[c]).abs() as f64).fold(0.0, f64::max);
            // An albedo-only table has no radius to be wrong about.
            let radius = if table.radius { rel(approx.radius_mm, exact.radius_mm) } else { 0.0 };
            Ok([rel(approx.albedo, exact.albedo), radius, rel(approx.base_color, exact.base_color)])
        })
        .collect::<Result<Vec<_>, SkinError>>()?;
    let max = |q: usize| errors.iter().map(|e| e[q]).fold(0.0, f64::max);
    Ok(TableError {
        samples,
        max_albedo_relative: max(0),
        max_radius_relative: max(1),
        max_base_color_relative: max(2),
    })
}

#[cfg(test)]
mod tests {
    use super::{cbrt_unit, exp_stored, fnv1a, MAX_STORED, MIN_STORED};

    /// The published FNV-1a 64 test vectors (Fowler, Noll & Vo's reference test suite): the cache files' names and
    /// checksums stay what they were when the hash was written by hand.
    #[test]
    fn fnv1a_matches_the_reference_vectors() {
        for (text, expected) in
            [("", 0xcbf2_9ce4_8422_2325u64), ("a", 0xaf63_dc4c_8601_ec8c), ("foobar", 0x8594_4171_f739_67e8)]
        {
            let got = fnv1a(text.as_bytes());
            assert_eq!(got, expected, "fnv1a({text:?}) = {got:016x}, expected {expected:016x}");
        }
    }

    /// Against f64's exp over the whole stored range, densely, in f32 ulps of the correctly rounded result.
    #[test]
    fn exp_is_within_two_ulps_over_the_stored_range() {
        let (lo, hi) = (MIN_STORED.ln(), MAX_STORED.ln());
        let mut worst = 0.0f64;
        for k in 0..=1_000_000u32 {
            let x = lo + (hi - lo) * k as f32 / 1e6;
            let exact = (x as f64).exp();
            let ulp = f64::from(f32::from_bits((exact as f32).to_bits() + 1) - exact as f32);
            worst = worst.max((f64::from(exp_stored(x)) - exact).abs() / ulp);
        }
        assert!(worst <= 2.0, "worst error {worst} ulps");
        assert!(exp_stored(f32::NAN).is_nan(), "{}", exp_stored(f32::NAN));
        assert_eq!(exp_stored(0.0), 1.0);
    }

    /// Against exact cubes (y³ rounded once, so the root is y within 1/3 ulp) and against libm over [0, 1].
    #[test]
    fn cube_root_is_within_two_ulps() {
        let mut worst = 0.0f64;
        for k in 1..=200_000u32 {
            let y = f64::from(k) / 200_000.0;
            worst = worst.max(((cbrt_unit(y * y * y) - y) / y).abs());
            let x = f64::from(k).powi(2) / 4e10; // dense near 0, where the guess is poorest in absolute terms
            worst = worst.max(((cbrt_unit(x) - x.cbrt()) / x.cbrt()).abs());
        }
        assert!(worst <= 2.0 * f64::EPSILON, "worst relative error {worst:e}");
        assert_eq!(cbrt_unit(0.0), 0.0);
        assert_eq!(cbrt_unit(1.0), 1.0);
        assert!(cbrt_unit(f64::NAN).is_nan(), "{}", cbrt_unit(f64::NAN));
        assert!(
            (cbrt_unit(1e-310) - 1e-310f64.cbrt()).abs() <= 1e-119,
            "{:e} vs {:e}",
            cbrt_unit(1e-310),
            1e-310f64.cbrt()
        );
    }
}
