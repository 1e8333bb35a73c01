//! One function per accuracy knob: each varies that knob with every other at its default, and measures error against
//! the converged reference and time.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::Serialize;
use spectral_skin::color::{spectrum_to_rgb, WavelengthGrid, WavelengthPlacement};
use spectral_skin::diffusion::fft_route::{fft_reflectance_profiles_with, FftGrid, PixelSampling};
use spectral_skin::diffusion::{Combination, HankelQuadrature, MultipoleTerms};
use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::RadiusFit;
use spectral_skin::maps::example::face_params;
use spectral_skin::maps::lut::{measure_error, MaterialTable, TableResolution};
use spectral_skin::maps::pipeline::Strategy;
use spectral_skin::maps::{compute_maps, MapSettings};
use spectral_skin::transport::ALL_TRANSPORTS;
use spectral_skin::{Accuracy, AccuracyLevel, Outputs, Request};

use crate::metrics::{delta_e_2000, max_relative, median_seconds, profile_log_error};
use crate::reference::{request, row, transport_row, worst, Budget, PresetReference, Row, Task, PROFILE_GRID};

/// A knob's measurements.
#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    pub key: &'static str,
    pub title: &'static str,
    /// What the time column measures.
    pub timed: &'static str,
    /// The metric on the plot's y axis.
    pub plot_metric: &'static str,
    pub rows: Vec<Row>,
}

pub struct Settings {
    pub quick: bool,
    pub budget: Budget,
}

pub fn wavelengths(refs: &[PresetReference], s: &Settings) -> Sweep {
    let steps: &[f64] = if s.quick { &[5.0, 20.0] } else { &[1.0, 2.0, 5.0, 10.0, 20.0, 40.0] };
    let mut rows = Vec::new();
    for (series, placement, steps) in [
        ("uniform", WavelengthPlacement::Uniform, steps),
        (
            "CMF-adapted",
            WavelengthPlacement::CmfAdapted,
            if s.quick { &[20.0][..] } else { &[5.0, 10.0, 20.0, 40.0][..] },
        ),
        ("RGB shortcut", WavelengthPlacement::RgbShortcut, &[5.0][..]),
    ] {
        for &step in steps {
            let acc = Accuracy { wavelength_step_nm: step, wavelength_placement: placement, ..Accuracy::default() };
            let count = WavelengthGrid::new(placement, step).wavelengths_nm.len();
            let label = match placement {
                WavelengthPlacement::RgbShortcut => "3 λ".to_string(),
                WavelengthPlacement::Uniform => format!("{step} nm"),
                WavelengthPlacement::CmfAdapted => format!("{count} λ"),
            };
            let mut r = row(refs, series, label, acc, Task::Material, s.budget);
            r.metrics.insert("wavelengths", count as f64);
            rows.push(r);
        }
    }
    Sweep {
        key: "wavelengths",
        title: "Wavelength sampling",
        timed: "albedo + radius",
        plot_metric: "albedo_rel",
        rows,
    }
}

/// The adding-doubling stream count (the transport of the totals): error against the reference (32 streams) and time.
/// What the streams cost in accuracy against the Monte Carlo is the "Transport against Monte Carlo" table.
pub fn streams(refs: &[PresetReference], s: &Settings) -> Sweep {
    let counts: &[usize] = if s.quick { &[4, 8] } else { &[4, 6, 8, 12, 16, 24] };
    let rows = counts
        .iter()
        .map(|&n| {
            let acc = Accuracy { streams: n, ..Accuracy::default() };
            row(refs, "adding-doubling streams", format!("{n}"), acc, Task::Material, s.budget)
        })
        .collect();
    Sweep {
        key: "streams",
        title: "Adding-doubling streams (exact transport)",
        timed: "albedo + radius",
        plot_metric: "albedo_rel",
        rows,
    }
}

