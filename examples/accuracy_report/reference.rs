//! The converged reference per preset, and the measurement of any accuracy setting against it.

use std::collections::BTreeMap;

use serde::Serialize;
use spectral_skin::color::spectrum_to_rgb;
use spectral_skin::evaluate::{Prepared, ProfileGrid};
use spectral_skin::fit::burley::{edge_misfit, fit_frequencies};
use spectral_skin::transport::Transport;
use spectral_skin::{evaluate, Accuracy, Evaluation, Outputs, Request, SkinParams, PRESETS};

use crate::metrics::{delta_e_2000, max_relative, median_seconds, profile_log_error};

/// Radii on which profiles are compared: 0.01 to 10 mm, log-spaced (the range).
pub const PROFILE_GRID: ProfileGrid = ProfileGrid { r_min_mm: 0.01, r_max_mm: 10.0, count: 41 };
/// Frequencies per decade of the reference transfer function (the edge misfit's grid).
const REFERENCE_FIT_PER_DECADE: f64 = 16.0;

/// One preset's converged figures.
pub struct PresetReference {
    pub name: &'static str,
    pub params: SkinParams,
    pub albedo: [f64; 3],
    pub radius_mm: [f64; 3],
    pub profile: Vec<[f64; 3]>,
    /// The profile with the reference quadrature on the default wavelength grid: the reference of the quadrature knobs
    /// (Hankel, FFT), which leaves out the spectral sampling's own share of the profile error.
    pub profile_default_wavelengths: Vec<[f64; 3]>,
    /// Albedo and radius with the reference settings on the default wavelength grid: the reference of the knobs other
    /// than the wavelengths (`albedo_knob`, `radius_knob`), without the wavelength sampling's share.
    pub albedo_default_wavelengths: [f64; 3],
    pub radius_default_wavelengths_mm: [f64; 3],
    /// Log-spaced frequencies and the normalised RGB transfer function N_c(s) = R~_c(s) / R~_c(0) on them.
    pub s_per_mm: Vec<f64>,
    pub normalized: [Vec<f64>; 3],
}

/// Which figures a measurement computes.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Task {
    /// Albedo and radius: what a material (and every texel) needs; timed as one such evaluation.
    Material,
    /// The RGB radial profile on [`PROFILE_GRID`]; timed as one such evaluation.
    Profile,
}

/// A measured setting: its time and its errors against the reference (worst over the presets).
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub series: String,
    pub label: String,
    /// Median wall time of one evaluation for the caucasian preset (2 threads), seconds.
    pub time_s: f64,
    pub metrics: BTreeMap<&'static str, f64>,
    pub is_default: bool,
    /// The evaluated settings (None for rows that are not one `Accuracy`).
    #[serde(skip)]
    pub accuracy: Option<Accuracy>,
}

pub fn request(accuracy: Accuracy, task: Task) -> Request {
    let outputs = match task {
        Task::Material => Outputs { albedo: true, radius: true, ..Outputs::default() },
        Task::Profile => Outputs { profile_rgb: true, ..Outputs::default() },
    };
    let mut accuracy = accuracy;
    accuracy.profile_grid = PROFILE_GRID;
    Request { outputs, accuracy, ..Request::default() }
}

impl PresetReference {
    pub fn compute(name: &'static str, params: SkinParams) -> PresetReference {
        let reference = Accuracy::reference();
        let material = evaluate(&params, &request(reference, Task::Material)).expect("reference evaluation");
        let profile = evaluate(&params, &request(reference, Task::Profile)).expect("reference profile");
        let d = Accuracy::default();
        let same_grid = Accuracy {
            wavelength_step_nm: d.wavelength_step_nm,
            wavelength_placement: d.wavelength_placement,
            ..reference
        };
        let quadrature = evaluate(&params, &request(same_grid, Task::Profile)).expect("reference quadrature profile");
        let same_grid_material =
            evaluate(&params, &request(same_grid, Task::Material)).expect("reference on the default grid");
        let (s_per_mm, normalized) = transfer_function(&params, reference, material.diffuse_reflectance_rgb.unwrap());
        PresetReference {
            name,
            params,
            albedo: material.diffuse_reflectance_rgb.unwrap(),
            radius_mm: material.methods.unwrap().burley.subsurface_radius_mm,
            profile: profile.profile.unwrap().rgb_per_mm2.unwrap(),
            profile_default_wavelengths: quadrature.profile.unwrap().rgb_per_mm2.unwrap(),
            albedo_default_wavelengths: same_grid_material.diffuse_reflectance_rgb.unwrap(),
            radius_default_wavelengths_mm: same_grid_material.methods.unwrap().burley.subsurface_radius_mm,
            s_per_mm,
            normalized,
        }
    }
}

/// The RGB transfer function, normalised by the albedo, on the dense reference frequency grid.
fn transfer_function(params: &SkinParams, accuracy: Accuracy, albedo: [f64; 3]) -> (Vec<f64>, [Vec<f64>; 3]) {
    let prepared = Prepared::new(&request(accuracy, Task::Material)).expect("prepared");
    let s = fit_frequencies(REFERENCE_FIT_PER_DECADE);
    // Each wavelength's transform as the core's radius fit sees it (the exact shape times the exact total).
    let transforms = prepared.transforms(params, &s).expect("transforms");
    let rgb: Vec<[f64; 3]> = (0..s.len())
        .map(|i| spectrum_to_rgb(&transforms.iter().map(|t| t[i]).collect::<Vec<_>>(), prepared.rgb_weights()))
        .collect();
    let normalized = [0, 1, 2].map(|c| rgb.iter().map(|v| v[c] / albedo[c]).collect());
    (s, normalized)
}

