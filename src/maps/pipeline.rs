//! The map pipeline: parameter planes in, Base Color / Subsurface Radius / specular planes out, by the cheapest
//! strategy that is exact enough: one evaluation for a constant map, one per distinct parameter tuple for maps with
//! few of them (8-bit sources, masks), otherwise a lookup table interpolated per texel (or, on request, every texel
//! evaluated directly). Shared by the CLI (`spectral-skin maps`) and Python (`spectral_skin.maps`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::io::{
    check_output_dir, commit_all, create_output_dir, read_params, stage_bytes, stage_channels_exr, Compression,
    ExrOptions, ParamImage, ParamInputs, Plane, Staged, ALL_CHANNELS, ALL_RANGES, EXTENDED_CHANNELS, PARAM_CHANNELS,
};
use super::lut::{measure_error_cancellable, MaterialTable, TableError, TableResolution, TexelMaterial};
use super::thickness_tables::{measure_stack_error, ThicknessTables};
use super::udim::{find_tiles, stack_tiles, tile_file_name, tile_set_file_name, TileRows};
use crate::error::SkinError;
use crate::evaluate::{Outputs, Prepared, Request};
use crate::fit::blender_target::TargetInfo;
use crate::fit::SubsurfaceMethod;
use crate::skin::params::{
    ParamSpec, EPIDERMIS_THICKNESS, EXTENDED_PARAMS, HEMOGLOBIN, MATERIAL_PARAMS, MELANIN, MELANIN_BLEND, OILINESS,
};
use crate::skin::SkinParams;
use crate::surface::principled::{specular_for, surface_inputs, SpecularParams, SurfaceInputs};

/// At most this many distinct (C_m, beta_m, C_h) tuples (with the extended physiology, when it varies) are evaluated
/// one by one; more use the table (a stack of tables over thickness when the epidermis thickness varies, or direct
/// evaluation of every texel when another extended parameter varies).
pub const MAX_DISTINCT_TUPLES: usize = 2048;
/// How many bad texels an error message lists by coordinate.
const LISTED_BAD_TEXELS: usize = 5;
/// Points at which a freshly built table's error is measured by default (each a direct evaluation).
pub const DEFAULT_TABLE_CHECK_SAMPLES: usize = 64;
/// Most check points a caller may ask for: each is one direct evaluation (about 0.25 ms on one core of the
/// 2-core machine of docs/maps-performance.md), so 10^6 is minutes of work; more is a mistake, not a finer check.
pub const MAX_TABLE_CHECK_SAMPLES: usize = 1_000_000;

/// How texels are evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StrategyChoice {
    /// Constant, distinct tuples or table, whichever applies first.
    #[default]
    Auto,
    /// Every texel (or distinct tuple) evaluated directly; never the table.
    Exact,
}

/// Settings of one map run.
#[derive(Debug, Clone)]
pub struct MapSettings {
    pub method: SubsurfaceMethod,
    pub strategy: StrategyChoice,
    /// Clamp NaN, infinite and out-of-range texels into range (and count them) instead of failing.
    pub clamp: bool,
    pub table: TableResolution,
    /// Points at which a freshly built table is checked against direct evaluation.
    pub table_check_samples: usize,
    /// Folder where built tables are kept for later runs (None: always build). See `lut::default_cache_dir`.
    pub table_cache: Option<PathBuf>,
    /// Accuracy, model and working space; its `outputs` say which maps are computed: `albedo` (Base Color),
    /// `radius` (Subsurface Radius) and `specular` (its other outputs are ignored). Without `radius` no radius is fitted
    /// anywhere and Base Color is the albedo, whatever the method (the Base Color of a material without subsurface);
    /// without `specular` no specular input is computed. The default asks for all three.
    pub request: Request,
}

impl Default for MapSettings {
    fn default() -> Self {
        MapSettings {
            method: crate::fit::DEFAULT_METHOD,
            strategy: StrategyChoice::Auto,
            clamp: false,
            table: TableResolution::default(),
            table_check_samples: DEFAULT_TABLE_CHECK_SAMPLES,
            table_cache: None,
            request: Request::new(Outputs::material()),
        }
    }
}

/// The strategy used, with its figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "name")]
pub enum Strategy {
    Constant,
    DistinctTuples {
        tuples: usize,
    },
    Table {
        resolution: TableResolution,
        nodes: usize,
        from_cache: bool,
        build_seconds: f64,
        measured_error: Option<TableError>,
    },
    /// The epidermis thickness varies (the rest of the extended physiology is one value): a table per thickness node
    /// in use, each texel blended between the two around its thickness ([`ThicknessTables`]); its error against direct
    /// evaluation measured at `check_samples` of the map's texels.
    ThicknessTables {
        resolution: TableResolution,
        tables: usize,
        tables_built: usize,
        node_range_mm: [f64; 2],
        build_seconds: f64,
        check_samples: usize,
        max_base_color_relative: f64,
        max_radius_relative: f64,
    },
    Exact {
        evaluations: usize,
    },
    /// Neither Base Color nor radius was asked for: no material was evaluated.
    None,
}

/// Texels that were out of range, NaN or infinite, per parameter (counted whether or not they were clamped).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BadTexels {
    pub parameter: String,
    pub nan: usize,
    pub infinite: usize,
    pub out_of_range: usize,
    /// The first few bad texels as (x, y), y = 0 at the top row.
    pub first: Vec<(usize, usize)>,
}

/// Specular output: maps when oiliness varies, else the constants.
#[derive(Debug, Clone)]
pub enum SpecularOutput {
    Constant(SpecularParams),
    /// The surface inputs that depend on the oiliness, per texel (`surface::principled::surface_inputs`):
    /// Specular IOR Level always, Coat Weight and Coat Roughness for a surface with a coat (`measured`). The others
    /// (Roughness, IOR, Coat IOR; Coat Weight 0 for `paper`) are one value: the fields of `constants` that are not
    /// maps.
    Map {
        specular_ior_level: Vec<f32>,
        coat: Option<CoatPlanes>,
        constants: SpecularParams,
    },
}

/// Principled Coat Weight and Coat Roughness per texel.
#[derive(Debug, Clone)]
pub struct CoatPlanes {
    pub weight: Vec<f32>,
    pub roughness: Vec<f32>,
}

