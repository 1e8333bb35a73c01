//! The table's row lookup (`MaterialTable::lookup_method_rows`, what the map pipeline uses) gives bit for bit the
//! values of its per-texel lookup (`lookup_method`) on rows with and without runs of repeated texels, at the domain's
//! edges (zero concentrations: the cube root's special case) and beyond them (clamped), with and without the radius.

use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::lut::{MaterialTable, TableResolution};
use spectral_skin::{Outputs, Request};

/// A small uneven grid: a wrong stride or a swapped axis shows.
const SMALL: TableResolution = TableResolution { melanin: 6, melanin_blend: 4, hemoglobin: 5 };

/// `n` texels: pseudo-random over the domain and a little beyond, with the domain's corners every 37th texel and,
/// with `run` > 1, each texel repeated `run` times.
fn row(n: usize, run: usize) -> [Vec<f32>; 3] {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut planes = [Vec::new(), Vec::new(), Vec::new()];
    while planes[0].len() < n {
        let k = planes[0].len() / run;
        let t = if k % 37 == 0 {
            [[0.0, 0.0, 0.0], [0.5, 1.0, 0.1], [0.0, 1.0, 0.1], [1e-40, 0.0, 1e-40]][k / 37 % 4]
        } else {
            [(next() * 0.52 - 0.01) as f32, (next() * 1.04 - 0.02) as f32, (next() * 0.104 - 0.002) as f32]
        };
        for _ in 0..run.min(n - planes[0].len()) {
            for (p, v) in planes.iter_mut().zip(t) {
                p.push(v);
            }
        }
    }
    planes
}

#[test]
fn row_lookup_equals_the_texel_lookup() {
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let table = MaterialTable::build(&prepared, SubsurfaceMethod::Burley, SMALL).unwrap();
    // Runs of 1 take the every-texel path; runs of 2 and 13 the run path; 1000 texels span several 64-texel batches.
    for (n, run) in [(1000, 1), (1000, 2), (1000, 13), (1, 1), (65, 1), (130, 13)] {
        let [m, b, h] = row(n, run);
        for with_radius in [true, false] {
            let mut c = [vec![f32::NAN; n], vec![f32::NAN; n], vec![f32::NAN; n]];
            let mut r = if with_radius {
                [vec![f32::NAN; n], vec![f32::NAN; n], vec![f32::NAN; n]]
            } else {
                Default::default()
            };
            let [c0, c1, c2] = &mut c;
            let [r0, r1, r2] = &mut r;
            table.lookup_method_rows(&m, &b, &h, [c0, c1, c2], [r0, r1, r2]);
            for x in 0..n {
                let (bc, rad) = table.lookup_method(m[x], b[x], h[x]);
                for k in 0..3 {
                    assert_eq!(c[k][x].to_bits(), bc[k].to_bits(), "Base Color {k} at {x} (n {n}, run {run})");
                    if with_radius {
                        assert_eq!(r[k][x].to_bits(), rad[k].to_bits(), "radius {k} at {x} (n {n}, run {run})");
                    }
                }
            }
        }
    }
}
