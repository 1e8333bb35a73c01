//! The map pipeline: parameter planes in, Base Color / Subsurface Radius / surface planes out, by the cheapest
//! strategy that is exact enough (decided and filled by [`super::plan`]); its settings, results and report, the
//! input check, and the CLI's run from files to files (streamed a block of rows at a time). Shared by the CLI
//! (`spectral-skin maps`) and Python (`spectral_skin.maps`).

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::io::{
    auto_sample_rows, check_output_dir, choose_compression, create_output_dir, read_params, stage_bytes, stage_files,
    Compression, ExrOptions, ExrStream, ParamImage, ParamInputs, Plane, PlaneFile, Staged, ALL_CHANNELS, ALL_RANGES,
    STREAM_ROWS,
};
use super::output::sidecar_json;
use super::plan::{MapPlan, SurfacePlan};
use super::summary::Summary;
use super::udim::{check_tile_widths, find_tiles};
use crate::error::SkinError;

pub use super::kinds::{
    MapKind, ALBEDO_FILE, ALBEDO_MAP, COAT_ROUGHNESS_MAP, COAT_WEIGHT_MAP, MAP_KINDS, RADIUS_FILE, RADIUS_MAP,
    SIDECAR_FILE, SPECULAR_FILE, SPECULAR_MAP, SURFACE_MAP_KINDS,
};
pub use super::output::{check_prefix, commit_map_files, output_name, stage_map_files, tile_output_name, MapFiles};
pub use super::report::{
    BadTexels, CoatPlanes, MapReport, MapResult, MapSettings, MapWork, OutputTexels, SpecularOutput, Strategy,
    StrategyChoice, Timings, DEFAULT_TABLE_CHECK_SAMPLES, MAX_DISTINCT_TUPLES, MAX_TABLE_CHECK_SAMPLES,
};

/// How many bad texels an error message lists by coordinate.
const LISTED_BAD_TEXELS: usize = 5;

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
    let start = Instant::now();
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 {
        return Err(SkinError::invalid("parameter maps", format!("expected at least one texel; got {w}x{h}")));
    }
    let plan = MapPlan::new(&Summary::of(image, settings.table_check_samples), settings, progress, cancel)?;
    let block = plan.fill(image, 0, h, progress, cancel)?;
    SkinError::check_cancel(cancel, "maps")?;
    let specular = plan.surface().map(|surface| match surface {
        SurfacePlan::Constant(c) => SpecularOutput::Constant(c),
        SurfacePlan::Map { coat, constants } => {
            let mut maps = block.surface.iter().cloned();
            let mut next = || maps.next().unwrap_or_default();
            let specular_ior_level = next();
            let coat = coat.then(|| CoatPlanes { weight: next(), roughness: next() });
            SpecularOutput::Map { specular_ior_level, coat, constants }
        }
    });
    Ok(MapResult {
        width: w,
        height: h,
        base_color: block.base_color,
        radius_mm: block.radius_mm,
        specular,
        report: plan.report(start.elapsed().as_secs_f64()),
    })
}

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

/// One tile's parameters (the whole texture's when `tile` is None), read and checked (clamped with `clamp`); a tile's
/// bad texels are reported with the tile named and positions inside the tile.
fn read_checked(
    inputs: &ParamInputs,
    tile: Option<u32>,
    clamp: bool,
) -> Result<(ParamImage, Vec<BadTexels>), SkinError> {
    let Some(tile) = tile else {
        let mut image = read_params(inputs)?;
        let clamped = check_planes(&mut image, clamp)?;
        return Ok((image, clamped));
    };
    let named = |parameter: String| format!("{parameter} (tile {tile})");
    let mut image = read_params(&inputs.for_tile(tile))?;
    let bad = check_planes(&mut image, clamp).map_err(|e| match e {
        SkinError::BadTexels { parameter, min, max, nan, infinite, out_of_range, first } => {
            SkinError::BadTexels { parameter: named(parameter), min, max, nan, infinite, out_of_range, first }
        }
        other => other,
    })?;
    Ok((image, bad.into_iter().map(|b| BadTexels { parameter: named(b.parameter), ..b }).collect()))
}

/// The texture `inputs` name, surveyed: its images, their summary, the bad texels found, and the image itself when it
/// is one.
struct Texture {
    /// None: the one image; else a UDIM set's tiles.
    tiles: Vec<Option<u32>>,
    summary: Summary,
    image: Option<ParamImage>,
    clamped: Vec<BadTexels>,
}

/// Survey the texture `inputs` name. A tile set is read once here, a tile at a time, for its summary (the set is
/// decided as one texture) and once more when each tile is written, so that one tile's planes are held at a time.
fn survey(inputs: &ParamInputs, settings: &MapSettings) -> Result<Texture, SkinError> {
    let samples = settings.table_check_samples;
    let Some(pattern) = inputs.tile_set() else {
        let (image, clamped) = read_checked(inputs, None, settings.clamp)?;
        let summary = Summary::of(&image, samples);
        return Ok(Texture { tiles: vec![None], summary, image: Some(image), clamped });
    };
    let tiles = find_tiles(pattern)?;
    let (mut summaries, mut clamped, mut sizes) = (Vec::new(), Vec::new(), Vec::new());
    for &tile in &tiles {
        let (image, bad) = read_checked(inputs, Some(tile), settings.clamp)?;
        summaries.push(Summary::of(&image, samples));
        clamped.extend(bad);
        sizes.push((image.width, image.height));
    }
    check_tile_widths(&tiles, &sizes)?;
    let summary = Summary::merge(summaries, samples);
    Ok(Texture { tiles: tiles.into_iter().map(Some).collect(), summary, image: None, clamped })
}

