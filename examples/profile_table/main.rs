//! Builds `data/profile_table.bin`, the exact profile shapes of the skin's stack (docs/model.md, Exact radial
//! profile): a white Monte Carlo per slice (walk.rs), its moments turned into the table's entries by the library's
//! `entries_from_moments`, written by `encode_table`.
//!
//! cargo run --release --example profile_table -- [--photons N] [--seed S] [--out PATH]
//!
//! The shipped table: 2,000,000 photons per slice, seed 2006 (about 12 minutes on this project's 2-core machine).

mod walk;

use spectral_skin::skin::scattering::DERMIS_SCATTERING_RATIO;
use spectral_skin::skin::SKIN_IOR;
use spectral_skin::transport::profile_table::{
    absorption_nodes, encode_table, entries_from_moments, tau_nodes, TableProvenance, MAX_PATH_MFP,
};

fn main() {
    let mut photons: u64 = 2_000_000;
    let mut seed: u64 = 2006;
    let mut out = String::from("data/profile_table.bin");
    let args: Vec<String> = std::env::args().skip(1).collect();
    for pair in args.chunks(2) {
        match (pair[0].as_str(), pair.get(1)) {
            ("--photons", Some(v)) => photons = v.parse().expect("--photons: a whole number"),
            ("--seed", Some(v)) => seed = v.parse().expect("--seed: a whole number"),
            ("--out", Some(v)) => out = v.clone(),
            _ => panic!("usage: profile_table [--photons N] [--seed S] [--out PATH]; got {pair:?}"),
        }
    }
    let a = absorption_nodes();
    let provenance = TableProvenance { photons, seed, ior: SKIN_IOR, bottom_scattering_ratio: DERMIS_SCATTERING_RATIO };
    let mut taus: Vec<f64> = tau_nodes();
    taus.push(f64::INFINITY);
    let mut slices = Vec::new();
    for (k, &tau) in taus.iter().enumerate() {
        let start = std::time::Instant::now();
        let w = walk::WhiteWalk {
            tau,
            bottom_scattering: DERMIS_SCATTERING_RATIO,
            ior: SKIN_IOR,
            photons,
            seed: seed.wrapping_add(k as u64),
            max_path: MAX_PATH_MFP,
        };
        let run = walk::run(&w, &a, &a);
        eprintln!(
            "slice {k} (tau {tau:.4}): {:.1} s, {:.1} collisions per photon, {} cut",
            start.elapsed().as_secs_f64(),
            run.collisions as f64 / photons as f64,
            run.cut
        );
        slices.push(entries_from_moments(&run.moments));
    }
    let bytes = encode_table(&provenance, &slices);
    let staged = format!("{out}.partial");
    std::fs::write(&staged, &bytes).expect("write the table");
    std::fs::rename(&staged, &out).expect("rename the table into place");
    eprintln!("wrote {out}: {} bytes", bytes.len());
}