impl SpecularOutput {
    /// The single-channel surface maps held, in [`MAP_KINDS`] order, with their kinds (none for constants).
    pub fn maps(&self) -> Vec<(MapKind, &[f32])> {
        match self {
            SpecularOutput::Constant(_) => Vec::new(),
            SpecularOutput::Map { specular_ior_level, coat, .. } => {
                let mut maps = vec![(SPECULAR_MAP, specular_ior_level.as_slice())];
                if let Some(coat) = coat {
                    maps.push((COAT_WEIGHT_MAP, coat.weight.as_slice()));
                    maps.push((COAT_ROUGHNESS_MAP, coat.roughness.as_slice()));
                }
                maps
            }
        }
    }
}

/// Everything a map run computed, before it is written; an output not asked for (`MapSettings::request`) is None.
#[derive(Debug, Clone)]
pub struct MapResult {
    pub width: usize,
    pub height: usize,
    /// Principled Base Color for the chosen method and target, linear RGB planes (without the radius: the albedo).
    pub base_color: Option<[Vec<f32>; 3]>,
    /// Principled Subsurface Radius x Scale for the chosen method and target, mm, RGB planes.
    pub radius_mm: Option<[Vec<f32>; 3]>,
    pub specular: Option<SpecularOutput>,
    pub report: MapReport,
}

/// What was done and how long it took (the sidecar's content, with the inputs and outputs added by `run_maps`).
#[derive(Debug, Clone, Serialize)]
pub struct MapReport {
    pub crate_version: &'static str,
    pub width: usize,
    pub height: usize,
    pub method: SubsurfaceMethod,
    /// The Blender version and engine the maps are for.
    pub target: TargetInfo,
    pub color_space: &'static str,
    pub strategy: Strategy,
    pub clamped: Vec<BadTexels>,
    /// The parameters that are one value everywhere (the paper's four and the extended physiology), by name.
    pub constant_parameters: Vec<&'static str>,
    /// The value of each of `constant_parameters` (as used, after any clamping): the extended physiology the maps
    /// were computed with when it is constant (its defaults unless a map or value gave others).
    pub constant_values: std::collections::BTreeMap<&'static str, f64>,
    pub request: Request,
    /// What was computed, counted (so a front can show that an effect it dropped was not computed).
    pub work: MapWork,
    pub seconds: Timings,
    /// What the reader accepted but a user should know ([`ParamImage::notes`]: an ignored alpha, channels of no
    /// parameter's name), one sentence each; fronts show them as warnings. Absent from the sidecar when empty.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub input_notes: Vec<String>,
    /// The UDIM tiles the maps were computed for, as one texture (each output a tile set of them); empty for a
    /// texture that is not a tile set (and absent from the sidecar then).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tiles: Vec<u32>,
}

/// The work of a map run. Every direct evaluation and every table node built is one material: the albedo, and when
/// the radius is asked for the Burley fit of the Subsurface Radius (three channel fits); a table lookup interpolates
/// nodes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct MapWork {
    /// Texels of each output map.
    pub texels: usize,
    /// Parameter sets evaluated directly: 1 for a constant map, one per distinct tuple, one per texel (exact), or
    /// the check points of a freshly built table.
    pub evaluations: usize,
    /// Lookup-table nodes computed (0 when the table came from the cache, or no table was used).
    pub table_nodes_built: usize,
    /// Texels interpolated from the table.
    pub table_lookups: usize,
    /// Burley fits of the Subsurface Radius (one per RGB channel of each evaluation and each node built; 0 without
    /// the radius output).
    pub radius_fits: usize,
    /// Specular inputs computed from an oiliness: 1 when it is one value, one per texel when it varies (0 without the
    /// specular output).
    pub specular_evaluations: usize,
    /// Texels produced per output.
    pub outputs: OutputTexels,
}

/// Texels produced per output map (0: the output is not a map, or was not asked for).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct OutputTexels {
    pub albedo: usize,
    pub radius: usize,
    pub specular: usize,
}

#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    pub read: f64,
    pub compute: f64,
    pub write: f64,
    pub total: f64,
}

/// Check every plane for NaN, infinities and values outside the parameter's range. Without `clamp` any bad texel is an
/// error naming the counts and the first coordinates; with `clamp` the planes are clamped (NaN and -inf to the
/// minimum, +inf to the maximum) and the counts returned.
pub fn check_planes(image: &mut ParamImage, clamp: bool) -> Result<Vec<BadTexels>, SkinError> {
    let width = image.width;
    let mut report = Vec::new();
    for (p, plane) in image.planes.iter_mut().chain(image.extended.iter_mut()).enumerate() {
        let (lo, hi) = (ALL_RANGES[p].0 as f32, ALL_RANGES[p].1 as f32);
        let mut bad = BadTexels { parameter: ALL_CHANNELS[p].to_string(), ..BadTexels::default() };
        let note = |i: usize, v: f32, bad: &mut BadTexels| {
            if v.is_nan() {
                bad.nan += 1;
            } else if v.is_infinite() {
                bad.infinite += 1;
            } else {
                bad.out_of_range += 1;
            }
            if bad.first.len() < LISTED_BAD_TEXELS {
                bad.first.push((i % width, i / width));
            }
        };
        let fix = |v: f32| if v.is_nan() { lo } else { v.clamp(lo, hi) };
        match plane {
            Plane::Constant(v) => {
                if !(*v >= lo && *v <= hi) {
                    note(0, *v, &mut bad);
                    *v = fix(*v);
                }
            }
            Plane::Texels(values) => {
                // In parallel, a chunk at a time; each chunk's counts and first bad texels, merged in order.
                const CHUNK: usize = 1 << 16;
                let chunks: Vec<BadTexels> = values
                    .par_chunks_mut(CHUNK)
                    .enumerate()
                    .map(|(c, chunk)| {
                        let mut bad = BadTexels::default();
                        for (i, v) in chunk.iter_mut().enumerate() {
                            if !(*v >= lo && *v <= hi) {
                                note(c * CHUNK + i, *v, &mut bad);
                                *v = fix(*v);
                            }
                        }
                        bad
                    })
                    .collect();
                for chunk in chunks {
                    bad.nan += chunk.nan;
                    bad.infinite += chunk.infinite;
                    bad.out_of_range += chunk.out_of_range;
                    let room = LISTED_BAD_TEXELS - bad.first.len();
                    bad.first.extend(chunk.first.into_iter().take(room));
                }
            }
        }
        if bad.nan + bad.infinite + bad.out_of_range > 0 {
            if !clamp {
                return Err(SkinError::BadTexels {
                    parameter: bad.parameter,
                    min: lo,
                    max: hi,
                    nan: bad.nan,
                    infinite: bad.infinite,
                    out_of_range: bad.out_of_range,
                    first: bad.first,
                });
            }
            report.push(bad);
        }
    }
    Ok(report)
}

