//! The map plan: where every texel's outputs come from, decided once from a [`Summary`] of the whole texture (one
//! image, or a UDIM set's tiles), then asked for any rows of any image of that texture ([`MapPlan::fill`]). The
//! strategies, cheapest first: one evaluation for a constant map, one per distinct parameter tuple for maps with few
//! of them (8-bit sources, masks), a lookup table interpolated per texel (a stack of tables over thickness when only
//! the epidermis thickness varies among the extended physiology), else every texel evaluated directly.
//! `compute_maps` fills every row at once; `run_maps` a block of rows at a time, streamed to the EXR writers, so its
//! memory is the input's (one tile of a set) and a few blocks, whatever the size.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::io::{ParamImage, Plane, ALL_CHANNELS, ALL_RANGES};
use super::kinds::{MapKind, ALBEDO_MAP, COAT_ROUGHNESS_MAP, COAT_WEIGHT_MAP, RADIUS_MAP, SPECULAR_MAP};
use super::lut::{measure_error_cancellable, MaterialTable, TexelMaterial};
use super::report::{MapReport, MapSettings, MapWork, Strategy, StrategyChoice, Timings};
use super::summary::{Summary, Tuple};
use super::thickness_tables::{measure_stack_error, ThicknessTables};
use crate::error::SkinError;
use crate::evaluate::{Outputs, Prepared};
use crate::fit::SubsurfaceMethod;
use crate::skin::params::{ParamSpec, EPIDERMIS_THICKNESS, MATERIAL_PARAMS, OILINESS};
use crate::skin::SkinParams;
use crate::surface::principled::{specular_for, surface_inputs, SpecularParams};

/// Base Color and Subsurface Radius (mm) of one texel.
type TexelValue = ([f32; 3], [f32; 3]);

/// A texel's value of `spec` as f64. Texels passed `check_planes` in f32; widening can step just past a bound
/// (0.1f32 > 0.1), so it is rounded back into the range.
pub(crate) fn widened(value: f32, spec: &ParamSpec) -> f64 {
    (value as f64).clamp(spec.min, spec.max)
}

/// Direct evaluation of one texel's material for the run's request, method and outputs.
struct Evaluator {
    prepared: Prepared,
    method: SubsurfaceMethod,
    fit_radius: bool,
}

impl Evaluator {
    fn material(&self, t: Tuple, cancel: &AtomicBool) -> Result<TexelMaterial, SkinError> {
        let p = SkinParams::from_fn(|spec| match MATERIAL_PARAMS.iter().position(|m| m.name == spec.name) {
            Some(k) => widened(t[k], spec),
            None => 0.0, // OILINESS: the surface's, not the material's
        })?;
        if self.fit_radius {
            TexelMaterial::of(&self.prepared.material_cancellable(&p, cancel)?, self.method)
        } else {
            Ok(TexelMaterial::albedo_only(self.prepared.albedo_cancellable(&p, cancel)?))
        }
    }

    fn value(&self, t: Tuple, cancel: &AtomicBool) -> Result<TexelValue, SkinError> {
        self.material(t, cancel).map(|m| (m.base_color, m.radius_mm))
    }
}

/// Where the material outputs of a texel come from.
enum MaterialSource {
    /// Neither Base Color nor radius asked for.
    None,
    Constant(TexelValue),
    Tuples(HashMap<[u32; 6], TexelValue>),
    Table(MaterialTable),
    ThicknessTables(ThicknessTables),
    /// Every texel evaluated as it is filled.
    Exact,
}

/// The surface outputs: one value, or per texel from the oiliness (Coat maps for a surface with a coat).
#[derive(Debug, Clone, Copy)]
pub enum SurfacePlan {
    Constant(SpecularParams),
    Map { coat: bool, constants: SpecularParams },
}

/// Rows of the outputs a plan fills: each asked-for map's planes, row-major (`rows * width` values).
#[derive(Debug, Default)]
pub struct Block {
    pub base_color: Option<[Vec<f32>; 3]>,
    pub radius_mm: Option<[Vec<f32>; 3]>,
    /// The maps of [`MapPlan::surface_kinds`], in that order.
    pub surface: Vec<Vec<f32>>,
}

