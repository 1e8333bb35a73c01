//! Fit to an RGB colour: the parameters (C_m, beta_m, C_h) whose model albedo (linear RGB in the working space, as
//! `evaluate`'s `diffuse_reflectance_rgb`) is closest in CIEDE2000 to a target colour, at fixed extended physiology.
//!
//! An RGB colour has three numbers and the model three free parameters, but they are not independent everywhere: a
//! little more eumelanin (beta_m) and a little less blood (C_h) can give nearly the same colour. The fit therefore
//! minimises ΔE00² + (w (beta_m - beta_prior))², a Tikhonov prior pulling the melanin blend toward a typical value
//! (`DEFAULT_MELANIN_BLEND_PRIOR`) with a small weight (`DEFAULT_PRIOR_WEIGHT`, ΔE00 per unit of beta_m), so that it
//! decides only where the colour does not, and reports the ambiguity it resolved: the parameters of the best fit at
//! each melanin blend on a grid whose colour is within `ambiguity_delta_e` of the target ([`Ambiguity`]).
//!
//! The search runs in the table coordinates of src/maps/lut.rs: u_m = (C_m / 0.5)^(1/3), beta_m, u_h = (C_h /
//! 0.1)^(1/3), each in [0, 1] (equal steps are similar changes in colour). A forward table over them ([`AlbedoTable`])
//! gives the start (the nearest node in CIELAB) and a bounded Levenberg-Marquardt refinement on the three-term
//! vector whose length is ΔE00 (`ciede2000_terms`); the single-colour fit then polishes with direct evaluation.
//! Out-of-gamut targets (a green texel) end at the nearest reachable colour on the domain's boundary, with their ΔE00
//! reported; nothing returns NaN.

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

use serde::Serialize;

use super::lm::{self, LmSettings};
use crate::color::difference::{ciede2000, ciede2000_terms, LabConverter};
use crate::color::WorkingSpace;
use crate::error::{check_range, SkinError};
use crate::evaluate::{Accuracy, Outputs, Prepared, Request};
use crate::maps::lut::{unwarp, warp, MaterialTable, TableResolution};
use crate::skin::params::{
    BLOOD_OXYGENATION, EPIDERMIS_THICKNESS, EXTENDED_DEFAULTS, HEMOGLOBIN, MELANIN, MELANIN_BLEND,
};
use crate::skin::SkinParams;
use crate::transport::{ExactTotals, Transport, DEFAULT_STREAMS};

/// The melanin blend the prior pulls toward: 0.7, that of the Caucasian and African skin types of Donner & Jensen
/// (2006, teaser caption; `PRESETS`).
pub const DEFAULT_MELANIN_BLEND_PRIOR: f64 = 0.7;
/// The prior's weight, ΔE00 per unit of beta_m: a fit may move beta_m the whole range from the prior for 0.2 ΔE00
/// of colour (well under the 0.5 to 1 ΔE00 of a just noticeable difference), so the colour decides wherever it can.
pub const DEFAULT_PRIOR_WEIGHT: f64 = 0.2;
/// The ΔE00 within which parameters count as reproducing a colour (the ambiguity set, `in_gamut`): 0.5, about half
/// a just noticeable difference.
pub const DEFAULT_AMBIGUITY_DELTA_E: f64 = 0.5;
/// Oiliness written into fitted parameter maps when none is given: 0.3, the DJ2006 presets' (albedo does not
/// depend on it).
pub const DEFAULT_OILINESS: f64 = 0.3;

/// The range each RGB gain (`rgb_gains`, and `albedo_gains`' estimate) is kept in (a factor 64 either way: six stops).
pub const GAIN_RANGE: (f64, f64) = (1.0 / 64.0, 64.0);
/// The melanin blends scanned for the ambiguity set.
const AMBIGUITY_BLEND_STEPS: usize = 21;