pub fn multipole(refs: &[PresetReference], s: &Settings) -> Sweep {
    let pairs: &[u32] = if s.quick { &[0, 2] } else { &[0, 1, 2, 3, 5, 10, 20] };
    let mut rows: Vec<Row> = pairs
        .iter()
        .map(|&n| {
            let acc = Accuracy { multipole_terms: MultipoleTerms::Pairs(n), ..Accuracy::default() };
            row(refs, "image pairs", format!("{n}"), acc, Task::Material, s.budget)
        })
        .collect();
    rows.push(row(refs, "closed form", "all".into(), Accuracy::default(), Task::Material, s.budget));
    Sweep { key: "multipole", title: "Multipole terms", timed: "albedo + radius", plot_metric: "albedo_knob", rows }
}

/// Inverse-Hankel quadrature: nodes per panel x panel refinement, and the cut-off.
pub fn hankel(refs: &[PresetReference], s: &Settings) -> Sweep {
    let orders: &[usize] = if s.quick { &[4, 8] } else { &[3, 4, 6, 8, 12] };
    let refinements: &[f64] = if s.quick { &[1.0] } else { &[0.25, 0.5, 1.0, 2.0] };
    let mut rows = Vec::new();
    for &refinement in refinements {
        for &gauss_order in orders {
            let hankel = HankelQuadrature { gauss_order, refinement, ..HankelQuadrature::default() };
            let acc = Accuracy { hankel, ..Accuracy::default() };
            rows.push(row(
                refs,
                &format!("refinement {refinement}"),
                format!("{gauss_order}"),
                acc,
                Task::Profile,
                s.budget,
            ));
        }
    }
    let cutoffs: &[f64] = if s.quick { &[1e-7] } else { &[1e-5, 1e-7, 1e-11, 1e-13] };
    for &cutoff in cutoffs {
        let hankel = HankelQuadrature { cutoff, ..HankelQuadrature::default() };
        let acc = Accuracy { hankel, ..Accuracy::default() };
        rows.push(row(refs, "cut-off", format!("{cutoff:.0e}"), acc, Task::Profile, s.budget));
    }
    Sweep {
        key: "hankel",
        title: "Inverse-Hankel quadrature (radial profile)",
        timed: "RGB profile, 41 radii",
        plot_metric: "quadrature_log",
        rows,
    }
}

