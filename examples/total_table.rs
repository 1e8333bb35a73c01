//! Builds `data/total_table.bin`, the adding-doubling totals of the two-layer stack over its three dimensionless
//! numbers (`spectral_skin::transport::total_table`; docs/model.md, Exact transport at table speed).
//!
//!     cargo run --release --example total_table -- [--out PATH]      # the shipped table (about a minute)
//!     cargo run --release --example total_table -- --study           # interpolation error against grid size
//!
//! The study builds smaller tables at 16 streams and compares them with fresh solves at the same streams, at random
//! stacks and at skin's stacks (random physiology inside the accepted ranges, 380-780 nm), printing the worst and
//! the 99th percentile of the relative error for each grid.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use spectral_skin::skin::params::PARAMS;
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams, SKIN_IOR};
use spectral_skin::transport::adding_doubling::{slab_reflectance, OpticalSlab};
use spectral_skin::transport::total_table::{
    build_values, encode, TotalTable, TwoLayerStack, TABLE_NODES, TABLE_STREAMS,
};

/// A uniform pseudo-random number in [0, 1).
fn uniform(rng: &mut Pcg64Mcg) -> f64 {
    rng.random()
}

fn skin_stacks(count: usize, seed: u64) -> Vec<TwoLayerStack> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let model = SkinModel::default();
    (0..count)
        .map(|_| {
            let values = PARAMS.map(|spec| {
                let (lo, hi) = spec.range();
                lo + (hi - lo) * uniform(&mut rng)
            });
            let params = SkinParams::from_values(values).expect("inside the ranges");
            let wavelength_nm = 380.0 + 400.0 * uniform(&mut rng);
            TwoLayerStack::of_layers(&skin_layers(&params, &model, wavelength_nm), SKIN_IOR).expect("two layers")
        })
        .collect()
}

fn random_stacks(count: usize, seed: u64) -> Vec<TwoLayerStack> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..count)
        .map(|_| TwoLayerStack {
            top_albedo: uniform(&mut rng),
            top_optical_thickness: 10f64.powf(-3.0 + 6.0 * uniform(&mut rng)),
            bottom_albedo: uniform(&mut rng),
        })
        .collect()
}

fn solve(s: &TwoLayerStack, streams: usize) -> f64 {
    let slabs = [
        OpticalSlab { albedo: s.top_albedo, optical_thickness: s.top_optical_thickness, g: 0.0 },
        OpticalSlab { albedo: s.bottom_albedo, optical_thickness: f64::INFINITY, g: 0.0 },
    ];
    slab_reflectance(&slabs, SKIN_IOR, streams).expect("a valid stack")
}

fn report(name: &str, table: &TotalTable, stacks: &[TwoLayerStack], streams: usize) {
    let errors: Vec<(f64, &TwoLayerStack)> = stacks
        .iter()
        .map(|s| {
            let exact = solve(s, streams);
            ((table.total(s) - exact).abs() / exact.max(1e-3), s)
        })
        .collect();
    let worst = errors.iter().max_by(|a, b| a.0.total_cmp(&b.0)).expect("stacks");
    let mut relative: Vec<f64> = errors.iter().map(|e| e.0).collect();
    relative.sort_by(f64::total_cmp);
    println!("  {name}: worst at {:?}", worst.1);
    let p99 = relative[(relative.len() * 99) / 100];
    println!(
        "  {name}: worst {:.2e}, p99 {p99:.2e}, median {:.2e}",
        relative[relative.len() - 1],
        relative[relative.len() / 2]
    );
}

fn study() {
    let streams = 16;
    let skin = skin_stacks(2000, 7);
    let random = random_stacks(2000, 11);
    for n in [17, 33, 49, 65] {
        let nodes = [n, n, n];
        let start = std::time::Instant::now();
        let values = build_values(nodes, SKIN_IOR, streams).expect("build");
        let table = TotalTable::from_values(nodes, SKIN_IOR, streams, &values);
        println!("{n}^3 nodes, built in {:.1} s (relative error, floor 1e-3 absolute):", start.elapsed().as_secs_f64());
        report("skin stacks", &table, &skin, streams);
        report("random stacks", &table, &random, streams);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--study") {
        return study();
    }
    let out = match args.as_slice() {
        [] => String::from("data/total_table.bin"),
        [flag, path] if flag == "--out" => path.clone(),
        other => panic!("usage: total_table [--out PATH] | --study; got {other:?}"),
    };
    let start = std::time::Instant::now();
    let values = build_values(TABLE_NODES, SKIN_IOR, TABLE_STREAMS).expect("build the table");
    let bytes = encode(TABLE_NODES, SKIN_IOR, TABLE_STREAMS, &values);
    let staged = format!("{out}.partial");
    std::fs::write(&staged, &bytes).expect("write the table");
    std::fs::rename(&staged, &out).expect("rename the table into place");
    eprintln!("wrote {out}: {} bytes in {:.1} s", bytes.len(), start.elapsed().as_secs_f64());
}