/// Compute the maps of a checked image (see [`check_planes`]). `progress(done, total)` is told, row by row, how many
/// more texels are done out of how many.
pub fn compute_maps(
    image: &ParamImage,
    settings: &MapSettings,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
) -> Result<MapResult, SkinError> {
    compute_maps_cancellable(image, settings, progress, &AtomicBool::new(false))
}

/// [`compute_maps`] that stops once `cancel` is set, with [`SkinError::interrupted`]: the rows and evaluations not
/// started are skipped (the flag is read before each), an evaluation under way stops before its next wavelength's
/// transport, and a lookup table being built (and its check) stops within a node's evaluation. The progress
/// callback is told `(0, texels)` after each evaluation and about once per percent of a table's nodes, so a front's
/// callback can set the flag at any stage. A cancelled call never returns a (partial) result.
pub fn compute_maps_cancellable(
    image: &ParamImage,
    settings: &MapSettings,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
) -> Result<MapResult, SkinError> {
    let result = compute_maps_until_cancelled(image, settings, progress, cancel)?;
    SkinError::check_cancel(cancel, "maps")?;
    Ok(result)
}

/// The work of [`compute_maps_cancellable`], whose result is incomplete when `cancel` was set during it.
fn compute_maps_until_cancelled(
    image: &ParamImage,
    settings: &MapSettings,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
) -> Result<MapResult, SkinError> {
    let start = Instant::now();
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 {
        return Err(SkinError::invalid("parameter maps", format!("expected at least one texel; got {w}x{h}")));
    }
    settings.table.validate()?;
    let prepared = Prepared::new(&settings.request)?;
    let method = settings.method;
    // The method must be one the target's Blender offers (an error naming those that are).
    settings.request.target.method_entry(method)?;
    let n = image.texel_count();
    let wanted = settings.request.outputs;
    let fit_radius = wanted.radius;
    // Texel tuples: the values of MATERIAL_PARAMS (oiliness does not enter the material), in that order.
    let material_planes: [&Plane; 6] = MATERIAL_PARAMS.map(|spec| image.plane_of(&spec));
    let evaluate_one = |t: [f32; 6]| -> Result<TexelMaterial, SkinError> {
        let p = SkinParams::from_fn(|spec| match MATERIAL_PARAMS.iter().position(|m| m.name == spec.name) {
            Some(k) => widened(t[k], spec),
            None => 0.0, // OILINESS: the surface's, not the material's
        })?;
        if fit_radius {
            TexelMaterial::of(&prepared.material_cancellable(&p, cancel)?, method)
        } else {
            Ok(TexelMaterial::albedo_only(prepared.albedo_cancellable(&p, cancel)?))
        }
    };
    let tuple = |i: usize| material_planes.map(|plane| plane.value(i));
    // The extended physiology's values where a plane is one value everywhere (each plane scanned once).
    let extended_values: [Option<f32>; 3] = EXTENDED_PARAMS.map(|spec| uniform_value(image.plane_of(&spec)));
    // The extended physiology when it is one value everywhere (the table bakes it in), widened as `evaluate_one` does.
    let extended_uniform: Option<[f64; 3]> = match extended_values {
        [Some(x), Some(y), Some(z)] => Some(std::array::from_fn(|k| widened([x, y, z][k], &EXTENDED_PARAMS[k]))),
        _ => None,
    };

    // The radius plane is filled only when asked for; Base Color whenever a material is evaluated (the radius needs
    // the albedo) and kept only when asked for.
    let needs_material = wanted.albedo || wanted.radius;
    let planes = |wanted: bool| if wanted { [vec![0f32; n], vec![0f32; n], vec![0f32; n]] } else { Default::default() };
    let mut base_color = planes(needs_material);
    let mut radius = planes(fit_radius);
    let select = |t: &TexelMaterial| (t.base_color, t.radius_mm);

    let all_constant = extended_uniform.is_some()
        && [MELANIN, MELANIN_BLEND, HEMOGLOBIN].iter().all(|spec| uniform_value(image.plane_of(spec)).is_some());
    let mut work = MapWork { texels: n, ..MapWork::default() };
    // Row y of plane k of the tables' axes (the three concentrations, then the thickness) for the table lookups:
    // constant planes become one shared row.
    let row_planes: [&Plane; 4] = TABLE_AXES.map(|spec| image.plane_of(&spec));
    let rows_of = |plane: &Plane| match plane {
        Plane::Texels(_) => None,
        Plane::Constant(v) => Some(vec![*v; w]),
    };
    let constant_rows = row_planes.map(rows_of);
    let row = |k: usize, y: usize| -> &[f32] {
        match (row_planes[k], &constant_rows[k]) {
            (Plane::Texels(values), _) => &values[y * w..(y + 1) * w],
            (Plane::Constant(_), Some(row)) => row,
            (Plane::Constant(_), None) => unreachable!("constant planes have a row"),
        }
    };
    // Only the thickness varies among the extended physiology: the stack of tables over thickness, the other two
    // (EXTENDED_PARAMS after the thickness) held.
    let thickness = image.plane_of(&EPIDERMIS_THICKNESS);
    let thickness_only: Option<[f64; 2]> = match extended_values {
        [None, Some(y), Some(z)] => {
            Some([(y, &EXTENDED_PARAMS[1]), (z, &EXTENDED_PARAMS[2])].map(|(v, s)| widened(v, s)))
        }
        _ => None,
    };
    let strategy = if !needs_material {
        Strategy::None
    } else if all_constant {
        work.evaluations = 1;
        let (c, r) = select(&evaluate_one(tuple(0))?);
        for k in 0..3 {
            base_color[k].fill(c[k]);
            if fit_radius {
                radius[k].fill(r[k]);
            }
        }
        Strategy::Constant
    } else if let Some(tuples) = distinct_tuples(image, MAX_DISTINCT_TUPLES) {
        let keys: Vec<[u32; 6]> = tuples.keys().cloned().collect();
        // The flag is read before each evaluation (one is up to a few tenths of a second at the reference level), and
        // each evaluation is a progress tick `(0, texels)`, as a table node is: an evaluation not started when the
        // flag is set is skipped (its placeholder is never written: `fill_rows` skips every row then).
        let evaluated = AtomicUsize::new(0);
        let values = keys
            .par_iter()
            .map(|k| {
                if cancel.load(Ordering::Relaxed) {
                    return Ok(([0.0; 3], [0.0; 3]));
                }
                let value = evaluate_one(k.map(f32::from_bits)).map(|t| select(&t));
                evaluated.fetch_add(1, Ordering::Relaxed);
                if let Some(p) = progress {
                    p(0, n);
                }
                value
            })
            .collect::<Result<Vec<_>, SkinError>>()?;
        work.evaluations = evaluated.into_inner();
        let index: HashMap<[u32; 6], usize> = keys.iter().enumerate().map(|(i, k)| (*k, i)).collect();
        fill_rows(w, &mut base_color, &mut radius, progress, cancel, |i| values[index[&tuple(i).map(f32::to_bits)]]);
        if settings.strategy == StrategyChoice::Exact {
            Strategy::Exact { evaluations: keys.len() }
        } else {
            Strategy::DistinctTuples { tuples: keys.len() }
        }
    } else if let (StrategyChoice::Auto, Some(extended)) = (settings.strategy, extended_uniform) {
        let build = Instant::now();
        let tick = progress.map(|p| move || p(0, n));
        // Without the radius the table holds the albedo alone: its nodes fit no radius. The extended physiology, one
        // value everywhere, is baked into every node (and into the cache key).
        let (table, from_cache) = MaterialTable::load_or_build_outputs(
            &prepared,
            method,
            settings.table,
            fit_radius,
            extended,
            settings.table_cache.as_deref(),
            cancel,
            tick.as_ref().map(|t| t as &(dyn Fn() + Sync)),
        )?;
        let build_seconds = build.elapsed().as_secs_f64();
        // A freshly built table is checked against direct evaluation; a cached one was checked when it was built.
        let measured_error = if from_cache || settings.table_check_samples == 0 {
            None
        } else {
            Some(measure_error_cancellable(&table, &prepared, settings.table_check_samples, cancel)?)
        };
        fill_rows_with(w, &mut base_color, &mut radius, progress, cancel, |y, c, r| {
            table.lookup_method_rows(row(0, y), row(1, y), row(2, y), c, r)
        });
        let (resolution, nodes) = (settings.table, settings.table.node_count());
        work.evaluations = measured_error.as_ref().map_or(0, |_| settings.table_check_samples);
        work.table_nodes_built = if from_cache { 0 } else { nodes };
        work.table_lookups = n;
        Strategy::Table { resolution, nodes, from_cache, build_seconds, measured_error }
    } else if let (StrategyChoice::Auto, Some(rest), Plane::Texels(thickness)) =
        (settings.strategy, thickness_only, thickness)
    {
        let (lo, hi) = thickness
            .par_iter()
            .fold(|| (f32::INFINITY, f32::NEG_INFINITY), |(a, b), &t| (a.min(t), b.max(t)))
            .reduce(|| (f32::INFINITY, f32::NEG_INFINITY), |x, y| (x.0.min(y.0), x.1.max(y.1)));
        let tick = progress.map(|p| move || p(0, n));
        let (stack, figures) = ThicknessTables::load_or_build(
            &prepared,
            method,
            settings.table,
            fit_radius,
            [lo as f64, hi as f64],
            rest,
            settings.table_cache.as_deref(),
            cancel,
            tick.as_ref().map(|t| t as &(dyn Fn() + Sync)),
        )?;
        fill_rows_with(w, &mut base_color, &mut radius, progress, cancel, |y, c, r| {
            stack.lookup_row([row(0, y), row(1, y), row(2, y), row(3, y)], c, r)
        });
        let samples = settings.table_check_samples;
        let [base_color_error, radius_error] = measure_stack_error(
            &stack,
            n,
            samples,
            fit_radius,
            |i| row_planes.map(|plane| plane.value(i)),
            |i| evaluate_one(tuple(i)).map(|t| [t.base_color, t.radius_mm]),
            cancel,
        )?;
        let nodes = settings.table.node_count();
        work.evaluations = samples.min(n);
        work.table_nodes_built = figures.tables_built * nodes;
        work.table_lookups = 2 * n;
        Strategy::ThicknessTables {
            resolution: settings.table,
            tables: figures.tables,
            tables_built: figures.tables_built,
            node_range_mm: figures.node_range_mm,
            build_seconds: figures.build_seconds,
            check_samples: samples.min(n),
            max_base_color_relative: base_color_error,
            max_radius_relative: radius_error,
        }
    } else {
        // Direct evaluation of every texel, row by row in parallel: on request, or when an extended parameter other
        // than the thickness varies over more tuples than `MAX_DISTINCT_TUPLES`.
        // The flag is read before each texel's evaluation (a row of a wide map is minutes at the reference level),
        // each evaluation is a progress tick `(0, texels)` and each finished row a progress of its texels.
        type Row = Result<Vec<([f32; 3], [f32; 3])>, SkinError>;
        let evaluated = AtomicUsize::new(0);
        let rows: Vec<Row> = (0..h)
            .into_par_iter()
            .map(|y| {
                let mut row = Vec::with_capacity(w);
                for x in 0..w {
                    if cancel.load(Ordering::Relaxed) {
                        return Ok(Vec::new());
                    }
                    row.push(evaluate_one(tuple(y * w + x)).map(|t| select(&t))?);
                    evaluated.fetch_add(1, Ordering::Relaxed);
                    if let Some(p) = progress {
                        p(0, n);
                    }
                }
                if let Some(p) = progress {
                    p(w, n);
                }
                Ok(row)
            })
            .collect();
        for (y, row) in rows.into_iter().enumerate() {
            for (x, (c, r)) in row?.into_iter().enumerate() {
                for k in 0..3 {
                    base_color[k][y * w + x] = c[k];
                    if fit_radius {
                        radius[k][y * w + x] = r[k];
                    }
                }
            }
        }
        work.evaluations = evaluated.into_inner();
        Strategy::Exact { evaluations: n }
    };

    // With the radius, every evaluation and every node built is a material with its three channel fits
    // (`Prepared::material`); without it, the albedo alone (`Prepared::albedo`).
    if fit_radius {
        work.radius_fits = 3 * (work.evaluations + work.table_nodes_built);
        work.outputs.radius = n;
    }
    if wanted.albedo {
        work.outputs.albedo = n;
    }
    let oiliness = image.plane_of(&OILINESS);
    let specular = match wanted.specular {
        true => Some(specular_output(oiliness, &settings.request)?),
        false => None,
    };
    (work.specular_evaluations, work.outputs.specular) = match &specular {
        None => (0, 0),
        Some(SpecularOutput::Constant(_)) => (1, 0),
        Some(SpecularOutput::Map { specular_ior_level, .. }) => (specular_ior_level.len(), specular_ior_level.len()),
    };

    let constant_values: std::collections::BTreeMap<&'static str, f64> = (0..ALL_CHANNELS.len())
        .filter_map(|p| {
            // Widened and rounded into range as the evaluation does (0.01f32 is just below 0.01).
            uniform_value(image.plane(p)).map(|v| (ALL_CHANNELS[p], (v as f64).clamp(ALL_RANGES[p].0, ALL_RANGES[p].1)))
        })
        .collect();
    let constant_parameters =
        (0..ALL_CHANNELS.len()).map(|p| ALL_CHANNELS[p]).filter(|n| constant_values.contains_key(n)).collect();
    let report = MapReport {
        crate_version: env!("CARGO_PKG_VERSION"),
        width: w,
        height: h,
        method,
        target: settings.request.target.info(),
        color_space: settings.request.working_space.name(),
        strategy,
        clamped: Vec::new(),
        constant_parameters,
        constant_values,
        request: *prepared.request(),
        work,
        seconds: Timings { compute: start.elapsed().as_secs_f64(), ..Timings::default() },
        input_notes: image.notes.clone(),
        tiles: Vec::new(),
    };
    Ok(MapResult {
        width: w,
        height: h,
        base_color: wanted.albedo.then_some(base_color),
        radius_mm: fit_radius.then_some(radius),
        specular,
        report,
    })
}

