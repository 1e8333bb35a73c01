//! The shipped table of adding-doubling totals (`transport::total_table`, data/total_table.bin) against fresh solves
//! of the same stacks: skin's stacks (random physiology inside the accepted ranges, 380-780 nm, the presets) and
//! stacks anywhere in the table's domain; and the table's streams against twice as many (its convergence).
//! The table against Monte Carlo: tests/physics/exact_transport.rs. Run with `-- --nocapture` for the figures.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use spectral_skin::skin::params::PARAMS;
use spectral_skin::skin::{skin_layers, SkinModel, SkinParams, PRESETS, SKIN_IOR};
use spectral_skin::transport::adding_doubling::{slab_reflectance, OpticalSlab};
use spectral_skin::transport::total_table::{TotalTable, TwoLayerStack, TABLE_STREAMS};

/// A uniform pseudo-random number in [0, 1).
fn uniform(rng: &mut Pcg64Mcg) -> f64 {
    rng.random()
}

fn skin_stacks(count: usize, seed: u64) -> Vec<TwoLayerStack> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let model = SkinModel::default();
    let mut params: Vec<(SkinParams, f64)> = PRESETS
        .iter()
        .flat_map(|p| [400.0, 450.0, 550.0, 650.0].map(|w| (SkinParams::preset(p.name).unwrap(), w)))
        .collect();
    params.extend((0..count).map(|_| {
        let values = PARAMS.map(|spec| {
            let (lo, hi) = spec.range();
            lo + (hi - lo) * uniform(&mut rng)
        });
        (SkinParams::from_values(values).unwrap(), 380.0 + 400.0 * uniform(&mut rng))
    }));
    params
        .iter()
        .map(|(p, w)| TwoLayerStack::of_layers(&skin_layers(p, &model, *w), SKIN_IOR).expect("the table's kind"))
        .collect()
}

fn solve(s: &TwoLayerStack, streams: usize) -> f64 {
    let slabs = [
        OpticalSlab { albedo: s.top_albedo, optical_thickness: s.top_optical_thickness, g: 0.0 },
        OpticalSlab { albedo: s.bottom_albedo, optical_thickness: f64::INFINITY, g: 0.0 },
    ];
    slab_reflectance(&slabs, SKIN_IOR, streams).unwrap()
}

/// The worst relative difference of `a` from `b` over `stacks` (below `floor`, the absolute difference over `floor`).
fn worst(
    stacks: &[TwoLayerStack],
    floor: f64,
    a: impl Fn(&TwoLayerStack) -> f64,
    b: impl Fn(&TwoLayerStack) -> f64,
) -> f64 {
    stacks.iter().map(|s| (a(s) - b(s)).abs() / b(s).max(floor)).fold(0.0, f64::max)
}

#[test]
fn table_matches_fresh_solves_on_skin() {
    let table = TotalTable::shipped();
    assert_eq!((table.ior(), table.streams()), (SKIN_IOR, TABLE_STREAMS));
    let stacks = skin_stacks(300, 2026);
    let error = worst(&stacks, 1e-3, |s| table.total(s), |s| solve(s, TABLE_STREAMS));
    println!("table vs {TABLE_STREAMS}-stream solves, {} skin stacks: worst relative {error:.2e}", stacks.len());
    // Measured 2.2e-5 (examples/total_table.rs --study, 2,000 stacks).
    assert!(error <= 1e-4, "{error}");
}

#[test]
fn table_matches_fresh_solves_anywhere_in_its_domain() {
    let table = TotalTable::shipped();
    let mut rng = Pcg64Mcg::seed_from_u64(35);
    let stacks: Vec<TwoLayerStack> = (0..300)
        .map(|_| TwoLayerStack {
            top_albedo: uniform(&mut rng),
            top_optical_thickness: 10f64.powf(-2.0 + 5.0 * uniform(&mut rng)),
            bottom_albedo: uniform(&mut rng),
        })
        .chain([0.0, 0.5, 1.0].map(|a| TwoLayerStack {
            top_albedo: a,
            top_optical_thickness: f64::INFINITY,
            bottom_albedo: 0.3,
        }))
        .collect();
    let error = worst(&stacks, 1.0, |s| table.total(s), |s| solve(s, TABLE_STREAMS));
    println!("table vs solves, {} stacks anywhere: worst absolute {error:.2e}", stacks.len());
    // Far outside skin (an optically thin, nearly white layer over a black one) the interpolation errs most.
    assert!(error <= 1e-4, "{error}");
}

#[test]
fn table_streams_are_converged_for_skin() {
    let stacks = skin_stacks(40, 7);
    let error = worst(&stacks, 1e-3, |s| solve(s, TABLE_STREAMS), |s| solve(s, 2 * TABLE_STREAMS));
    println!(
        "{TABLE_STREAMS} vs {} streams, {} skin stacks: worst relative {error:.2e}",
        2 * TABLE_STREAMS,
        stacks.len()
    );
    assert!(error <= 1e-5, "{error}");
}

#[test]
fn stacks_outside_the_table_are_not_read_from_it() {
    let table = TotalTable::shipped();
    let layers = skin_layers(&SkinParams::preset("caucasian").unwrap(), &SkinModel::default(), 550.0);
    assert!(table.total_of(&layers).is_some());
    let finite_dermis = [layers[0], spectral_skin::layer::Layer { thickness_mm: 2.0, ..layers[1] }];
    assert!(table.total_of(&finite_dermis).is_none());
    let other_index = layers.map(|l| spectral_skin::layer::Layer { ior: 1.33, ..l });
    assert!(table.total_of(&other_index).is_none());
    assert!(table.total_of(&layers[..1]).is_none());
}