/// What the fit holds fixed and how it regularises.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoFitOptions {
    pub working_space: WorkingSpace,
    /// epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation (held fixed; default the paper's).
    pub extended: [f64; 3],
    /// Written into the result (the albedo does not depend on it).
    pub oiliness: f64,
    pub melanin_blend_prior: f64,
    pub prior_weight: f64,
    pub ambiguity_delta_e: f64,
    /// How the model's albedo is computed (exact totals by default, [`Transport`]) and the adding-doubling streams.
    pub transport: Transport,
    pub streams: usize,
    /// Exact totals from the shipped table (the default) or solved at `streams` ([`ExactTotals`]).
    pub exact_totals: ExactTotals,
    /// Exposure and white balance: each target colour's (texel's) linear RGB is multiplied by these before the fit
    /// (default 1, 1, 1; [`super::albedo_gains`] estimates them for a photograph).
    pub rgb_gains: [f64; 3],
}

impl Default for AlbedoFitOptions {
    fn default() -> Self {
        AlbedoFitOptions {
            working_space: WorkingSpace::default(),
            extended: EXTENDED_DEFAULTS,
            oiliness: DEFAULT_OILINESS,
            melanin_blend_prior: DEFAULT_MELANIN_BLEND_PRIOR,
            prior_weight: DEFAULT_PRIOR_WEIGHT,
            ambiguity_delta_e: DEFAULT_AMBIGUITY_DELTA_E,
            transport: Transport::default(),
            streams: DEFAULT_STREAMS,
            exact_totals: ExactTotals::Table,
            rgb_gains: [1.0; 3],
        }
    }
}

impl AlbedoFitOptions {
    /// The options if every value is in range (the extended parameters' and oiliness' ranges of `PARAMS`).
    pub fn validated(self) -> Result<Self, SkinError> {
        SkinParams::from_values([0.0, 0.0, 0.0, self.oiliness, self.extended[0], self.extended[1], self.extended[2]])?;
        check_range(
            "melanin_blend_prior",
            "the melanin blend the prior pulls toward",
            self.melanin_blend_prior,
            0.0,
            1.0,
        )?;
        check_range("prior_weight", "ΔE00 per unit of melanin blend", self.prior_weight, 0.0, 100.0)?;
        check_range("ambiguity_delta_e", "ΔE00 of the ambiguity set", self.ambiguity_delta_e, 1e-6, 100.0)?;
        crate::transport::adding_doubling::validate_streams(self.streams)?;
        let (lo, hi) = GAIN_RANGE;
        for (name, g) in ["rgb_gains[0] (R)", "rgb_gains[1] (G)", "rgb_gains[2] (B)"].iter().zip(self.rgb_gains) {
            if !(lo..=hi).contains(&g) {
                return Err(SkinError::invalid(
                    *name,
                    format!("must be in [{lo}, {hi}] (a factor on the colour's linear RGB); got {g}"),
                ));
            }
        }
        Ok(self)
    }

    /// The evaluation the fit inverts: the albedo alone, default accuracy (with the options' streams), in the working
    /// space, with the options' transport.
    pub fn prepared(&self) -> Result<Prepared, SkinError> {
        let request = Request::new(Outputs { albedo: true, ..Outputs::default() });
        Prepared::new(&Request {
            working_space: self.working_space,
            transport: self.transport,
            accuracy: Accuracy { streams: self.streams, exact_totals: self.exact_totals, ..request.accuracy },
            ..request
        })
    }

    /// The parameters at table coordinates `u` (clamped to [0, 1]).
    pub fn params_at(&self, u: [f64; 3]) -> SkinParams {
        let [um, b, uh] = u.map(|x| x.clamp(0.0, 1.0));
        SkinParams {
            melanin: unwarp(um, MELANIN.max),
            melanin_blend: MELANIN_BLEND.min + b * (MELANIN_BLEND.max - MELANIN_BLEND.min),
            hemoglobin: unwarp(uh, HEMOGLOBIN.max),
            oiliness: self.oiliness,
            epidermis_thickness_mm: self.extended[0],
            baseline_absorption_scale: self.extended[1],
            blood_oxygenation: self.extended[2],
        }
    }
}