/// The plane's value if every texel holds the same one (a constant, or a map that is constant in fact).
fn uniform_value(plane: &Plane) -> Option<f32> {
    match plane {
        Plane::Constant(v) => Some(*v),
        Plane::Texels(values) => {
            let first = values.first()?.to_bits();
            values.par_iter().all(|v| v.to_bits() == first).then(|| f32::from_bits(first))
        }
    }
}

/// The distinct (C_m, beta_m, C_h, extended physiology) tuples (as f32 bit patterns) if there are at most `limit`,
/// else None.
fn distinct_tuples(image: &ParamImage, limit: usize) -> Option<HashMap<[u32; 6], ()>> {
    let planes = MATERIAL_PARAMS.map(|spec| image.plane_of(&spec));
    let mut set = HashMap::new();
    for i in 0..image.texel_count() {
        let t = planes.map(|plane| plane.value(i));
        set.insert(t.map(f32::to_bits), ());
        if set.len() > limit {
            return None;
        }
    }
    Some(set)
}

/// The axes of the lookup tables, in the order their lookups take rows: the three concentrations, then the thickness
/// (a stack of tables over it when it varies).
const TABLE_AXES: [ParamSpec; 4] = [MELANIN, MELANIN_BLEND, HEMOGLOBIN, EPIDERMIS_THICKNESS];