impl Block {
    /// The planes of each of [`MapPlan::kinds`], in that order.
    pub fn into_planes(self) -> Vec<Vec<Vec<f32>>> {
        let rgb = |p: Option<[Vec<f32>; 3]>| p.map(|p| p.into_iter().collect::<Vec<_>>());
        let mut planes: Vec<Vec<Vec<f32>>> =
            [rgb(self.base_color), rgb(self.radius_mm)].into_iter().flatten().collect();
        planes.extend(self.surface.into_iter().map(|s| vec![s]));
        planes
    }
}

/// The decided plan of one texture, ready to fill rows.
pub struct MapPlan {
    width: usize,
    texels: usize,
    wanted: Outputs,
    material: MaterialSource,
    evaluator: Evaluator,
    surface: Option<SurfacePlan>,
    /// Texels evaluated directly while filling (the exact strategy).
    filled_evaluations: AtomicUsize,
    report: MapReport,
}

impl MapPlan {
    /// Decide the strategy for the texture `summary` describes and do its up-front work (the constant's or the
    /// tuples' evaluations, the table's build or load and check). `progress(0, texels)` ticks after each evaluation
    /// and about once per percent of a table's nodes; `cancel` stops it with [`SkinError::interrupted`].
    pub fn new(
        summary: &Summary,
        settings: &MapSettings,
        progress: Option<&(dyn Fn(usize, usize) + Sync)>,
        cancel: &AtomicBool,
    ) -> Result<MapPlan, SkinError> {
        let start = Instant::now();
        let (w, n) = (summary.width, summary.texels);
        if w == 0 || n == 0 {
            return Err(SkinError::invalid(
                "parameter maps",
                format!("expected at least one texel; got {w}x{}", n / w.max(1)),
            ));
        }
        settings.table.validate()?;
        let prepared = Prepared::new(&settings.request)?;
        // The method must be one the target's Blender offers (an error naming those that are).
        settings.request.target.method_entry(settings.method)?;
        let wanted = settings.request.outputs;
        let evaluator = Evaluator { prepared, method: settings.method, fit_radius: wanted.radius };
        let mut work = MapWork { texels: n, ..MapWork::default() };
        let (material, strategy) = decide(summary, settings, &evaluator, &mut work, progress, cancel)?;
        let surface = match wanted.specular {
            false => None,
            true => Some(surface_plan(summary.uniform_of(&OILINESS), &settings.request)?),
        };
        let constant_values: std::collections::BTreeMap<&'static str, f64> = (0..ALL_CHANNELS.len())
            .filter_map(|p| {
                // Widened and rounded into range as the evaluation does (0.01f32 is just below 0.01).
                let v = summary.uniform[p]?;
                Some((ALL_CHANNELS[p], (v as f64).clamp(ALL_RANGES[p].0, ALL_RANGES[p].1)))
            })
            .collect();
        let report = MapReport {
            crate_version: env!("CARGO_PKG_VERSION"),
            model_version: crate::stamp::MODEL_VERSION,
            width: w,
            height: n / w,
            method: settings.method,
            target: settings.request.target.info(),
            color_space: settings.request.working_space.name(),
            strategy,
            clamped: Vec::new(),
            // In plane order (the paper's four, then the extended physiology), not the map's name order.
            constant_parameters: ALL_CHANNELS.into_iter().filter(|n| constant_values.contains_key(n)).collect(),
            constant_values,
            request: *evaluator.prepared.request(),
            work,
            seconds: Timings { compute: start.elapsed().as_secs_f64(), ..Timings::default() },
            input_notes: summary.notes.clone(),
            tiles: Vec::new(),
        };
        Ok(MapPlan { width: w, texels: n, wanted, material, evaluator, surface, filled_evaluations: 0.into(), report })
    }

    /// The maps this plan fills, in [`Block::into_planes`] order.
    pub fn kinds(&self) -> Vec<MapKind> {
        let mut kinds = Vec::new();
        if self.wanted.albedo {
            kinds.push(ALBEDO_MAP);
        }
        if self.wanted.radius {
            kinds.push(RADIUS_MAP);
        }
        kinds.extend(self.surface_kinds());
        kinds
    }