/// Table coordinates of parameters (inverse of [`AlbedoFitOptions::params_at`]).
pub fn table_coordinates(p: &SkinParams) -> [f64; 3] {
    [warp(p.melanin, MELANIN.max), p.melanin_blend, warp(p.hemoglobin, HEMOGLOBIN.max)]
}

/// Nodes per axis (u_m, beta_m, u_h) of the fit's forward table: chosen so that the table's colour error (ΔE00
/// against direct evaluation, `tests/inverse/inverse_albedo.rs`) leaves room within the 0.5 ΔE00 a fit must reach.
pub const ALBEDO_TABLE_RESOLUTION: TableResolution = TableResolution { melanin: 41, melanin_blend: 11, hemoglobin: 25 };

/// The model albedo over the table coordinates at fixed extended physiology, for the fits: an albedo-only
/// [`MaterialTable`] (the maps' table over the same warped axes: ln albedo at each node, interpolated trilinearly)
/// with the CIELAB of each node's albedo.
#[derive(Debug, Clone)]
pub struct AlbedoTable {
    table: MaterialTable,
    /// CIELAB of each node's albedo (the coarse search's candidates).
    lab: Vec<[f64; 3]>,
    converter: LabConverter,
}

impl AlbedoTable {
    /// Evaluate every node (in parallel).
    pub fn build(options: &AlbedoFitOptions) -> Result<AlbedoTable, SkinError> {
        AlbedoTable::build_cancellable(options, &AtomicBool::new(false))
    }

    /// [`AlbedoTable::build`] that stops once `cancel` is set (read before each node), with
    /// [`SkinError::interrupted`].
    pub fn build_cancellable(options: &AlbedoFitOptions, cancel: &AtomicBool) -> Result<AlbedoTable, SkinError> {
        AlbedoTable::build_ticking(options, cancel, None)
    }

    /// [`AlbedoTable::build_cancellable`] that calls `tick` about once per percent of the nodes (from the worker
    /// threads), so that a front's progress callback is asked during the build.
    pub fn build_ticking(
        options: &AlbedoFitOptions,
        cancel: &AtomicBool,
        tick: Option<&(dyn Fn() + Sync)>,
    ) -> Result<AlbedoTable, SkinError> {
        let options = options.validated()?;
        let prepared = options.prepared()?;
        // An albedo-only table: no node fits a radius, so the method only names the target's entry.
        let table = MaterialTable::build_outputs(
            &prepared,
            crate::fit::DEFAULT_METHOD,
            ALBEDO_TABLE_RESOLUTION,
            false,
            options.extended,
            cancel,
            tick,
        )?;
        let converter = LabConverter::new(options.working_space);
        let lab = (0..table.node_count()).map(|n| converter.lab(table.node_albedo(n))).collect();
        Ok(AlbedoTable { table, lab, converter })
    }

    pub fn node_count(&self) -> usize {
        self.table.node_count()
    }

    /// Nodes per axis (u_m, beta_m, u_h).
    fn axes(&self) -> [usize; 3] {
        let r = self.table.resolution();
        [r.melanin, r.melanin_blend, r.hemoglobin]
    }

    pub fn node_u(&self, i: usize) -> [f64; 3] {
        self.table.node_warped(i)
    }

    pub fn node_lab(&self, i: usize) -> [f64; 3] {
        self.lab[i]
    }

    pub fn converter(&self) -> &LabConverter {
        &self.converter
    }

    /// The albedo at table coordinates `u` (clamped to [0, 1]).
    pub fn albedo(&self, u: [f64; 3]) -> [f64; 3] {
        self.table.albedo_at_warped(u)
    }
}

/// How many forward tables [`cached_albedo_table`] keeps (about 0.3 MB each): a texture fit that chooses the
/// epidermis thickness uses up to seven.
const TABLE_CACHE_SIZE: usize = 8;

