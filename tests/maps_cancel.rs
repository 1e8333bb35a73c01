//! `compute_maps_cancellable`: a cancel flag set from the progress callback stops the work at the next row, and a
//! flag never set changes nothing. The reference is `compute_maps` itself on the same image (the uncancelled result)
//! and the count of rows the callback saw.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use spectral_skin::maps::example::face_params;
use spectral_skin::maps::pipeline::{check_planes, compute_maps_cancellable};
use spectral_skin::maps::{compute_maps, MapSettings, StrategyChoice};

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

    // Cancel once a quarter of the rows are done.
    let cancel = AtomicBool::new(false);
    let rows = AtomicUsize::new(0);
    let progress = |_: usize, _: usize| {
        if rows.fetch_add(1, Ordering::SeqCst) + 1 >= 12 {
            cancel.store(true, Ordering::SeqCst);
        }
    };
    let part = compute_maps_cancellable(&image, &settings, Some(&progress), &cancel).expect("maps");
    let done = rows.load(Ordering::SeqCst);
    assert!((12..48).contains(&done), "{done} rows done of 48");
    let width = image.width;
    let written_rows =
        (0..image.height).filter(|y| part.base_color[0][y * width..(y + 1) * width].iter().any(|&v| v != 0.0)).count();
    assert_eq!(written_rows, done, "rows written = rows reported");
    for y in 0..image.height {
        let row = y * width..(y + 1) * width;
        if part.base_color[0][row.clone()].iter().any(|&v| v != 0.0) {
            assert_eq!(part.base_color[0][row.clone()], full.base_color[0][row], "a finished row is complete");
        }
    }
}