/// A texel's value of `spec` as f64. Texels passed `check_planes` in f32; widening can step just past a bound
/// (0.1f32 > 0.1), so it is rounded back into the range.
fn widened(value: f32, spec: &ParamSpec) -> f64 {
    (value as f64).clamp(spec.min, spec.max)
}

/// Fill the output planes row by row in parallel from a per-texel function; rows not started when `cancel` is set
/// are skipped. Empty radius planes (the radius not asked for) stay empty.
fn fill_rows(
    width: usize,
    base_color: &mut [Vec<f32>; 3],
    radius: &mut [Vec<f32>; 3],
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
    texel: impl Fn(usize) -> ([f32; 3], [f32; 3]) + Sync,
) {
    fill_rows_with(width, base_color, radius, progress, cancel, |y, [c0, c1, c2], [r0, r1, r2]| {
        let with_radius = !r0.is_empty();
        for x in 0..width {
            let (c, r) = texel(y * width + x);
            (c0[x], c1[x], c2[x]) = (c[0], c[1], c[2]);
            if with_radius {
                (r0[x], r1[x], r2[x]) = (r[0], r[1], r[2]);
            }
        }
    });
}

/// Fill the output planes row by row in parallel: `row(y, base_color, radius)` writes row `y` of each plane (the
/// radius slices are empty when the radius is not asked for). Rows not started when `cancel` is set are skipped.
fn fill_rows_with(
    width: usize,
    base_color: &mut [Vec<f32>; 3],
    radius: &mut [Vec<f32>; 3],
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
    row: impl Fn(usize, [&mut [f32]; 3], [&mut [f32]; 3]) + Sync,
) {
    let total = base_color[0].len();
    let [c0, c1, c2] = base_color;
    let [r0, r1, r2] = radius;
    // Without the radius its rows are empty slices, one per row of Base Color.
    fn rows(plane: &mut [f32], width: usize, count: usize) -> Vec<&mut [f32]> {
        if plane.is_empty() {
            (0..count).map(|_| &mut [][..]).collect()
        } else {
            plane.chunks_mut(width).collect()
        }
    }
    let count = total / width;
    let (r0, r1, r2) = (rows(r0, width, count), rows(r1, width, count), rows(r2, width, count));
    c0.par_chunks_mut(width)
        .zip(c1.par_chunks_mut(width))
        .zip(c2.par_chunks_mut(width))
        .zip(r0.into_par_iter().zip(r1.into_par_iter()).zip(r2.into_par_iter()))
        .enumerate()
        .for_each(|(y, (((c0, c1), c2), ((r0, r1), r2)))| {
            if cancel.load(Ordering::Relaxed) {
                return;
            }
            row(y, [c0, c1, c2], [r0, r1, r2]);
            if let Some(p) = progress {
                p(width, total);
            }
        });
}

/// The R, G, B channels of three planes, for the EXR writer.
fn rgb(p: &[Vec<f32>; 3]) -> Vec<(&'static str, &[f32])> {
    vec![("R", p[0].as_slice()), ("G", p[1].as_slice()), ("B", p[2].as_slice())]
}