/// The forward table for `options`, from an in-process cache of the last few (keyed by working space, extended
/// physiology, transport and streams), else built. Returns whether it came from the cache.
pub fn cached_albedo_table(options: &AlbedoFitOptions) -> Result<(Arc<AlbedoTable>, bool), SkinError> {
    cached_albedo_table_cancellable(options, &AtomicBool::new(false))
}

/// [`cached_albedo_table`] whose build stops once `cancel` is set (a stopped build is not cached).
pub fn cached_albedo_table_cancellable(
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<(Arc<AlbedoTable>, bool), SkinError> {
    cached_albedo_table_ticking(options, cancel, None)
}

/// [`cached_albedo_table_cancellable`] whose build calls `tick` ([`AlbedoTable::build_ticking`]).
pub fn cached_albedo_table_ticking(
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
    tick: Option<&(dyn Fn() + Sync)>,
) -> Result<(Arc<AlbedoTable>, bool), SkinError> {
    static CACHE: Mutex<Vec<(String, Arc<AlbedoTable>)>> = Mutex::new(Vec::new());
    let key = albedo_table_key(options);
    if let Some((_, t)) = CACHE.lock().map_err(|_| poisoned())?.iter().find(|(k, _)| *k == key) {
        return Ok((t.clone(), true));
    }
    let table = Arc::new(AlbedoTable::build_ticking(options, cancel, tick)?);
    let mut cache = CACHE.lock().map_err(|_| poisoned())?;
    if cache.len() >= TABLE_CACHE_SIZE {
        cache.remove(0);
    }
    cache.push((key, table.clone()));
    Ok((table, false))
}

/// The key of [`cached_albedo_table`]'s cache: everything the table depends on.
pub fn albedo_table_key(options: &AlbedoFitOptions) -> String {
    format!(
        "{:?}|{:?}|{}|{}|{}",
        options.working_space,
        options.extended.map(f64::to_bits),
        options.transport.name(),
        options.streams,
        options.exact_totals.name()
    )
}

fn poisoned() -> SkinError {
    SkinError::invalid("albedo table cache", "a thread panicked while holding it")
}

/// The least-squares problem: residual (ΔE00 terms, prior) at table coordinates, with some coordinates held fixed.
pub(crate) struct Problem<'a, F: Fn([f64; 3]) -> [f64; 3]> {
    pub forward: F,
    pub converter: &'a LabConverter,
    pub target_lab: [f64; 3],
    pub prior: f64,
    pub weight: f64,
    pub free: [bool; 3],
}

impl<F: Fn([f64; 3]) -> [f64; 3]> Problem<'_, F> {
    fn residual(&self, u: [f64; 3]) -> [f64; 4] {
        let lab = self.converter.lab((self.forward)(u));
        let t = ciede2000_terms(self.target_lab, lab);
        [t[0], t[1], t[2], self.weight * (u[1] - self.prior)]
    }

    /// Bounded Levenberg-Marquardt ([`lm::minimize`]) from `start` over [0, 1]³ (a coordinate that is not free held
    /// at its start). Returns the coordinates and the cost |r|².
    pub fn solve(&self, start: [f64; 3], max_iterations: usize) -> ([f64; 3], f64) {
        let start = start.map(|x| x.clamp(0.0, 1.0));
        let lower = [0, 1, 2].map(|i| if self.free[i] { 0.0 } else { start[i] });
        let upper = [0, 1, 2].map(|i| if self.free[i] { 1.0 } else { start[i] });
        let settings = LmSettings { max_iterations, ..ALBEDO_LM };
        let fit = lm::minimize(|u: &[f64; 3]| self.residual(*u), start, lower, upper, &settings);
        (fit.x, fit.cost)
    }
}