    /// The single-channel surface maps this plan fills (none when the oiliness is one value).
    pub fn surface_kinds(&self) -> Vec<MapKind> {
        match self.surface {
            Some(SurfacePlan::Map { coat: true, .. }) => vec![SPECULAR_MAP, COAT_WEIGHT_MAP, COAT_ROUGHNESS_MAP],
            Some(SurfacePlan::Map { coat: false, .. }) => vec![SPECULAR_MAP],
            _ => Vec::new(),
        }
    }

    pub fn surface(&self) -> Option<SurfacePlan> {
        self.surface
    }

    /// Whether filling a texel costs a direct evaluation (the exact strategy): such a texture is filled once, whole.
    pub fn evaluates_every_texel(&self) -> bool {
        matches!(self.material, MaterialSource::Exact)
    }

    /// The report of the work so far (the up-front work and every fill), with `compute` seconds.
    pub fn report(&self, compute_seconds: f64) -> MapReport {
        let mut report = self.report.clone();
        let work = &mut report.work;
        work.evaluations += self.filled_evaluations.load(Ordering::Relaxed);
        // With the radius, every evaluation and every node built is a material with its three channel fits
        // (`Prepared::material`); without it, the albedo alone (`Prepared::albedo`).
        if self.wanted.radius {
            work.radius_fits = 3 * (work.evaluations + work.table_nodes_built);
            work.outputs.radius = self.texels;
        }
        if self.wanted.albedo {
            work.outputs.albedo = self.texels;
        }
        (work.specular_evaluations, work.outputs.specular) = match self.surface {
            None => (0, 0),
            Some(SurfacePlan::Constant(_)) => (1, 0),
            Some(SurfacePlan::Map { .. }) => (self.texels, self.texels),
        };
        report.seconds.compute = compute_seconds;
        report
    }

    /// The outputs of rows `first_row..first_row + rows` of `image` (a texture the plan was made for, or one tile of
    /// it). Rows are filled in parallel; each filled row tells `progress(width, texels)`, each direct evaluation
    /// `progress(0, texels)`; rows (and evaluations) not started when `cancel` is set are skipped, and the block is
    /// then incomplete (the caller reads the flag).
    pub fn fill(
        &self,
        image: &ParamImage,
        first_row: usize,
        rows: usize,
        progress: Option<&(dyn Fn(usize, usize) + Sync)>,
        cancel: &AtomicBool,
    ) -> Result<Block, SkinError> {
        let w = self.width;
        let count = rows * w;
        let needs_material = self.wanted.albedo || self.wanted.radius;
        let planes =
            |on: bool| if on { [vec![0f32; count], vec![0f32; count], vec![0f32; count]] } else { Default::default() };
        let (mut base_color, mut radius) = (planes(needs_material), planes(self.wanted.radius));
        let tick = |texels: usize| {
            if let Some(p) = progress {
                p(texels, self.texels);
            }
        };
        let axes = |specs: &[ParamSpec]| -> Vec<Cow<'_, [f32]>> {
            specs.iter().map(|s| rows_of(image.plane_of(s), first_row, rows, w)).collect()
        };
        let fill = Rows { width: w, cancel, tick: &tick };
        match &self.material {
            MaterialSource::None => {}
            MaterialSource::Constant((c, r)) => fill.each(&mut base_color, &mut radius, |_, _| (*c, *r)),
            MaterialSource::Tuples(values) => {
                let axes = axes(&MATERIAL_PARAMS);
                fill.each(&mut base_color, &mut radius, |y, x| {
                    let t: Tuple = std::array::from_fn(|k| axes[k][y * w + x]);
                    values[&t.map(f32::to_bits)]
                })
            }
            MaterialSource::Table(table) => {
                let a = axes(&[MATERIAL_PARAMS[0], MATERIAL_PARAMS[1], MATERIAL_PARAMS[2]]);
                fill.rows(&mut base_color, &mut radius, |y, c, r| {
                    let row = |k: usize| &a[k][y * w..(y + 1) * w];
                    table.lookup_method_rows(row(0), row(1), row(2), c, r)
                })
            }
            MaterialSource::ThicknessTables(stack) => {
                let a = axes(&[MATERIAL_PARAMS[0], MATERIAL_PARAMS[1], MATERIAL_PARAMS[2], EPIDERMIS_THICKNESS]);
                fill.rows(&mut base_color, &mut radius, |y, c, r| {
                    let row = |k: usize| &a[k][y * w..(y + 1) * w];
                    stack.lookup_row([row(0), row(1), row(2), row(3)], c, r)
                })
            }
            MaterialSource::Exact => {
                let axes = axes(&MATERIAL_PARAMS);
                let failed = std::sync::Mutex::new(None);
                fill.each(&mut base_color, &mut radius, |y, x| {
                    if cancel.load(Ordering::Relaxed) {
                        return ([0.0; 3], [0.0; 3]);
                    }
                    let t: Tuple = std::array::from_fn(|k| axes[k][y * w + x]);
                    let value = self.evaluator.value(t, cancel).unwrap_or_else(|e| {
                        failed.lock().map(|mut f| *f = Some(e)).ok();
                        ([0.0; 3], [0.0; 3])
                    });
                    self.filled_evaluations.fetch_add(1, Ordering::Relaxed);
                    tick(0);
                    value
                });
                if let Some(e) = failed.into_inner().ok().flatten() {
                    return Err(e);
                }
            }
        }
        let surface = match self.surface {
            Some(SurfacePlan::Map { coat, .. }) => {
                surface_rows(&rows_of(image.plane_of(&OILINESS), first_row, rows, w), coat, &self.evaluator)?
            }
            _ => Vec::new(),
        };
        Ok(Block {
            base_color: self.wanted.albedo.then_some(base_color),
            radius_mm: self.wanted.radius.then_some(radius),
            surface,
        })
    }
}