/// The paper's route: sampled real-space profiles, 2-D FFT, layers combined per frequency bin, inverse FFT. The speed
/// comparison is on the caucasian preset (`quadrature_log`), whose profiles a 40 mm grid can resolve; the worst over
/// all presets is `quadrature_log_all`. The closed-form rows are the Hankel sweep's settings on the same preset.
pub fn fft(refs: &[PresetReference], s: &Settings, hankel: &Sweep) -> Sweep {
    let sizes: &[usize] = if s.quick { &[64, 128] } else { &[128, 256, 512, 1024] };
    // The extent covers the caucasian red tail (a 20 mm tile wraps its periodic copy onto r = 10 mm).
    let extent_mm = 40.0;
    // The default's wavelengths, colour weights and layers: the comparison is of the two routes alone.
    let prepared = Prepared::new(&request(Accuracy::default(), Task::Profile)).expect("prepared");
    let weights = prepared.rgb_weights();
    let radii = PROFILE_GRID.radii_mm();
    let run = |r: &PresetReference, fft_grid: FftGrid, sampling: PixelSampling| {
        let stacks = prepared.stacks(&r.params).expect("layers");
        let out = fft_reflectance_profiles_with(
            &stacks,
            &radii,
            Combination::Directional,
            MultipoleTerms::All,
            fft_grid,
            sampling,
        )
        .expect("fft route");
        let profile: Vec<[f64; 3]> = (0..radii.len())
            .map(|i| spectrum_to_rgb(&out.profiles.iter().map(|p| p[i]).collect::<Vec<_>>(), weights))
            .collect();
        (spectrum_to_rgb(&out.totals, weights), profile)
    };
    let mut rows = Vec::new();
    for (series, sampling) in
        [("FFT, pixel centres (DJ05)", PixelSampling::Centre), ("FFT, pixel areas", PixelSampling::Area)]
    {
        for &size in sizes {
            let fft_grid = FftGrid { size, extent_mm };
            // The first preset (caucasian) is the timed one, on one thread like the closed form; large grids are timed
            // by that one run.
            let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("one-thread pool");
            let mut time_s = f64::NAN;
            let metrics = worst(refs.iter().enumerate().map(|(k, r)| {
                let start = Instant::now();
                let (albedo, profile) =
                    if k == 0 { one_thread.install(|| run(r, fft_grid, sampling)) } else { run(r, fft_grid, sampling) };
                if k == 0 {
                    time_s = start.elapsed().as_secs_f64();
                }
                let mut m = BTreeMap::new();
                m.insert("albedo_rel", max_relative(albedo, r.albedo));
                m.insert("delta_e00", delta_e_2000(albedo, r.albedo));
                m.insert("profile_log", profile_log_error(&PROFILE_GRID.radii_mm(), &profile, &r.profile));
                m.insert(
                    "quadrature_log_all",
                    profile_log_error(&PROFILE_GRID.radii_mm(), &profile, &r.profile_default_wavelengths),
                );
                if k == 0 {
                    m.insert(
                        "quadrature_log",
                        profile_log_error(&PROFILE_GRID.radii_mm(), &profile, &r.profile_default_wavelengths),
                    );
                }
                m
            }));
            if size < 512 {
                time_s = one_thread.install(|| {
                    median_seconds(s.budget.min_runs, s.budget.seconds, || {
                        std::hint::black_box(run(&refs[0], fft_grid, sampling));
                    })
                });
            }
            let mut metrics = metrics;
            metrics.insert("pixel_mm", extent_mm / size as f64);
            rows.push(Row {
                series: series.into(),
                label: format!("{size}²"),
                time_s,
                metrics,
                is_default: false,
                accuracy: None,
            });
        }
    }
    // The closed form on the same preset: the Hankel sweep's settings (their times are already the caucasian ones).
    let caucasian = &refs[0];
    for h in &hankel.rows {
        let Some(accuracy) = h.accuracy else { continue };
        let ev = spectral_skin::evaluate(&caucasian.params, &request(accuracy, Task::Profile)).expect("profile");
        let profile = ev.profile.unwrap().rgb_per_mm2.unwrap();
        let mut metrics = BTreeMap::new();
        metrics.insert(
            "quadrature_log",
            profile_log_error(&PROFILE_GRID.radii_mm(), &profile, &caucasian.profile_default_wavelengths),
        );
        rows.push(Row { series: format!("closed form, {}", h.series), metrics, accuracy: None, ..h.clone() });
    }
    Sweep {
        key: "fft",
        title: "FFT convolution route (DJ05) vs closed form",
        timed: "RGB profile, 41 radii",
        plot_metric: "quadrature_log",
        rows,
    }
}

/// Radius fit: frequencies per decade of the edge fit, and the second-moment shortcut.
pub fn radius_fit(refs: &[PresetReference], s: &Settings) -> Sweep {
    let per_decade: &[f64] = if s.quick { &[2.0, 4.0] } else { &[2.0, 3.0, 4.0, 6.0, 8.0, 16.0] };
    let mut rows: Vec<Row> = per_decade
        .iter()
        .map(|&n| {
            let acc = Accuracy { fit_frequencies_per_decade: n, ..Accuracy::default() };
            row(refs, "edge L2 fit", format!("{n}/dec"), acc, Task::Material, s.budget)
        })
        .collect();
    let acc = Accuracy { radius_fit: RadiusFit::SecondMoment, ..Accuracy::default() };
    rows.push(row(refs, "second moment", "moment".into(), acc, Task::Material, s.budget));
    Sweep { key: "radius_fit", title: "Radius fit", timed: "albedo + radius", plot_metric: "radius_knob", rows }
}

/// The transport (the totals' solver and the profile's shape): the exact shapes of the table (default), the
/// multipole's shape scaled to the exact totals, and the paper's diffusion; error against the reference, time.
pub fn transport(refs: &[PresetReference], s: &Settings) -> Sweep {
    let rows = ALL_TRANSPORTS.iter().map(|&t| transport_row(refs, t, s.budget)).collect();
    Sweep {
        key: "transport",
        title: "Transport and profile shape",
        timed: "albedo + radius",
        plot_metric: "radius_rel",
        rows,
    }
}

