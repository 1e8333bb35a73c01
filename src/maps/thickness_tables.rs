//! Maps whose epidermis thickness varies per texel (a fitted or painted thickness): a stack of the three-axis material
//! tables of src/maps/lut.rs, one per thickness node, each texel looked up in the four tables around its thickness
//! and interpolated in thickness (the logarithm, by the cubic through the four nodes around it). Direct
//! evaluation of every texel costs about 0.8 ms a texel (a 1024² map about 14 CPU-minutes); the stack costs a table
//! build per node in use (cached on disk like the single table) and four lookups a texel. Its error against direct evaluation is measured on the map's own texels (docs/maps-performance.md,
//! "A varying epidermis thickness").

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::lut::{MaterialTable, TableResolution};
use crate::error::SkinError;
use crate::evaluate::Prepared;
use crate::fit::SubsurfaceMethod;

/// The thickness nodes, mm, over the range of `EPIDERMIS_THICKNESS` (0.01 to 0.5), closer where the colour changes
/// fastest (a thin epidermis). Measured with them: docs/maps-performance.md.
pub const THICKNESS_NODES_MM: [f64; 17] =
    [0.01, 0.015, 0.02, 0.03, 0.04, 0.05, 0.065, 0.08, 0.1, 0.125, 0.15, 0.2, 0.25, 0.3, 0.35, 0.42, 0.5];

/// The tables of the nodes that bracket a map's thicknesses, in node order.
pub struct ThicknessTables {
    nodes_mm: Vec<f64>,
    tables: Vec<MaterialTable>,
}

/// What building (or loading) the stack did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StackFigures {
    /// Tables in the stack (thickness nodes in use) and how many were built (the rest came from the cache).
    pub tables: usize,
    pub tables_built: usize,
    /// The thinnest and thickest node in use, mm.
    pub node_range_mm: [f64; 2],
    pub build_seconds: f64,
}