/// Rows `first_row..first_row + rows` of a plane: a slice of its texels, or its constant repeated.
fn rows_of(plane: &Plane, first_row: usize, rows: usize, width: usize) -> Cow<'_, [f32]> {
    match plane {
        Plane::Texels(values) => Cow::Borrowed(&values[first_row * width..(first_row + rows) * width]),
        Plane::Constant(v) => Cow::Owned(vec![*v; rows * width]),
    }
}

/// The surface maps of a block's oiliness: Specular IOR Level, then Coat Weight and Coat Roughness with a coat.
fn surface_rows(oiliness: &[f32], coat: bool, evaluator: &Evaluator) -> Result<Vec<Vec<f32>>, SkinError> {
    let request = evaluator.prepared.request();
    let (model, engine) = (request.surface, request.target.engine);
    let inputs: Vec<_> =
        oiliness.par_iter().map(|&o| surface_inputs(model, o as f64, engine)).collect::<Result<_, _>>()?;
    let plane = |f: fn(&crate::surface::principled::SurfaceInputs) -> f64| {
        inputs.par_iter().map(|i| f(i) as f32).collect::<Vec<f32>>()
    };
    let mut maps = vec![plane(|i| i.specular_ior_level)];
    if coat {
        maps.push(plane(|i| i.coat_weight));
        maps.push(plane(|i| i.coat_roughness));
    }
    Ok(maps)
}

/// The surface outputs for an oiliness that is `uniform` (one value) or varies.
fn surface_plan(uniform: Option<f32>, request: &crate::evaluate::Request) -> Result<SurfacePlan, SkinError> {
    let (model, engine) = (request.surface, request.target.engine);
    Ok(match uniform {
        Some(v) => SurfacePlan::Constant(specular_for(model, v as f64, engine)?),
        None => SurfacePlan::Map { coat: !model.is_paper(), constants: specular_for(model, 0.0, engine)? },
    })
}

