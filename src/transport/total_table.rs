//! The exact total reflectance of a two-layer stack, tabulated once (docs/model.md, Exact transport at table speed).
//!
//! With isotropic scattering (the model's reduced coefficients) and one index of refraction, a layer over a
//! semi-infinite one is three numbers: the top layer's single-scattering albedo and optical thickness and the bottom
//! layer's albedo. The table holds the adding-doubling total ([`super::adding_doubling`], [`TABLE_STREAMS`] streams,
//! within 1e-5 of converged) on a grid of those three, in coordinates in which the total is smooth:
//! `u = 1 - sqrt(1 - albedo)` (a medium's reflectance near conservative scattering is linear in `sqrt(1 - albedo)`;
//! van de Hulst 1980, ch. 15) and `x = tau / (tau + TAU_SCALE)` (so the semi-infinite top layer is the node x = 1,
//! which the total approaches like 1/tau without absorption). Between nodes it is interpolated by tricubic
//! Catmull-Rom splines (continuous first derivatives, which the fits' finite differences need), with the edges
//! extended by quadratic extrapolation. Its error against fresh solves is measured by tests/physics/total_table.rs
//! and reported in docs/accuracy-vs-time.md.
//!
//! The table is built by `examples/total_table.rs` and shipped as `data/total_table.bin`. This module knows nothing
//! of skin, only of the dimensionless stack.

use std::sync::OnceLock;

use rayon::prelude::*;

use super::adding_doubling::{totals_over_semi_infinite, OpticalSlab, SemiInfiniteLayers};
use crate::error::SkinError;
use crate::layer::Layer;

/// Streams of the tabulated solves: 32 streams are within 1e-5 of 64 for every skin stack (tests).
pub const TABLE_STREAMS: usize = 32;
/// Nodes per axis of the shipped table: top albedo, top optical thickness, bottom albedo.
pub const TABLE_NODES: [usize; 3] = [65, 65, 65];
/// The optical thickness at the middle of the thickness axis (x = 0.5).
pub const TAU_SCALE: f64 = 1.0;
const MAGIC: &[u8; 8] = b"SSTOTAB1";
const HEADER_BYTES: usize = MAGIC.len() + 5 * 8;

/// The table coordinate of a single-scattering albedo.
fn albedo_coordinate(albedo: f64) -> f64 {
    1.0 - (1.0 - albedo).max(0.0).sqrt()
}

/// The albedo at table coordinate `u`.
fn albedo_at(u: f64) -> f64 {
    1.0 - (1.0 - u) * (1.0 - u)
}

/// The table coordinate of an optical thickness (infinite: 1).
fn thickness_coordinate(tau: f64) -> f64 {
    if tau.is_infinite() {
        1.0
    } else {
        tau / (tau + TAU_SCALE)
    }
}

/// The optical thickness at table coordinate `x` (x = 1: infinite).
fn thickness_at(x: f64) -> f64 {
    if x >= 1.0 {
        f64::INFINITY
    } else {
        TAU_SCALE * x / (1.0 - x)
    }
}

fn axis(n: usize) -> impl Iterator<Item = f64> {
    (0..n).map(move |i| i as f64 / (n - 1) as f64)
}

/// The totals at every node of a grid of `nodes` (top albedo, top thickness, bottom albedo; the last index varying
/// fastest) for index `ior` and `streams` streams; the (albedo, thickness) rows solved in parallel.
pub fn build_values(nodes: [usize; 3], ior: f64, streams: usize) -> Result<Vec<f64>, SkinError> {
    if nodes.iter().any(|&n| n < 4) {
        return Err(SkinError::invalid("nodes", "a table needs at least 4 nodes per axis"));
    }
    let bottom_albedos: Vec<f64> = axis(nodes[2]).map(albedo_at).collect();
    let bottom = SemiInfiniteLayers::new(&bottom_albedos, ior, streams)?;
    let rows: Vec<(f64, f64)> =
        axis(nodes[0]).flat_map(|u| axis(nodes[1]).map(move |x| (albedo_at(u), thickness_at(x)))).collect();
    let totals: Vec<Vec<f64>> = rows
        .par_iter()
        .map(|&(albedo, optical_thickness)| {
            // A top layer of no thickness is no layer (the thin-layer start divides by its thickness).
            let top = [OpticalSlab { albedo, optical_thickness, g: 0.0 }];
            totals_over_semi_infinite(if optical_thickness > 0.0 { &top } else { &[] }, &bottom)
        })
        .collect::<Result<_, _>>()?;
    Ok(totals.concat())
}

/// Serialise a table: header (magic, the three node counts, index, streams), then every total as f32.
pub fn encode(nodes: [usize; 3], ior: f64, streams: usize, values: &[f64]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + 4 * values.len());
    out.extend_from_slice(MAGIC);
    for n in nodes {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
    out.extend_from_slice(&ior.to_le_bytes());
    out.extend_from_slice(&(streams as u64).to_le_bytes());
    for v in values {
        out.extend_from_slice(&(*v as f32).to_le_bytes());
    }
    out
}

