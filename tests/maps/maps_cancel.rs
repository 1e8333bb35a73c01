//! `compute_maps_cancellable`: a cancel flag set from the progress callback stops the work (the call returns the
//! interruption, never a partial result), and a flag never set changes nothing. The reference is `compute_maps`
//! itself on the same image (the uncancelled result) and the count of rows and evaluations the callback saw.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use spectral_skin::maps::example::face_params;
use spectral_skin::maps::io::{default_extended, ParamImage, Plane};
use spectral_skin::maps::pipeline::{check_planes, compute_maps_cancellable, MAX_DISTINCT_TUPLES};
use spectral_skin::maps::{compute_maps, MapSettings, StrategyChoice};
use spectral_skin::{Accuracy, Outputs, Request};

#[test]
fn cancel_skips_the_rows_not_started() {
    let mut image = face_params(48);
    check_planes(&mut image, false).expect("the example map is in range");
    // Exact: every row is real work, so skipped rows are visible as unwritten (zero) outputs.
    let settings = MapSettings { strategy: StrategyChoice::Exact, ..MapSettings::default() };
    let full = compute_maps(&image, &settings, None).expect("maps");

    let never = AtomicBool::new(false);
    let same = compute_maps_cancellable(&image, &settings, None, &never).expect("maps");
    assert_eq!(same.base_color, full.base_color);
    assert_eq!(same.radius_mm, full.radius_mm);

    // Cancel once a quarter of the rows are done: the rows not started are skipped, the one under way stops within
    // an evaluation, and the call is the interruption.
    let cancel = AtomicBool::new(false);
    let rows = AtomicUsize::new(0);
    // Rows are the calls with texels done; a call with 0 is a tick between evaluations.
    let progress = |done: usize, _: usize| {
        if done > 0 && rows.fetch_add(1, Ordering::SeqCst) + 1 >= 12 {
            cancel.store(true, Ordering::SeqCst);
        }
    };
    let e = compute_maps_cancellable(&image, &settings, Some(&progress), &cancel).expect_err("cancelled").to_string();
    assert!(e.contains("interrupted"), "{e}");
    let done = rows.load(Ordering::SeqCst);
    assert!((12..12 + rayon::current_num_threads()).contains(&done), "{done} rows done of 48 after the 12th");
}

/// A table build stops once the flag is set: set from the build's own tick (about once per percent of the nodes),
/// the build returns an error after at most one more node per worker thread instead of all 100 ticks, and nothing
/// is stored in the cache folder. The pipeline passes the tick on as a progress call `(0, texels)`, so a progress
/// callback can cancel a build it is not otherwise told about.
#[test]
fn cancel_stops_a_table_build() {
    use spectral_skin::evaluate::{Outputs, Prepared, Request};
    use spectral_skin::fit::SubsurfaceMethod;
    use spectral_skin::maps::lut::{MaterialTable, TableResolution};

    let prepared = Prepared::new(&Request::new(Outputs::material())).expect("request");
    // 27 000 nodes: about 10 s of work on 2 cores if the flag were ignored.
    let resolution = TableResolution { melanin: 30, melanin_blend: 30, hemoglobin: 30 };
    let dir = tempfile::tempdir().expect("temp dir");
    let cancel = AtomicBool::new(false);
    let ticks = AtomicUsize::new(0);
    let tick = || {
        if ticks.fetch_add(1, Ordering::SeqCst) + 1 >= 3 {
            cancel.store(true, Ordering::SeqCst);
        }
    };
    let result = MaterialTable::load_or_build_cancellable(
        &prepared,
        SubsurfaceMethod::Burley,
        resolution,
        Some(dir.path()),
        &cancel,
        Some(&tick),
    );
    let e = result.expect_err("a cancelled build is an error").to_string();
    assert!(e.contains("interrupted"), "{e}");
    let seen = ticks.load(Ordering::SeqCst);
    assert!(
        seen <= 3 + rayon::current_num_threads(),
        "{seen} ticks of 100 with {} threads: the build went on",
        rayon::current_num_threads()
    );
    assert_eq!(std::fs::read_dir(dir.path()).expect("cache dir").count(), 0, "a cancelled table was cached");

    // Through the pipeline: a 64 x 64 map of 4096 distinct texels takes the table; the progress callback cancels
    // at its first call, which is a build tick.
    let n = 64 * 64;
    let ramp = |scale: f32| Plane::Texels((0..n).map(|i| scale * i as f32 / n as f32).collect());
    let image = ParamImage::new(64, 64, [ramp(0.5), ramp(1.0), ramp(0.1), Plane::Constant(0.3)]);
    let settings = MapSettings { table: resolution, ..MapSettings::default() };
    let cancel = AtomicBool::new(false);
    let calls = AtomicUsize::new(0);
    let progress = |done: usize, _: usize| {
        assert_eq!(done, 0, "no texel is done while the table is built");
        calls.fetch_add(1, Ordering::SeqCst);
        cancel.store(true, Ordering::SeqCst);
    };
    let e = compute_maps_cancellable(&image, &settings, Some(&progress), &cancel).expect_err("cancelled").to_string();
    assert!(e.contains("interrupted"), "{e}");
    let (called, threads) = (calls.load(Ordering::SeqCst), rayon::current_num_threads());
    assert!(called <= 1 + threads, "progress called {called} times with {threads} threads");
}

/// The flag is read before every evaluation, not once per row (issue 38 item 2: one row of an exact map at the
/// reference level is minutes of work; a 2 x 128 map stopped 52 s after Ctrl-C). One row of distinct texels, as the
/// distinct-tuple path takes it (64 tuples) and as the per-texel path does (more than `MAX_DISTINCT_TUPLES`): the
/// progress callback cancels at its first call, and the evaluations done (one progress call each) are the one that
/// called plus at most one in flight per worker thread, where the whole row used to be evaluated.
#[test]
fn cancel_is_read_before_each_evaluation() {
    let threads = rayon::current_num_threads();
    for width in [64, MAX_DISTINCT_TUPLES + 1] {
        let melanin: Vec<f32> = (0..width).map(|x| 0.01 + 0.4 * x as f32 / width as f32).collect();
        let image = ParamImage {
            width,
            height: 1,
            planes: [Plane::Texels(melanin), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)],
            extended: default_extended(),
            notes: Vec::new(),
        };
        let request =
            Request { accuracy: Accuracy::draft(), ..Request::new(Outputs { albedo: true, ..Outputs::default() }) };
        let settings = MapSettings { strategy: StrategyChoice::Exact, request, ..MapSettings::default() };
        let cancel = AtomicBool::new(false);
        // The progress calls after the first are the evaluations finished (each ticks once, `(0, texels)`).
        let calls = AtomicUsize::new(0);
        let progress = |_: usize, _: usize| {
            calls.fetch_add(1, Ordering::SeqCst);
            cancel.store(true, Ordering::SeqCst);
        };
        let e = compute_maps_cancellable(&image, &settings, Some(&progress), &cancel).expect_err("cancelled");
        assert!(e.to_string().contains("interrupted"), "{e}");
        let done = calls.load(Ordering::SeqCst);
        assert!(
            (1..=1 + threads).contains(&done),
            "{width} texels: {done} evaluations after a cancel at the first (at most {} expected)",
            1 + threads
        );
    }
}