/// The albedo fit's solver settings (the iterations are the caller's): derivatives over 1e-4 of the unit range of a
/// table coordinate (the table's cells are 0.025 to 0.1 wide), and the fit ends on a step that moves no coordinate by
/// more than 1e-10 or lowers ΔE00² by no more than 1e-14 (1 + ΔE00²).
const ALBEDO_LM: LmSettings = LmSettings {
    max_iterations: 40,
    difference_step: 1e-4,
    relative_tolerance: 1e-14,
    cost_floor: 1.0,
    step_tolerance: 1e-10,
};

/// The coarse start: the table node nearest the target in CIELAB (plus the prior's term), searched on every
/// `stride`-th node of the concentration axes. The hot path of a texture fit: the prior's term is taken once per
/// melanin blend and a node's coordinates only for the nearest (as [`MaterialTable::node_warped`] gives them).
pub(crate) fn coarse_start(
    table: &AlbedoTable,
    target_lab: [f64; 3],
    options: &AlbedoFitOptions,
    stride: usize,
    blend_level: Option<usize>,
) -> [f64; 3] {
    let n = table.axes();
    let mut best = (f64::INFINITY, 0);
    let levels = blend_level.map_or(0..n[1], |j| j..j + 1);
    for i in (0..n[0]).step_by(stride) {
        for j in levels.clone() {
            let blend = j as f64 / (n[1] - 1) as f64;
            let prior = (options.prior_weight * (blend - options.melanin_blend_prior)).powi(2);
            let row = (i * n[1] + j) * n[2];
            for k in (0..n[2]).step_by(stride) {
                let l = table.lab[row + k];
                let d = (0..3).map(|c| (l[c] - target_lab[c]).powi(2)).sum::<f64>() + prior;
                if d < best.0 {
                    best = (d, row + k);
                }
            }
        }
    }
    if best.0 < f64::INFINITY {
        table.node_u(best.1)
    } else {
        [0.0; 3]
    }
}

/// The cost (ΔE00² plus the prior's term) above which a table fit is restarted from other blends: 0.2² ΔE00².
const RESTART_COST: f64 = 0.04;

/// The table fit of one colour: coarse start, then Levenberg-Marquardt on the table. Returns table coordinates and
/// the table's ΔE00 there.
pub(crate) fn fit_on_table(table: &AlbedoTable, target_rgb: [f64; 3], options: &AlbedoFitOptions) -> ([f64; 3], f64) {
    let (u, de, _) = fit_on_table_costed(table, target_rgb, options);
    (u, de)
}

/// The fit of `target_lab` on the table's albedo over all three coordinates, with the options' prior.
fn table_problem<'a>(
    table: &'a AlbedoTable,
    target_lab: [f64; 3],
    options: &AlbedoFitOptions,
) -> Problem<'a, impl Fn([f64; 3]) -> [f64; 3] + 'a> {
    Problem {
        forward: |u| table.albedo(u),
        converter: table.converter(),
        target_lab,
        prior: options.melanin_blend_prior,
        weight: options.prior_weight,
        free: [true; 3],
    }
}

/// [`fit_on_table`] with the fit's cost (ΔE00² plus the prior's term) as well.
pub(crate) fn fit_on_table_costed(
    table: &AlbedoTable,
    target_rgb: [f64; 3],
    options: &AlbedoFitOptions,
) -> ([f64; 3], f64, f64) {
    let conv = table.converter();
    let target_lab = conv.lab(target_rgb);
    let problem = table_problem(table, target_lab, options);
    let (mut u, mut cost) = problem.solve(coarse_start(table, target_lab, options, 2, None), 40);
    // A poor fit may be a local minimum (or a start stuck on a bound): restart from the nearest node at every other
    // melanin blend of the table and keep the best.
    if cost > RESTART_COST {
        for j in (0..table.axes()[1]).step_by(2) {
            let (v, c) = problem.solve(coarse_start(table, target_lab, options, 2, Some(j)), 40);
            if c < cost {
                (u, cost) = (v, c);
            }
        }
    }
    (u, ciede2000(target_lab, conv.lab(table.albedo(u))), cost)
}