/// The stack of the table's three numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoLayerStack {
    pub top_albedo: f64,
    /// Infinite for a semi-infinite top layer.
    pub top_optical_thickness: f64,
    pub bottom_albedo: f64,
}

impl TwoLayerStack {
    /// The stack of `layers` in optical units, if it is the table's kind: a finite or semi-infinite layer over a
    /// semi-infinite one, both of index `ior` (within round-off), each scattering or absorbing something.
    pub fn of_layers(layers: &[Layer], ior: f64) -> Option<TwoLayerStack> {
        let [top, bottom] = layers else { return None };
        let same = |a: f64| (a - ior).abs() <= 1e-12 * ior;
        if !same(top.ior) || !same(bottom.ior) || !bottom.thickness_mm.is_infinite() {
            return None;
        }
        let (t, b) = (OpticalSlab::of_layer(top), OpticalSlab::of_layer(bottom));
        let finite = |v: f64| v.is_finite() && v >= 0.0;
        let valid =
            finite(t.albedo) && finite(b.albedo) && (finite(t.optical_thickness) || top.thickness_mm.is_infinite());
        valid.then_some(TwoLayerStack {
            top_albedo: t.albedo.min(1.0),
            top_optical_thickness: t.optical_thickness,
            bottom_albedo: b.albedo.min(1.0),
        })
    }
}

/// The decoded table, each axis padded with one extrapolated node on either side.
#[derive(Debug, Clone)]
pub struct TotalTable {
    nodes: [usize; 3],
    ior: f64,
    streams: usize,
    /// (n0 + 2) x (n1 + 2) x (n2 + 2) totals, the last index fastest.
    padded: Vec<f32>,
}

impl TotalTable {
    /// The table compiled into the crate (`data/total_table.bin`), decoded once per process.
    pub fn shipped() -> &'static TotalTable {
        static TABLE: OnceLock<TotalTable> = OnceLock::new();
        TABLE.get_or_init(|| {
            TotalTable::decode(include_bytes!("../../data/total_table.bin"))
                .expect("data/total_table.bin is the format this build reads (examples/total_table.rs writes it)")
        })
    }

    /// A table from the bytes [`encode`] writes.
    pub fn decode(bytes: &[u8]) -> Result<TotalTable, SkinError> {
        let bad = |why: &str| SkinError::invalid("total table", why.to_string());
        if bytes.len() < HEADER_BYTES || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad("not a table of totals (magic)"));
        }
        let word = |i: usize| {
            let at = MAGIC.len() + 8 * i;
            u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
        };
        let nodes = [word(0), word(1), word(2)].map(|n| n as usize);
        if nodes.iter().any(|&n| !(4..=4096).contains(&n)) {
            return Err(bad("node counts outside 4-4096"));
        }
        let count = nodes.iter().product::<usize>();
        if bytes.len() != HEADER_BYTES + 4 * count {
            return Err(bad("length differs from the grid's"));
        }
        let values: Vec<f64> = bytes[HEADER_BYTES..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64)
            .collect();
        Ok(TotalTable::from_values(nodes, f64::from_bits(word(3)), word(4) as usize, &values))
    }

    /// A table of `values` ([`build_values`]'s order) on a grid of `nodes`.
    pub fn from_values(nodes: [usize; 3], ior: f64, streams: usize, values: &[f64]) -> TotalTable {
        TotalTable { nodes, ior, streams, padded: pad(nodes, values).into_iter().map(|v| v as f32).collect() }
    }

    /// The index of refraction the table was solved for.
    pub fn ior(&self) -> f64 {
        self.ior
    }

    /// The streams the table was solved with.
    pub fn streams(&self) -> usize {
        self.streams
    }

    /// The total of `layers` if the table holds their stack ([`TwoLayerStack::of_layers`] at the table's index).
    pub fn total_of(&self, layers: &[Layer]) -> Option<f64> {
        TwoLayerStack::of_layers(layers, self.ior).map(|s| self.total(&s))
    }

    /// The interpolated total of `stack`, clamped to [0, 1].
    pub fn total(&self, stack: &TwoLayerStack) -> f64 {
        let coordinates = [
            albedo_coordinate(stack.top_albedo),
            thickness_coordinate(stack.top_optical_thickness),
            albedo_coordinate(stack.bottom_albedo),
        ];
        let mut first = [0usize; 3];
        let mut weights = [[0.0; 4]; 3];
        for d in 0..3 {
            let t = coordinates[d].clamp(0.0, 1.0) * (self.nodes[d] - 1) as f64;
            let cell = (t.floor() as usize).min(self.nodes[d] - 2);
            // Padded index of the stencil's first node: the cell's left node is padded index cell + 1.
            first[d] = cell;
            weights[d] = catmull_rom(t - cell as f64);
        }
        let (s1, s2) = (self.nodes[2] + 2, (self.nodes[1] + 2) * (self.nodes[2] + 2));
        let mut total = 0.0;
        for (i, wi) in weights[0].iter().enumerate() {
            for (j, wj) in weights[1].iter().enumerate() {
                let row = (first[0] + i) * s2 + (first[1] + j) * s1 + first[2];
                let v = &self.padded[row..row + 4];
                let inner = wj
                    * (weights[2][0] * v[0] as f64
                        + weights[2][1] * v[1] as f64
                        + weights[2][2] * v[2] as f64
                        + weights[2][3] * v[3] as f64);
                total += wi * inner;
            }
        }
        total.clamp(0.0, 1.0)
    }
}