/// One kind of texture map: its one name on every front (the `outputs` request, the key of the Python result and of
/// `write_maps`' images and written files, the add-on's texture, the file stem), its file, channels and unit, and
/// the Principled BSDF input it feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapKind {
    pub name: &'static str,
    pub file: &'static str,
    pub channels: &'static [&'static str],
    /// The values' unit ("" for a dimensionless one).
    pub unit: &'static str,
    pub principled_input: &'static str,
}

/// The surface inputs of an oiliness plane for the request's surface model and engine: the constants of one value,
/// or maps (per texel: cheap and exact, `surface_inputs`); the plane's values were checked to lie in [0, 1].
fn specular_output(oiliness: &Plane, request: &Request) -> Result<SpecularOutput, SkinError> {
    let (model, engine) = (request.surface, request.target.engine);
    let values = match (uniform_value(oiliness), oiliness) {
        (Some(v), _) => return Ok(SpecularOutput::Constant(specular_for(model, v as f64, engine)?)),
        (None, Plane::Constant(_)) => unreachable!("a constant plane is uniform"),
        (None, Plane::Texels(values)) => values,
    };
    let inputs: Vec<SurfaceInputs> =
        values.par_iter().map(|&o| surface_inputs(model, o as f64, engine)).collect::<Result<_, _>>()?;
    let plane = |f: fn(&SurfaceInputs) -> f64| inputs.par_iter().map(|i| f(i) as f32).collect::<Vec<f32>>();
    let coat = (!model.is_paper())
        .then(|| CoatPlanes { weight: plane(|i| i.coat_weight), roughness: plane(|i| i.coat_roughness) });
    Ok(SpecularOutput::Map {
        specular_ior_level: plane(|i| i.specular_ior_level),
        coat,
        constants: specular_for(model, 0.0, engine)?,
    })
}

/// Principled Base Color for the method (the albedo itself without the radius output), linear RGB.
pub const ALBEDO_MAP: MapKind = MapKind {
    name: "albedo",
    file: "albedo.exr",
    channels: &["R", "G", "B"],
    unit: "",
    principled_input: "Base Color",
};
/// Principled Subsurface Radius x Subsurface Scale for the method, mm.
pub const RADIUS_MAP: MapKind = MapKind {
    name: "radius",
    file: "radius.exr",
    channels: &["R", "G", "B"],
    unit: "mm",
    principled_input: "Subsurface Radius",
};
/// Principled Specular IOR Level per texel (written only when the oiliness varies).
pub const SPECULAR_MAP: MapKind = MapKind {
    name: "specular",
    file: "specular.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Specular IOR Level",
};
/// Principled Coat Weight per texel (the `measured` surface's sharp lobe; written only when the oiliness varies).
pub const COAT_WEIGHT_MAP: MapKind = MapKind {
    name: "coat_weight",
    file: "coat_weight.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Coat Weight",
};
/// Principled Coat Roughness per texel (as [`COAT_WEIGHT_MAP`]).
pub const COAT_ROUGHNESS_MAP: MapKind = MapKind {
    name: "coat_roughness",
    file: "coat_roughness.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Coat Roughness",
};
/// Every map kind, in the order results list them.
pub const MAP_KINDS: [MapKind; 5] = [ALBEDO_MAP, RADIUS_MAP, SPECULAR_MAP, COAT_WEIGHT_MAP, COAT_ROUGHNESS_MAP];
/// The single-channel surface maps: the specular output's, when the oiliness varies.
pub const SURFACE_MAP_KINDS: [MapKind; 3] = [SPECULAR_MAP, COAT_WEIGHT_MAP, COAT_ROUGHNESS_MAP];

/// Output file names.
pub const ALBEDO_FILE: &str = ALBEDO_MAP.file;
pub const RADIUS_FILE: &str = RADIUS_MAP.file;
pub const SPECULAR_FILE: &str = SPECULAR_MAP.file;
pub const SIDECAR_FILE: &str = "skin_maps.json";

/// Read the inputs, check them, compute and write `albedo.exr`, `radius.exr`, `specular.exr` (if oiliness varies)
/// and `skin_maps.json` into `out_dir`. Nothing is written unless everything succeeded: outputs are staged as
/// temporary files and renamed into place together at the end.
///
/// Inputs naming a UDIM tile set (`params.<UDIM>.exr`, see [`super::udim`]) are computed as one texture of every
/// tile the first such file has on disk; each output is then a tile set with the same tiles (`albedo.1001.exr`,
/// ...), and the sidecar lists the tiles.
pub fn run_maps(
    inputs: &ParamInputs,
    out_dir: &Path,
    settings: &MapSettings,
    exr: ExrOptions,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
) -> Result<MapReport, SkinError> {
    run_maps_cancellable(inputs, out_dir, settings, exr, progress, &AtomicBool::new(false))
}

/// The parameters of `inputs`, checked (and clamped with `clamp`): one image, or a tile set's tiles stacked with the
/// rows of each (a tile's bad texels are reported with the tile named and positions inside the tile).
fn read_checked(
    inputs: &ParamInputs,
    clamp: bool,
) -> Result<(ParamImage, Vec<BadTexels>, Option<TileRows>), SkinError> {
    let Some(pattern) = inputs.tile_set() else {
        let mut image = read_params(inputs)?;
        let clamped = check_planes(&mut image, clamp)?;
        return Ok((image, clamped, None));
    };
    let tiles = find_tiles(pattern)?;
    let mut images = Vec::with_capacity(tiles.len());
    let mut clamped: Vec<BadTexels> = Vec::new();
    for &tile in &tiles {
        let named = |parameter: String| format!("{parameter} (tile {tile})");
        let mut image = read_params(&inputs.for_tile(tile))?;
        let bad = check_planes(&mut image, clamp).map_err(|e| match e {
            SkinError::BadTexels { parameter, min, max, nan, infinite, out_of_range, first } => {
                SkinError::BadTexels { parameter: named(parameter), min, max, nan, infinite, out_of_range, first }
            }
            other => other,
        })?;
        clamped.extend(bad.into_iter().map(|b| BadTexels { parameter: named(b.parameter), ..b }));
        images.push(image);
    }
    let (image, rows) = stack_tiles(&tiles, images)?;
    Ok((image, clamped, Some(rows)))
}