/// The strategy for `summary` and its up-front work, cheapest first (see the module's doc).
fn decide(
    summary: &Summary,
    settings: &MapSettings,
    evaluator: &Evaluator,
    work: &mut MapWork,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
) -> Result<(MaterialSource, Strategy), SkinError> {
    let n = summary.texels;
    let wanted = settings.request.outputs;
    let tick = progress.map(|p| move || p(0, n));
    let tick = tick.as_ref().map(|t| t as &(dyn Fn() + Sync));
    let extended: [Option<f32>; 3] = [3, 4, 5].map(|k| summary.uniform_of(&MATERIAL_PARAMS[k]));
    let extended_uniform = match extended {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        _ => None,
    };
    let widen = |v: [f32; 3]| -> [f64; 3] { std::array::from_fn(|k| widened(v[k], &MATERIAL_PARAMS[3 + k])) };
    if !(wanted.albedo || wanted.radius) {
        return Ok((MaterialSource::None, Strategy::None));
    }
    let material_uniform: Option<Tuple> = MATERIAL_PARAMS
        .iter()
        .map(|s| summary.uniform_of(s))
        .collect::<Option<Vec<f32>>>()
        .map(|v| std::array::from_fn(|k| v[k]));
    if let Some(t) = material_uniform {
        work.evaluations = 1;
        return Ok((MaterialSource::Constant(evaluator.value(t, cancel)?), Strategy::Constant));
    }
    if let Some(tuples) = &summary.tuples {
        return evaluate_tuples(tuples, settings.strategy, evaluator, work, tick, cancel);
    }
    if let (StrategyChoice::Auto, Some(rest)) = (settings.strategy, extended_uniform) {
        let build = Instant::now();
        // Without the radius the table holds the albedo alone: its nodes fit no radius. The extended physiology, one
        // value everywhere, is baked into every node (and into the cache key).
        let (table, from_cache) = MaterialTable::load_or_build_outputs(
            &evaluator.prepared,
            settings.method,
            settings.table,
            wanted.radius,
            widen(rest),
            settings.table_cache.as_deref(),
            cancel,
            tick,
        )?;
        let build_seconds = build.elapsed().as_secs_f64();
        // A freshly built table is checked against direct evaluation; a cached one was checked when it was built.
        let measured_error = if from_cache || settings.table_check_samples == 0 {
            None
        } else {
            Some(measure_error_cancellable(&table, &evaluator.prepared, settings.table_check_samples, cancel)?)
        };
        let (resolution, nodes) = (settings.table, settings.table.node_count());
        work.evaluations = measured_error.as_ref().map_or(0, |_| settings.table_check_samples);
        work.table_nodes_built = if from_cache { 0 } else { nodes };
        work.table_lookups = n;
        let strategy = Strategy::Table { resolution, nodes, from_cache, build_seconds, measured_error };
        return Ok((MaterialSource::Table(table), strategy));
    }
    // Only the thickness varies among the extended physiology: the stack of tables over thickness, the other two held.
    if let (StrategyChoice::Auto, [None, Some(y), Some(z)]) = (settings.strategy, extended) {
        let rest = [y, z];
        let rest = [widened(rest[0], &MATERIAL_PARAMS[4]), widened(rest[1], &MATERIAL_PARAMS[5])];
        let [lo, hi] = summary.thickness_mm;
        let (stack, figures) = ThicknessTables::load_or_build(
            &evaluator.prepared,
            settings.method,
            settings.table,
            wanted.radius,
            [lo as f64, hi as f64],
            rest,
            settings.table_cache.as_deref(),
            cancel,
            tick,
        )?;
        let check = &summary.check_texels;
        let [base_color_error, radius_error] = measure_stack_error(
            &stack,
            check.len(),
            wanted.radius,
            |i| [check[i][0], check[i][1], check[i][2], check[i][3]],
            |i| evaluator.material(check[i], cancel).map(|t| [t.base_color, t.radius_mm]),
            cancel,
        )?;
        let nodes = settings.table.node_count();
        work.evaluations = check.len();
        work.table_nodes_built = figures.tables_built * nodes;
        work.table_lookups = 2 * n;
        let strategy = Strategy::ThicknessTables {
            resolution: settings.table,
            tables: figures.tables,
            tables_built: figures.tables_built,
            node_range_mm: figures.node_range_mm,
            build_seconds: figures.build_seconds,
            check_samples: check.len(),
            max_base_color_relative: base_color_error,
            max_radius_relative: radius_error,
        };
        return Ok((MaterialSource::ThicknessTables(stack), strategy));
    }
    // Direct evaluation of every texel as it is filled: on request, or when an extended parameter other than the
    // thickness varies over more tuples than `MAX_DISTINCT_TUPLES`.
    Ok((MaterialSource::Exact, Strategy::Exact { evaluations: n }))
}