impl ThicknessTables {
    /// The tables for thicknesses from `min_mm` to `max_mm` (clamped to the nodes' range), each at `rest` (baseline
    /// absorption scale, blood oxygenation), loaded from `cache_dir` or built.
    #[allow(clippy::too_many_arguments)]
    pub fn load_or_build(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        radius: bool,
        [min_mm, max_mm]: [f64; 2],
        rest: [f64; 2],
        cache_dir: Option<&std::path::Path>,
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<(ThicknessTables, StackFigures), SkinError> {
        let start = Instant::now();
        let n = THICKNESS_NODES_MM.len();
        // The nodes around the thicknesses, one more each side (the cubic's window), at least four.
        let first = THICKNESS_NODES_MM.iter().rposition(|&t| t <= min_mm).unwrap_or(0).saturating_sub(1);
        let last = (THICKNESS_NODES_MM.iter().position(|&t| t >= max_mm).unwrap_or(n - 1) + 1).min(n - 1);
        let (first, last) =
            if last - first < 3 { (first.min(n - 4), (first.min(n - 4) + 3).max(last)) } else { (first, last) };
        let nodes_mm = THICKNESS_NODES_MM[first..=last].to_vec();
        let mut tables = Vec::with_capacity(nodes_mm.len());
        let mut built = 0;
        for &t in &nodes_mm {
            let (table, from_cache) = MaterialTable::load_or_build_outputs(
                prepared,
                method,
                resolution,
                radius,
                [t, rest[0], rest[1]],
                cache_dir,
                cancel,
                tick,
            )?;
            built += usize::from(!from_cache);
            tables.push(table);
        }
        let figures = StackFigures {
            tables: tables.len(),
            tables_built: built,
            node_range_mm: [nodes_mm[0], nodes_mm[nodes_mm.len() - 1]],
            build_seconds: start.elapsed().as_secs_f64(),
        };
        Ok((ThicknessTables { nodes_mm, tables }, figures))
    }

    /// The first of the four nodes around thickness `t_mm` (clamped to the stack's range) and the cubic Lagrange
    /// weights of those four nodes at it.
    fn window(&self, t_mm: f32) -> (usize, [f32; 4]) {
        let nodes = &self.nodes_mm;
        let t = (t_mm as f64).clamp(nodes[0], nodes[nodes.len() - 1]);
        let k = nodes.partition_point(|&n| n <= t).saturating_sub(1).min(nodes.len() - 2);
        let s = k.saturating_sub(1).min(nodes.len() - 4);
        let x = &nodes[s..s + 4];
        let weights = std::array::from_fn(|j| {
            (0..4).filter(|&i| i != j).map(|i| (t - x[i]) / (x[j] - x[i])).product::<f64>() as f32
        });
        (s, weights)
    }

    /// One row: Base Color and (when the tables hold it) the radius of each texel, from its (C_m, beta_m, C_h) and
    /// thickness: the logarithm of each value interpolated in thickness by the cubic through the four nodes around it
    /// (the light that crosses the epidermis falls like exp(-2 sigma_a d), so the logarithm is the smooth quantity).
    /// Texels are grouped by window so that each table looks up whole runs (its vectorised row lookup).
    pub fn lookup_row(
        &self,
        [melanin, blend, hemoglobin, thickness]: [&[f32]; 4],
        base_color: [&mut [f32]; 3],
        radius_mm: [&mut [f32]; 3],
    ) {
        let n = melanin.len();
        let with_radius = !radius_mm[0].is_empty();
        let windows: Vec<(usize, [f32; 4])> = thickness.iter().map(|&t| self.window(t)).collect();
        let mut starts: Vec<usize> = windows.iter().map(|w| w.0).collect();
        starts.sort_unstable();
        starts.dedup();
        let [c0, c1, c2] = base_color;
        let [r0, r1, r2] = radius_mm;
        let outputs: [&mut [f32]; 6] = [c0, c1, c2, r0, r1, r2];
        let planes = if with_radius { 6 } else { 3 };
        for s in starts {
            let idx: Vec<usize> = (0..n).filter(|&i| windows[i].0 == s).collect();
            let gather = |plane: &[f32]| -> Vec<f32> { idx.iter().map(|&i| plane[i]).collect() };
            let (m, b, h) = (gather(melanin), gather(blend), gather(hemoglobin));
            let len = idx.len();
            let mut logs = vec![vec![0f32; len]; planes];
            for node in 0..4 {
                let mut out = vec![vec![0f32; len]; 6];
                let [a0, a1, a2, a3, a4, a5] = out.as_mut_slice() else { unreachable!("six planes") };
                let radius: [&mut [f32]; 3] =
                    if with_radius { [a3, a4, a5] } else { [&mut [][..], &mut [][..], &mut [][..]] };
                self.tables[s + node].lookup_method_rows(&m, &b, &h, [a0, a1, a2], radius);
                for (q, log) in logs.iter_mut().enumerate() {
                    for (j, &i) in idx.iter().enumerate() {
                        log[j] += windows[i].1[node] * out[q][j].max(f32::MIN_POSITIVE).ln();
                    }
                }
            }
            for (q, log) in logs.iter().enumerate() {
                for (j, &i) in idx.iter().enumerate() {
                    outputs[q][i] = log[j].exp();
                }
            }
        }
    }

    /// The stack's value at one texel.
    pub fn lookup(&self, melanin: f32, blend: f32, hemoglobin: f32, thickness: f32, radius: bool) -> [[f32; 3]; 2] {
        let mut c = [[0f32; 1]; 3];
        let mut r = [[0f32; 1]; 3];
        let [c0, c1, c2] = &mut c;
        let [r0, r1, r2] = &mut r;
        let radius_out: [&mut [f32]; 3] =
            if radius { [&mut r0[..], &mut r1[..], &mut r2[..]] } else { [&mut [][..], &mut [][..], &mut [][..]] };
        self.lookup_row(
            [&[melanin], &[blend], &[hemoglobin], &[thickness]],
            [&mut c0[..], &mut c1[..], &mut c2[..]],
            radius_out,
        );
        [[c[0][0], c[1][0], c[2][0]], [r[0][0], r[1][0], r[2][0]]]
    }
}

/// The largest relative errors of the stack against direct evaluation at `count` check texels (the map plan picks them
/// spread evenly over the texture): (Base Color, radius), each the maximum over the channels and texels. `texel(i)`
/// gives check texel i's (C_m, beta_m, C_h, thickness) and `exact(i)` its direct evaluation (Base Color, radius).
pub fn measure_stack_error(
    stack: &ThicknessTables,
    count: usize,
    radius: bool,
    texel: impl Fn(usize) -> [f32; 4] + Sync,
    exact: impl Fn(usize) -> Result<[[f32; 3]; 2], SkinError> + Sync,
    cancel: &AtomicBool,
) -> Result<[f64; 2], SkinError> {
    let errors = (0..count)
        .into_par_iter()
        .map(|i| {
            SkinError::check_cancel(cancel, "thickness table check")?;
            let [m, b, h, t] = texel(i);
            let approx = stack.lookup(m, b, h, t, radius);
            let truth = exact(i)?;
            let rel =
                |a: [f32; 3], e: [f32; 3]| (0..3).map(|c| ((a[c] - e[c]) / e[c]).abs() as f64).fold(0.0, f64::max);
            Ok([rel(approx[0], truth[0]), if radius { rel(approx[1], truth[1]) } else { 0.0 }])
        })
        .collect::<Result<Vec<_>, SkinError>>()?;
    Ok([0, 1].map(|q| errors.iter().map(|e| e[q]).fold(0.0, f64::max)))
}