/// [`run_maps`] that stops once `cancel` is set (the CLI's Ctrl-C): the computation stops (see
/// [`compute_maps_cancellable`]), and a run cancelled before its files are renamed into place writes nothing (the
/// staged temporaries are deleted), so the output folder keeps the previous run's files.
pub fn run_maps_cancellable(
    inputs: &ParamInputs,
    out_dir: &Path,
    settings: &MapSettings,
    exr: ExrOptions,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
) -> Result<MapReport, SkinError> {
    let cancelled = || SkinError::invalid("maps", "interrupted before the outputs were written; nothing was changed");
    let start = Instant::now();
    // The output folder first (not created yet: a failed run leaves none): one that cannot be written fails now, not
    // after the computation.
    check_output_dir(out_dir)?;
    let (image, clamped, tile_rows) = read_checked(inputs, settings.clamp)?;
    let read = start.elapsed().as_secs_f64();
    // A flag set during the computation is its error; one set after it is read before the files are renamed.
    let mut result = compute_maps_cancellable(&image, settings, progress, cancel)?;
    drop(image);
    let write_start = Instant::now();
    let surface_maps = result.specular.as_ref().map(SpecularOutput::maps).unwrap_or_default();
    let mut staged = Vec::new();
    let tiles: Vec<Option<u32>> = match &tile_rows {
        None => {
            let files = MapFiles {
                width: result.width,
                height: result.height,
                base_color: result.base_color.as_ref(),
                radius_mm: result.radius_mm.as_ref(),
                surface: surface_maps.clone(),
            };
            staged.extend(stage_map_files(out_dir, None, None, &files, exr)?);
            vec![None]
        }
        Some(rows) => {
            let w = result.width;
            let rgb = |planes: Option<&[Vec<f32>; 3]>, from: usize, to: usize| {
                planes.map(|p| p.each_ref().map(|c| c[from * w..to * w].to_vec()))
            };
            for &(tile, first, height) in rows {
                let (base_color, radius_mm) = (
                    rgb(result.base_color.as_ref(), first, first + height),
                    rgb(result.radius_mm.as_ref(), first, first + height),
                );
                let files = MapFiles {
                    width: w,
                    height,
                    base_color: base_color.as_ref(),
                    radius_mm: radius_mm.as_ref(),
                    surface: surface_maps.iter().map(|&(k, s)| (k, &s[first * w..(first + height) * w])).collect(),
                };
                staged.extend(stage_map_files(out_dir, None, Some(tile), &files, exr)?);
            }
            rows.iter().map(|r| Some(r.0)).collect()
        }
    };
    result.report.clamped = clamped;
    result.report.tiles = tiles.iter().flatten().copied().collect();
    let mut report = result.report.clone();
    report.seconds.read = read;
    report.seconds.write = write_start.elapsed().as_secs_f64();
    report.seconds.total = start.elapsed().as_secs_f64();
    let compressions: Vec<(String, Compression)> = staged
        .iter()
        .filter_map(|s| Some((s.target().file_name()?.to_string_lossy().into_owned(), s.compression()?)))
        .collect();
    let sidecar = sidecar_json(&report, inputs, &result, exr, &compressions);
    staged.push(stage_bytes(&out_dir.join(SIDECAR_FILE), sidecar.as_bytes())?);
    if cancel.load(Ordering::Relaxed) {
        // Dropping the staged files deletes them.
        drop(staged);
        return Err(cancelled());
    }
    // The run is the folder's whole content: a tile-set run removes a plain run's files, and a plain run every
    // tile's (`udim::TILE_RANGE`), as well as the files of its own tiles it did not write.
    let mut removed = tiles.clone();
    if tiles.iter().any(Option::is_some) {
        removed.push(None);
    } else {
        removed.extend(crate::maps::udim::TILE_RANGE.map(Some));
    }
    commit_map_files(out_dir, None, &removed, staged)?;
    Ok(report)
}

/// The maps one write puts in files: each present one becomes its EXR (`albedo.exr` RGB, `radius.exr` RGB, and
/// each single-channel surface map its kind's file, `specular.exr` Y etc.), row-major planes of `width * height`
/// values.
pub struct MapFiles<'a> {
    pub width: usize,
    pub height: usize,
    pub base_color: Option<&'a [Vec<f32>; 3]>,
    pub radius_mm: Option<&'a [Vec<f32>; 3]>,
    /// Single-channel maps of [`SURFACE_MAP_KINDS`], with their kinds.
    pub surface: Vec<(MapKind, &'a [f32])>,
}

/// A file-name prefix for [`output_name`]: a non-empty file name part, no path separator, not "." or "..".
pub fn check_prefix(prefix: Option<&str>) -> Result<(), SkinError> {
    match prefix {
        Some(p) if p.is_empty() || p.contains(['/', '\\']) || p == "." || p == ".." => {
            Err(SkinError::invalid("prefix", format!("must be a non-empty file name part without / or \\; got {p:?}")))
        }
        _ => Ok(()),
    }
}

/// The name of output `file` (one of the `*_FILE` names) with `prefix`: `<prefix>_albedo.exr`; without, `albedo.exr`.
pub fn output_name(prefix: Option<&str>, file: &str) -> String {
    match prefix {
        Some(prefix) => format!("{prefix}_{file}"),
        None => file.to_string(),
    }
}

/// [`output_name`] of one UDIM tile: `<prefix>_albedo.1001.exr` ([`super::udim::tile_file_name`]); `tile` None is
/// the file of a texture that is not a tile set.
pub fn tile_output_name(prefix: Option<&str>, tile: Option<u32>, file: &str) -> String {
    let name = output_name(prefix, file);
    match tile {
        Some(tile) => tile_file_name(&name, tile),
        None => name,
    }
}

/// Create `out_dir` and stage the EXRs of `files` there as temporary files (see [`commit_map_files`]); dropping the
/// result deletes them. The one writer of map files: the CLI's `maps` and Python's `write_maps`.
pub fn stage_map_files(
    out_dir: &Path,
    prefix: Option<&str>,
    tile: Option<u32>,
    files: &MapFiles,
    exr: ExrOptions,
) -> Result<Vec<Staged>, SkinError> {
    create_output_dir(out_dir)?;
    let (w, h) = (files.width, files.height);
    let path = |file: &str| out_dir.join(tile_output_name(prefix, tile, file));
    // The three files are encoded at once: each write gathers its blocks on one thread while its compression runs
    // in parallel, so overlapping the files keeps both cores busy (figures: docs/maps-performance.md).
    type Channels<'a> = Vec<(&'static str, &'a [f32])>;
    let mut jobs: Vec<(PathBuf, Channels)> = Vec::new();
    if let Some(base_color) = files.base_color {
        jobs.push((path(ALBEDO_FILE), rgb(base_color)));
    }
    if let Some(radius_mm) = files.radius_mm {
        jobs.push((path(RADIUS_FILE), rgb(radius_mm)));
    }
    for &(kind, texels) in &files.surface {
        jobs.push((path(kind.file), vec![(kind.channels[0], texels)]));
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> =
            jobs.iter().map(|(path, c)| scope.spawn(move || stage_channels_exr(path, w, h, c, exr))).collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| Err(SkinError::invalid("output", "an EXR writer panicked"))))
            .collect::<Result<Vec<_>, SkinError>>()
    })
}