pub fn references() -> Vec<PresetReference> {
    PRESETS.iter().map(|p| PresetReference::compute(p.name, p.params)).collect()
}

/// Errors of one evaluation against its preset's reference.
pub fn errors_of(ev: &Evaluation, reference: &PresetReference) -> BTreeMap<&'static str, f64> {
    let mut m = BTreeMap::new();
    let d = Accuracy::default();
    let default_grid = ev.accuracy.wavelength_step_nm == d.wavelength_step_nm
        && ev.accuracy.wavelength_placement == d.wavelength_placement;
    if let Some(albedo) = ev.diffuse_reflectance_rgb {
        m.insert("albedo_rel", max_relative(albedo, reference.albedo));
        m.insert("delta_e00", delta_e_2000(albedo, reference.albedo));
        if default_grid {
            m.insert("albedo_knob", max_relative(albedo, reference.albedo_default_wavelengths));
        }
    }
    if let Some(methods) = ev.methods {
        let radius = methods.burley.subsurface_radius_mm;
        m.insert("radius_rel", max_relative(radius, reference.radius_mm));
        if default_grid {
            m.insert("radius_knob", max_relative(radius, reference.radius_default_wavelengths_mm));
        }
        let d = ev.radius_fit.unwrap().map(|f| f.d_mm);
        let edge = (0..3).map(|c| edge_misfit(&reference.s_per_mm, &reference.normalized[c], d[c])).fold(0.0, f64::max);
        m.insert("edge_misfit", edge);
    }
    if let Some(profile) = ev.profile.as_ref().and_then(|p| p.rgb_per_mm2.as_ref()) {
        m.insert("profile_log", profile_log_error(&PROFILE_GRID.radii_mm(), profile, &reference.profile));
        if default_grid {
            m.insert(
                "quadrature_log",
                profile_log_error(&PROFILE_GRID.radii_mm(), profile, &reference.profile_default_wavelengths),
            );
        }
    }
    m
}

/// Worst of each metric over several maps.
pub fn worst(maps: impl IntoIterator<Item = BTreeMap<&'static str, f64>>) -> BTreeMap<&'static str, f64> {
    let mut out = BTreeMap::new();
    for m in maps {
        for (k, v) in m {
            let e = out.entry(k).or_insert(0.0f64);
            *e = e.max(v);
        }
    }
    out
}

/// Timing budget per measured setting.
#[derive(Clone, Copy)]
pub struct Budget {
    pub min_runs: usize,
    pub seconds: f64,
}

/// Measure `accuracy` for `task` over every preset: worst errors, and the median time of the caucasian evaluation on
/// one thread (steadier than two, and what one table node or one texel costs): `Prepared::material` for a material,
/// `evaluate` for a profile.
pub fn measure(
    refs: &[PresetReference],
    accuracy: Accuracy,
    task: Task,
    budget: Budget,
) -> (f64, BTreeMap<&'static str, f64>) {
    measure_request(refs, &request(accuracy, task), task, budget)
}

/// [`measure`] of a whole request (one whose transport is not the default's, say).
pub fn measure_request(
    refs: &[PresetReference],
    req: &Request,
    task: Task,
    budget: Budget,
) -> (f64, BTreeMap<&'static str, f64>) {
    let req = *req;
    let metrics = worst(refs.iter().map(|r| errors_of(&evaluate(&r.params, &req).expect("evaluation"), r)));
    let timed = &refs[0].params;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("one-thread pool");
    let time = pool.install(|| match task {
        Task::Material => {
            let prepared = Prepared::new(&req).expect("prepared");
            median_seconds(budget.min_runs, budget.seconds, || {
                std::hint::black_box(prepared.material(timed).expect("material"));
            })
        }
        Task::Profile => median_seconds(budget.min_runs, budget.seconds, || {
            std::hint::black_box(evaluate(timed, &req).expect("evaluation"));
        }),
    });
    (time, metrics)
}

/// A measured row.
pub fn row(
    refs: &[PresetReference],
    series: &str,
    label: String,
    accuracy: Accuracy,
    task: Task,
    budget: Budget,
) -> Row {
    let (time_s, metrics) = measure(refs, accuracy, task, budget);
    let is_default = accuracy == Accuracy::default();
    Row { series: series.to_string(), label, time_s, metrics, is_default, accuracy: Some(accuracy) }
}

/// A measured row of the default accuracy with another transport (the profile's shape and the totals' solver).
pub fn transport_row(refs: &[PresetReference], transport: Transport, budget: Budget) -> Row {
    let req = Request { transport, ..request(Accuracy::default(), Task::Material) };
    let (time_s, metrics) = measure_request(refs, &req, Task::Material, budget);
    Row {
        series: "transport".to_string(),
        label: transport.name().to_string(),
        time_s,
        metrics,
        is_default: transport == Transport::default(),
        accuracy: Some(Accuracy::default()),
    }
}