/// Catmull-Rom weights of the four nodes around a point a fraction `t` of the way from the second to the third.
fn catmull_rom(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (-t + 2.0 * t2 - t3), 0.5 * (2.0 - 5.0 * t2 + 3.0 * t3), 0.5 * (t + 4.0 * t2 - 3.0 * t3), 0.5 * (t3 - t2)]
}

/// `values` on a grid of `nodes`, with one node added before and after along each axis by quadratic extrapolation
/// (`f(-1) = 3 f(0) - 3 f(1) + f(2)`), so the edge cells keep the interior's order.
fn pad(nodes: [usize; 3], values: &[f64]) -> Vec<f64> {
    let p = nodes.map(|n| n + 2);
    let at = |i: usize, j: usize, k: usize| (i * p[1] + j) * p[2] + k;
    let mut out = vec![0.0; p.iter().product()];
    for i in 0..nodes[0] {
        for j in 0..nodes[1] {
            for k in 0..nodes[2] {
                out[at(i + 1, j + 1, k + 1)] = values[(i * nodes[1] + j) * nodes[2] + k];
            }
        }
    }
    let extend = |out: &mut Vec<f64>, index: &dyn Fn(usize) -> usize, n: usize| {
        out[index(0)] = 3.0 * out[index(1)] - 3.0 * out[index(2)] + out[index(3)];
        out[index(n + 1)] = 3.0 * out[index(n)] - 3.0 * out[index(n - 1)] + out[index(n - 2)];
    };
    // Along the last axis, then the middle, then the first: each pass fills the previous passes' padding too.
    for i in 1..=nodes[0] {
        for j in 1..=nodes[1] {
            extend(&mut out, &|k| at(i, j, k), nodes[2]);
        }
    }
    for i in 1..=nodes[0] {
        for k in 0..p[2] {
            extend(&mut out, &|j| at(i, j, k), nodes[1]);
        }
    }
    for j in 0..p[1] {
        for k in 0..p[2] {
            extend(&mut out, &|i| at(i, j, k), nodes[0]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_invert() {
        for u in [0.0, 0.3, 0.9, 1.0] {
            assert!((albedo_coordinate(albedo_at(u)) - u).abs() < 1e-12);
        }
        for x in [0.0, 0.25, 0.9] {
            assert!((thickness_coordinate(thickness_at(x)) - x).abs() < 1e-12);
        }
        assert_eq!(thickness_coordinate(f64::INFINITY), 1.0);
    }

    #[test]
    fn catmull_rom_reproduces_quadratics_and_padding_extends_them() {
        // A quadratic in every coordinate is reproduced exactly, the padded edges included.
        let nodes = [5, 6, 7];
        let f = |u: f64, x: f64, v: f64| 0.2 + 0.3 * u * u - 0.1 * x + 0.05 * x * x + 0.2 * u * v + 0.1 * v * v;
        let values: Vec<f64> =
            axis(5).flat_map(|u| axis(6).flat_map(move |x| axis(7).map(move |v| f(u, x, v)))).collect();
        let table = TotalTable::from_values(nodes, 1.4, 8, &values);
        for (u, x, v) in [(0.05, 0.02, 0.97), (0.5, 0.5, 0.5), (0.99, 0.9, 0.01), (0.13, 0.71, 0.44)] {
            let stack = TwoLayerStack {
                top_albedo: albedo_at(u),
                top_optical_thickness: thickness_at(x),
                bottom_albedo: albedo_at(v),
            };
            assert!((table.total(&stack) - f(u, x, v)).abs() < 1e-6, "{u} {x} {v}");
        }
    }

    #[test]
    fn encoding_round_trips_and_bad_bytes_are_refused() {
        let nodes = [4, 4, 5];
        let values: Vec<f64> = (0..80).map(|i| i as f64 / 100.0).collect();
        let bytes = encode(nodes, 1.4, 8, &values);
        let table = TotalTable::decode(&bytes).unwrap();
        assert_eq!((table.ior(), table.streams()), (1.4, 8));
        assert!(TotalTable::decode(&bytes[..bytes.len() - 1]).is_err());
        assert!(TotalTable::decode(b"SSPRTAB1").is_err());
    }
}