/// Lookup-table resolution of the map pipeline: error against direct evaluation, build time, map time.
pub fn table(s: &Settings, map_size: usize) -> Sweep {
    let resolutions: &[(usize, usize, usize)] = if s.quick {
        &[(9, 3, 5), (17, 4, 9)]
    } else {
        &[(9, 3, 5), (17, 4, 9), (25, 5, 13), (33, 7, 17), (33, 9, 17), (49, 10, 25), (65, 13, 33)]
    };
    let prepared = Prepared::new(&Request::new(Outputs::material())).expect("prepared");
    let face = face_params(map_size);
    let samples = if s.quick { 64 } else { 2000 };
    let cache = tempfile::tempdir().expect("temporary cache folder");
    let mut rows = Vec::new();
    for &(m, b, h) in resolutions {
        let resolution = TableResolution { melanin: m, melanin_blend: b, hemoglobin: h };
        let start = Instant::now();
        let table = MaterialTable::build(&prepared, spectral_skin::fit::DEFAULT_METHOD, resolution).expect("table");
        let build_s = start.elapsed().as_secs_f64();
        let error = measure_error(&table, &prepared, samples).expect("table error");
        let settings = MapSettings {
            table: resolution,
            table_check_samples: 0,
            table_cache: Some(cache.path().to_path_buf()),
            ..MapSettings::default()
        };
        compute_maps(&face, &settings, None).expect("maps (builds and caches the table)");
        let map_s = median_seconds(s.budget.min_runs.min(3), 0.0, || {
            let result = compute_maps(&face, &settings, None).expect("maps");
            assert!(matches!(result.report.strategy, Strategy::Table { from_cache: true, .. }));
        });
        let mut metrics = BTreeMap::new();
        metrics.insert("albedo_rel", error.max_albedo_relative);
        metrics.insert("radius_rel", error.max_radius_relative);
        metrics.insert("build_s", build_s);
        metrics.insert("map_s", map_s);
        metrics.insert("table_kib", resolution.node_count() as f64 * 48.0 / 1024.0);
        rows.push(Row {
            series: "table".into(),
            label: format!("{m}×{b}×{h}"),
            time_s: build_s,
            metrics,
            is_default: resolution == TableResolution::default(),
            accuracy: None,
        });
    }
    Sweep {
        key: "table",
        title: "Lookup-table resolution (map pipeline)",
        timed: "table build",
        plot_metric: "albedo_rel",
        rows,
    }
}

/// The named levels, on every metric, with the time of a material, a profile and a whole map.
pub fn levels(refs: &[PresetReference], s: &Settings, map_size: usize) -> Sweep {
    let face = face_params(map_size);
    let mut rows = Vec::new();
    for level in spectral_skin::accuracy::ALL_ACCURACY_LEVELS {
        if s.quick && level == AccuracyLevel::Reference {
            continue;
        }
        let acc = level.accuracy();
        let mut r = row(refs, "level", level.name().into(), acc, Task::Material, s.budget);
        let p = row(refs, "level", level.name().into(), acc, Task::Profile, s.budget);
        r.metrics.insert("profile_log", p.metrics["profile_log"]);
        r.metrics.insert("profile_s", p.time_s);
        let settings = MapSettings {
            request: Request { accuracy: acc, ..Request::new(Outputs::material()) },
            table_check_samples: 0,
            ..MapSettings::default()
        };
        let start = Instant::now();
        let result = compute_maps(&face, &settings, None).expect("maps");
        r.metrics.insert("map_cold_s", start.elapsed().as_secs_f64());
        if let Strategy::Table { build_seconds, .. } = result.report.strategy {
            r.metrics.insert("table_build_s", build_seconds);
        }
        r.metrics.insert(
            "wavelengths",
            WavelengthGrid::new(acc.wavelength_placement, acc.wavelength_step_nm).wavelengths_nm.len() as f64,
        );
        rows.push(r);
    }
    Sweep { key: "levels", title: "Named accuracy levels", timed: "albedo + radius", plot_metric: "albedo_rel", rows }
}