/// Time spent computing and writing, each summed over the run's parts.
#[derive(Default)]
struct Clock {
    compute: f64,
    write: f64,
}

/// Stage the maps of one image of the texture `plan` was made for (`tile`: its UDIM tile): the rows filled a block
/// at a time ([`STREAM_ROWS`]) and streamed to a writer per file, so only a few blocks of outputs are held. A plan
/// that evaluates every texel is filled once, whole, and written from memory (so that no texel is evaluated twice for
/// [`Compression::Auto`]'s sample; such maps are small: docs/maps-performance.md).
#[allow(clippy::too_many_arguments)] // one texture's writing: the run's parts, passed through
fn stage_image(
    plan: &MapPlan,
    image: &ParamImage,
    out_dir: &Path,
    tile: Option<u32>,
    exr: ExrOptions,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
    clock: &mut Clock,
) -> Result<Vec<Staged>, SkinError> {
    create_output_dir(out_dir)?;
    let (w, h) = (image.width, image.height);
    let kinds = plan.kinds();
    let path = |kind: &MapKind| out_dir.join(tile_output_name(None, tile, kind.file));
    let mut fill = |first_row: usize, rows: usize, progress| -> Result<Vec<Vec<Vec<f32>>>, SkinError> {
        let start = Instant::now();
        let block = plan.fill(image, first_row, rows, progress, cancel)?;
        SkinError::check_cancel(cancel, "maps")?;
        clock.compute += start.elapsed().as_secs_f64();
        Ok(block.into_planes())
    };
    if plan.evaluates_every_texel() {
        let planes = fill(0, h, progress)?;
        let start = Instant::now();
        let files: Vec<PlaneFile> = kinds
            .iter()
            .zip(&planes)
            .map(|(kind, p)| (path(kind), kind.channels.iter().zip(p).map(|(c, p)| (*c, p.as_slice())).collect()))
            .collect();
        let staged = stage_files(w, h, &files, exr);
        clock.write += start.elapsed().as_secs_f64();
        return staged;
    }
    // Compression::Auto decides from a sample of blocks: their rows filled first (a few dozen rows).
    let sample_rows = match exr.compression {
        Compression::Auto => auto_sample_rows(h, exr.precision),
        _ => Vec::new(),
    };
    let mut sample: Vec<Vec<Vec<f32>>> = Vec::new();
    for &(y, n) in &sample_rows {
        for (k, planes) in fill(y, n, None)?.into_iter().enumerate() {
            match sample.get_mut(k) {
                Some(held) => held.iter_mut().zip(planes).for_each(|(a, b)| a.extend(b)),
                None => sample.push(planes),
            }
        }
    }
    let start = Instant::now();
    let mut streams = Vec::with_capacity(kinds.len());
    for (k, kind) in kinds.iter().enumerate() {
        let compression = match sample.get(k) {
            Some(planes) => {
                let named: Vec<(&str, &[f32])> =
                    kind.channels.iter().zip(planes).map(|(c, p)| (*c, p.as_slice())).collect();
                choose_compression(w, &named, exr)
                    .map_err(|e| SkinError::io(&path(kind), format!("cannot write output EXR: {e}")))?
            }
            None => exr.compression,
        };
        streams.push(ExrStream::start(&path(kind), w, h, kind.channels, ExrOptions { compression, ..exr })?);
    }
    clock.write += start.elapsed().as_secs_f64();
    for first_row in (0..h).step_by(STREAM_ROWS) {
        let planes = fill(first_row, STREAM_ROWS.min(h - first_row), progress)?;
        let start = Instant::now();
        for (stream, planes) in streams.iter_mut().zip(planes) {
            stream.send(first_row, planes)?;
        }
        clock.write += start.elapsed().as_secs_f64();
    }
    let start = Instant::now();
    let staged = streams.into_iter().map(ExrStream::finish).collect();
    clock.write += start.elapsed().as_secs_f64();
    staged
}

/// [`run_maps`] that stops once `cancel` is set (the CLI's Ctrl-C): the computation stops (see
/// [`compute_maps_cancellable`]), and a run cancelled before its files are renamed into place writes nothing (the
/// staged temporaries are deleted), so the output folder keeps the previous run's files. Memory: the input planes of
/// one image (one tile of a set) and a few blocks of rows of the outputs.
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
    let Texture { tiles, summary, mut image, clamped } = survey(inputs, settings)?;
    let mut read = start.elapsed().as_secs_f64();
    let plan_start = Instant::now();
    let plan = MapPlan::new(&summary, settings, progress, cancel)?;
    let mut clock = Clock { compute: plan_start.elapsed().as_secs_f64(), ..Clock::default() };
    let mut staged = Vec::new();
    for &tile in &tiles {
        let image = match (image.take(), tile) {
            (Some(image), _) => image,
            (None, tile) => {
                let again = Instant::now();
                let (image, _) = read_checked(inputs, tile, settings.clamp)?;
                read += again.elapsed().as_secs_f64();
                image
            }
        };
        staged.extend(stage_image(&plan, &image, out_dir, tile, exr, progress, cancel, &mut clock)?);
    }
    let mut report = plan.report(clock.compute);
    report.clamped = clamped;
    report.tiles = tiles.iter().flatten().copied().collect();
    report.seconds.read = read;
    report.seconds.write = clock.write;
    report.seconds.total = start.elapsed().as_secs_f64();
    let compressions: Vec<(String, Compression)> = staged
        .iter()
        .filter_map(|s| Some((s.target().file_name()?.to_string_lossy().into_owned(), s.compression()?)))
        .collect();
    let sidecar = sidecar_json(&report, inputs, plan.surface(), exr, &compressions);
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