/// One evaluation per distinct tuple, in parallel. The flag is read before each evaluation (one is up to a few tenths
/// of a second at the reference level), and each evaluation is a progress tick `(0, texels)`, as a table node is.
fn evaluate_tuples(
    tuples: &HashSet<[u32; 6]>,
    choice: StrategyChoice,
    evaluator: &Evaluator,
    work: &mut MapWork,
    tick: Option<&(dyn Fn() + Sync)>,
    cancel: &AtomicBool,
) -> Result<(MaterialSource, Strategy), SkinError> {
    let keys: Vec<[u32; 6]> = tuples.iter().copied().collect();
    let values = keys
        .par_iter()
        .map(|k| {
            SkinError::check_cancel(cancel, "maps")?;
            let value = evaluator.value(k.map(f32::from_bits), cancel);
            if let Some(tick) = tick {
                tick();
            }
            value.map(|v| (*k, v))
        })
        .collect::<Result<HashMap<_, _>, SkinError>>()?;
    work.evaluations = keys.len();
    let strategy = match choice {
        StrategyChoice::Exact => Strategy::Exact { evaluations: keys.len() },
        StrategyChoice::Auto => Strategy::DistinctTuples { tuples: keys.len() },
    };
    Ok((MaterialSource::Tuples(values), strategy))
}

/// Filling a block's rows in parallel: rows not started when `cancel` is set are skipped; each row filled ticks.
struct Rows<'a> {
    width: usize,
    cancel: &'a AtomicBool,
    tick: &'a (dyn Fn(usize) + Sync),
}

impl Rows<'_> {
    /// Each texel from `texel(y, x)` (y within the block).
    fn each(
        &self,
        base_color: &mut [Vec<f32>; 3],
        radius: &mut [Vec<f32>; 3],
        texel: impl Fn(usize, usize) -> TexelValue + Sync,
    ) {
        let w = self.width;
        self.rows(base_color, radius, |y, [c0, c1, c2], [r0, r1, r2]| {
            let with_radius = !r0.is_empty();
            for x in 0..w {
                let (c, r) = texel(y, x);
                (c0[x], c1[x], c2[x]) = (c[0], c[1], c[2]);
                if with_radius {
                    (r0[x], r1[x], r2[x]) = (r[0], r[1], r[2]);
                }
            }
        });
    }

    /// Each row from `row(y, base_color, radius)` (the radius slices empty when the radius is not asked for).
    fn rows(
        &self,
        base_color: &mut [Vec<f32>; 3],
        radius: &mut [Vec<f32>; 3],
        row: impl Fn(usize, [&mut [f32]; 3], [&mut [f32]; 3]) + Sync,
    ) {
        let w = self.width;
        let count = base_color[0].len() / w.max(1);
        let [c0, c1, c2] = base_color;
        // Without the radius its rows are empty slices, one per row of Base Color.
        fn split(plane: &mut [f32], width: usize, count: usize) -> Vec<&mut [f32]> {
            if plane.is_empty() {
                (0..count).map(|_| &mut [][..]).collect()
            } else {
                plane.chunks_mut(width).collect()
            }
        }
        let [r0, r1, r2] = radius.each_mut().map(|p| split(p, w, count));
        c0.par_chunks_mut(w)
            .zip(c1.par_chunks_mut(w))
            .zip(c2.par_chunks_mut(w))
            .zip(r0.into_par_iter().zip(r1.into_par_iter()).zip(r2.into_par_iter()))
            .enumerate()
            .for_each(|(y, (((c0, c1), c2), ((r0, r1), r2)))| {
                if self.cancel.load(Ordering::Relaxed) {
                    return;
                }
                row(y, [c0, c1, c2], [r0, r1, r2]);
                (self.tick)(w);
            });
    }
}