/// A colour's table fit when the fit of a nearby colour (the same texel under slightly other gains) is known: its
/// table coordinates `start` and cost `start_cost`. Levenberg-Marquardt from there; the full fit ([`fit_on_table`]:
/// coarse start and restarts) only where that ends above the restart cost while the nearby fit did not (a colour
/// that has just left skin's colours). A colour outside them already keeps the basin its full fit's restarts chose.
/// Returns table coordinates, the table's ΔE00 there and the cost.
pub(crate) fn refit_on_table(
    table: &AlbedoTable,
    target_rgb: [f64; 3],
    options: &AlbedoFitOptions,
    (start, start_cost): ([f64; 3], f64),
) -> ([f64; 3], f64, f64) {
    let conv = table.converter();
    let target_lab = conv.lab(target_rgb);
    let problem = table_problem(table, target_lab, options);
    let (u, cost) = problem.solve(start, 40);
    if cost > RESTART_COST && start_cost <= RESTART_COST {
        return fit_on_table_costed(table, target_rgb, options);
    }
    (u, ciede2000(target_lab, conv.lab(table.albedo(u))), cost)
}

/// Parameters that reproduce a colour within the ambiguity ΔE00: the best fit at each melanin blend of a grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ambiguity {
    pub delta_e00: f64,
    /// (min, max) of each parameter over the set (with the fit itself).
    pub melanin: [f64; 2],
    pub melanin_blend: [f64; 2],
    pub hemoglobin: [f64; 2],
    /// The set's members: (C_m, beta_m, C_h, ΔE00 by direct evaluation).
    pub members: Vec<[f64; 4]>,
}

/// The result of [`fit_albedo`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AlbedoFit {
    pub params: SkinParams,
    /// The colour fitted: the target times the options' `rgb_gains`.
    pub target_rgb: [f64; 3],
    /// The model albedo of `params` (direct evaluation).
    pub albedo_rgb: [f64; 3],
    pub delta_e00: f64,
    /// Whether `delta_e00` is within the ambiguity threshold (the colour is one the model reaches).
    pub in_gamut: bool,
    pub ambiguity: Ambiguity,
    pub table_from_cache: bool,
    /// The model fitted: its transport and adding-doubling streams (`AlbedoFitOptions`).
    pub transport: Transport,
    pub streams: usize,
}

/// Check an RGB target: finite (negative channels are allowed: out-of-gamut colours of a working space).
pub fn check_rgb(name: &str, rgb: [f64; 3]) -> Result<[f64; 3], SkinError> {
    if rgb.iter().all(|v| v.is_finite() && v.abs() <= 1e6) {
        Ok(rgb)
    } else {
        Err(SkinError::invalid(
            name,
            format!("every channel must be a finite linear RGB value (|v| <= 1e6); got {rgb:?}"),
        ))
    }
}

/// Fit one colour (see the module's text). `target_rgb` is linear RGB in `options.working_space`.
pub fn fit_albedo(target_rgb: [f64; 3], options: &AlbedoFitOptions) -> Result<AlbedoFit, SkinError> {
    fit_albedo_cancellable(target_rgb, options, &AtomicBool::new(false))
}