/// Rename the `staged` outputs into place together, then remove the outputs with `prefix` (of each of `tiles`; None:
/// the untiled files) that an earlier run wrote and this one did not (`specular.exr` when the oiliness is now
/// constant, a texture a front dropped, a sidecar), so the folder holds exactly this run's files. The removal runs
/// after the new files are in place: if it fails, the new files (and a sidecar listing them) are right, and the error
/// says which file is stale.
pub fn commit_map_files(
    out_dir: &Path,
    prefix: Option<&str>,
    tiles: &[Option<u32>],
    staged: Vec<Staged>,
) -> Result<(), SkinError> {
    let written: Vec<PathBuf> = staged.iter().map(|s| s.target().to_path_buf()).collect();
    commit_all(staged)?;
    let maps = tiles.iter().flat_map(|&t| MAP_KINDS.map(|k| tile_output_name(prefix, t, k.file)));
    for name in maps.chain(std::iter::once(output_name(prefix, SIDECAR_FILE))) {
        let stale = out_dir.join(name);
        if written.contains(&stale) {
            continue;
        }
        match std::fs::remove_file(&stale) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => {
                return Err(SkinError::io_caused(
                    &stale,
                    format!("cannot remove the previous run's output (not written by this run): {e}"),
                    e,
                ))
            }
        }
    }
    Ok(())
}

/// The sidecar's record of the inputs.
fn inputs_json(inputs: &ParamInputs) -> serde_json::Value {
    match inputs {
        ParamInputs::Multi { path, constants } => serde_json::json!({
            "file": path.display().to_string(),
            "channels": PARAM_CHANNELS,
            "constants": PARAM_CHANNELS.iter().zip(constants).filter_map(|(n, c)| c.map(|v| (n.to_string(), v))).collect::<HashMap<_, _>>(),
        }),
        ParamInputs::Separate(sources) => serde_json::json!(PARAM_CHANNELS
            .iter()
            .zip(sources)
            .map(|(n, s)| (
                n.to_string(),
                match s {
                    super::io::ParamSource::File(p) => serde_json::json!({"file": p.display().to_string()}),
                    super::io::ParamSource::Constant(v) => serde_json::json!({"constant": v}),
                }
            ))
            .collect::<HashMap<_, _>>()),
        ParamInputs::Extended { inputs, extended } => {
            // The four as above, and each extended parameter's source: a file, a constant, or "channel or default"
            // (the channel of that name in a multi-channel file if it has one, else the default; the report's
            // constant_values say which value was used when it is one everywhere).
            let mut json = inputs_json(inputs);
            json["extended"] = serde_json::json!(EXTENDED_CHANNELS
                .iter()
                .zip(extended)
                .map(|(n, s)| (
                    n.to_string(),
                    match s {
                        Some(super::io::ParamSource::File(p)) => serde_json::json!({"file": p.display().to_string()}),
                        Some(super::io::ParamSource::Constant(v)) => serde_json::json!({"constant": v}),
                        None => serde_json::json!("channel or default"),
                    }
                ))
                .collect::<HashMap<_, _>>());
            json
        }
    }
}

/// The sidecar: what each file holds (channels, meaning, units, colour space), the inputs, and the report.
/// `compressions` holds each EXR's file name and the compression it was written with (what `auto` chose).
fn sidecar_json(
    report: &MapReport,
    inputs: &ParamInputs,
    result: &MapResult,
    exr: ExrOptions,
    compressions: &[(String, Compression)],
) -> String {
    let inputs_json = inputs_json(inputs);
    // A tile set's outputs are named as Blender loads them: albedo.<UDIM>.exr.
    let key = |file: &str| if report.tiles.is_empty() { file.to_string() } else { tile_set_file_name(file) };
    let (albedo_key, radius_key) = (key(ALBEDO_FILE), key(RADIUS_FILE));
    let mut outputs = serde_json::json!({});
    if result.base_color.is_some() {
        outputs[albedo_key.as_str()] = serde_json::json!({"channels": ["R", "G", "B"], "meaning": "Principled BSDF Base Color",
            "units": "reflectance", "color_space": report.color_space});
    }
    if result.radius_mm.is_some() {
        outputs[radius_key.as_str()] = serde_json::json!({"channels": ["R", "G", "B"],
            "meaning": "Principled BSDF Subsurface Radius x Subsurface Scale", "units": "mm", "color_space": "Non-Color"});
    }
    match &result.specular {
        None => {}
        Some(specular @ SpecularOutput::Map { constants, .. }) => {
            for (kind, _) in specular.maps() {
                outputs[key(kind.file).as_str()] = serde_json::json!({"channels": kind.channels,
                    "meaning": format!("Principled {}", kind.principled_input), "units": "dimensionless",
                    "color_space": "Non-Color", "surface": constants.surface, "roughness": constants.roughness,
                    "ior": constants.ior, "coat_ior": constants.coat_ior});
            }
        }
        Some(SpecularOutput::Constant(s)) => outputs["specular_constants"] = serde_json::json!(s),
    }
    for (file, compression) in compressions {
        // A tile's file (albedo.1001.exr) under its set's key; every tile of a set is encoded alike.
        let name = MAP_KINDS
            .map(|k| k.file)
            .into_iter()
            .find(|f| report.tiles.iter().any(|&t| tile_file_name(f, t) == *file))
            .map_or(file.clone(), key);
        if outputs[name.as_str()].is_object() {
            outputs[name.as_str()]["compression"] = serde_json::json!(compression);
        }
    }
    let value = serde_json::json!({
        "inputs": inputs_json,
        "outputs": outputs,
        "encoding": exr,
        "report": report,
    });
    serde_json::to_string_pretty(&value).unwrap_or_default()
}
