//! The maps against their floor, in one process: `run_maps` on the built-in face example (half-float PIZ, as
//! `spectral-skin example` writes it; the table read from the cache) against copying the same data through the same
//! reader and writer without the model (the input read and checked, then as many output planes as the run writes, in
//! the same encoding, filled from the input's planes). Medians of RUNS runs at each size; the ratio of the two, and the
//! time per texel against the smallest size's.
//!
//!     cargo run --release --example maps_floor -- [RUNS] [SIZE...]      (default: 5 runs, 4096 8192)
//!
//! Figures: docs/maps-performance.md. Peak memory is measured per process by scripts/reports/maps_report.py.

use std::path::Path;
use std::time::Instant;

use spectral_skin::maps::example::{write_example_params, ExampleKind};
use spectral_skin::maps::io::{read_params, stage_files, ExrOptions, ParamInputs, Plane, PlaneFile};
use spectral_skin::maps::pipeline::{check_planes, run_maps, MapSettings};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The floor: read and check the parameters, then write the same files (kinds and channels) the run wrote, each
/// channel filled from an input plane.
fn copy(inputs: &ParamInputs, out: &Path, files: &[(String, Vec<&'static str>)]) {
    std::fs::create_dir_all(out).unwrap();
    let mut image = read_params(inputs).unwrap();
    check_planes(&mut image, false).unwrap();
    let planes: Vec<&[f32]> = image
        .planes
        .iter()
        .map(|p| match p {
            Plane::Texels(v) => v.as_slice(),
            Plane::Constant(_) => panic!("the example has texels"),
        })
        .collect();
    let jobs: Vec<PlaneFile> = files
        .iter()
        .map(|(file, channels)| {
            (out.join(file), channels.iter().enumerate().map(|(c, name)| (*name, planes[c % planes.len()])).collect())
        })
        .collect();
    for staged in stage_files(image.width, image.height, &jobs, ExrOptions::default()).unwrap() {
        staged.commit().unwrap();
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let runs: usize = args.first().map_or(5, |s| s.parse().expect("RUNS"));
    let sizes: Vec<usize> =
        if args.len() > 1 { args[1..].iter().map(|s| s.parse().expect("SIZE")).collect() } else { vec![4096, 8192] };
    let dir = tempfile::tempdir().unwrap();
    let settings = MapSettings { table_cache: spectral_skin::maps::lut::default_cache_dir(), ..MapSettings::default() };
    println!("| size | maps (s) | copy floor (s) | maps / floor | maps ns per texel | vs {}² per texel |", sizes[0]);
    println!("|---|---|---|---|---|---|");
    let mut first_per_texel = None;
    for &size in &sizes {
        let params = dir.path().join(format!("face{size}.exr"));
        write_example_params(&params, ExampleKind::Face, size).unwrap();
        let inputs = ParamInputs::Multi { path: params, constants: [None; 4] };
        let out = dir.path().join("out");
        // One run first: the table into the cache, and the files whose kinds the floor copies.
        run_maps(&inputs, &out, &settings, ExrOptions::default(), None).unwrap();
        let mut files: Vec<(String, Vec<&'static str>)> = Vec::new();
        for kind in spectral_skin::maps::pipeline::MAP_KINDS {
            if out.join(kind.file).exists() {
                files.push((kind.file.to_string(), kind.channels.to_vec()));
            }
        }
        let (mut maps, mut floor) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            let start = Instant::now();
            run_maps(&inputs, &out, &settings, ExrOptions::default(), None).unwrap();
            maps.push(start.elapsed().as_secs_f64());
            let start = Instant::now();
            copy(&inputs, &dir.path().join("copy"), &files);
            floor.push(start.elapsed().as_secs_f64());
        }
        let (maps, floor) = (median(maps), median(floor));
        let per_texel = maps / (size * size) as f64;
        let first = *first_per_texel.get_or_insert(per_texel);
        println!(
            "| {size}² | {maps:.2} | {floor:.2} | {:.2} | {:.1} | {:.2} |",
            maps / floor,
            per_texel * 1e9,
            per_texel / first
        );
    }
}