/// [`fit_albedo`] that stops once `cancel` is set: in its table build (the first call for its options: seconds) and
/// in every direct evaluation of the polish and the ambiguity (each reads it before every wavelength's transport).
pub fn fit_albedo_cancellable(
    target_rgb: [f64; 3],
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<AlbedoFit, SkinError> {
    let options = options.validated()?;
    let target_rgb = check_rgb("target albedo", target_rgb)?;
    let target_rgb = [0, 1, 2].map(|c| target_rgb[c] * options.rgb_gains[c]);
    let (table, from_cache) = cached_albedo_table_cancellable(&options, cancel)?;
    let prepared = options.prepared()?;
    let conv = *table.converter();
    let target_lab = conv.lab(target_rgb);
    // Cancelled: NaN ends the polish at once (the solver takes no step to it), and the flag is read again after.
    let direct = |u: [f64; 3]| prepared.albedo_cancellable(&options.params_at(u), cancel).unwrap_or([f64::NAN; 3]);
    let (u_table, _) = fit_on_table(&table, target_rgb, &options);
    let polish = Problem {
        forward: direct,
        converter: &conv,
        target_lab,
        prior: options.melanin_blend_prior,
        weight: options.prior_weight,
        free: [true; 3],
    };
    let (u, _) = polish.solve(u_table, 20);
    SkinError::check_cancel(cancel, "fit_albedo")?;
    let params = options.params_at(u);
    let albedo_rgb = prepared.albedo_cancellable(&params, cancel)?;
    let delta_e00 = ciede2000(target_lab, conv.lab(albedo_rgb));
    // The ambiguity: at each melanin blend, the best (C_m, C_h) on the table, checked by direct evaluation.
    let mut members = vec![[params.melanin, params.melanin_blend, params.hemoglobin, delta_e00]];
    for s in 0..AMBIGUITY_BLEND_STEPS {
        let b = s as f64 / (AMBIGUITY_BLEND_STEPS - 1) as f64;
        let fixed = Problem {
            forward: |v: [f64; 3]| table.albedo(v),
            converter: &conv,
            target_lab,
            prior: 0.0,
            weight: 0.0,
            free: [true, false, true],
        };
        let (v, _) = fixed.solve([u[0], b, u[2]], 30);
        let p = options.params_at(v);
        let de = ciede2000(target_lab, conv.lab(prepared.albedo_cancellable(&p, cancel)?));
        if de <= options.ambiguity_delta_e {
            members.push([p.melanin, p.melanin_blend, p.hemoglobin, de]);
        }
    }
    let range =
        |q: usize| members.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], m| [lo.min(m[q]), hi.max(m[q])]);
    let ambiguity = Ambiguity {
        delta_e00: options.ambiguity_delta_e,
        melanin: range(0),
        melanin_blend: range(1),
        hemoglobin: range(2),
        members,
    };
    Ok(AlbedoFit {
        params,
        target_rgb,
        albedo_rgb,
        delta_e00,
        in_gamut: delta_e00 <= options.ambiguity_delta_e,
        ambiguity,
        table_from_cache: from_cache,
        transport: options.transport,
        streams: options.streams,
    })
}

/// Levels per channel of the colour cache's key: colours within one step of 10-bit sRGB encoding (IEC 61966-2-1) of
/// each other share a fit (the first texel's colour is fitted), so that a float texture whose colours vary by noise
/// below that step costs what an 8-bit one does.
pub const CACHE_LEVELS: f32 = 1023.0;

/// The cache key of a colour: its 10-bit sRGB codes where every channel is in [0, 1], else its exact bits (an
/// out-of-gamut colour is fitted as it is). A texture's distinct colours are its distinct keys (8-bit textures repeat
/// colours, and each is fitted once), kept in an FNV-1a hash map (the crate's one hasher, src/maps/lut.rs's cache
/// keys): measured on 4096² keys, 0.29 s against 0.18 s for a hand-written Fx hash at 192 000 distinct colours (2.1 s
/// against 1.3 s at 7.2 million), small beside the fit of those colours.
pub(crate) fn colour_key(t: &[f32; 3]) -> [u32; 3] {
    if t.iter().all(|v| (0.0..=1.0).contains(v)) {
        t.map(|v| {
            let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
            (s * CACHE_LEVELS).round() as u32
        })
    } else {
        // +0.0 and -0.0 are one colour; the top bit marks an exact key (codes stay below 1024).
        let b = t.map(|v| (v + 0.0).to_bits());
        [b[0], b[1], b[2] | 0x8000_0000]
    }
}

/// The extended parameters' names, for messages and results.
pub const EXTENDED_NAMES: [&str; 3] = [EPIDERMIS_THICKNESS.name, "baseline_absorption_scale", BLOOD_OXYGENATION.name];
