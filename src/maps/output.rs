//! The outputs of a map run: the map kinds (each name once, for every front), file naming (prefix, UDIM tile), the
//! staging of the map files and their commit together, and the sidecar that records the run.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::io::{
    commit_all, create_output_dir, stage_files, Compression, ExrOptions, ParamInputs, PlaneFile, Staged,
    EXTENDED_CHANNELS, PARAM_CHANNELS,
};
use super::kinds::{MapKind, ALBEDO_FILE, MAP_KINDS, RADIUS_FILE, RADIUS_MAP, SIDECAR_FILE, SURFACE_MAP_KINDS};
use super::plan::SurfacePlan;
use super::report::MapReport;
use super::udim::{tile_file_name, tile_set_file_name};
use crate::error::SkinError;

/// The R, G, B channels of three planes, for the EXR writer.
fn rgb(p: &[Vec<f32>; 3]) -> Vec<(&'static str, &[f32])> {
    vec![("R", p[0].as_slice()), ("G", p[1].as_slice()), ("B", p[2].as_slice())]
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
    // The files are encoded at once (a writer thread each: both cores stay busy; docs/maps-performance.md).
    let mut jobs: Vec<PlaneFile> = Vec::new();
    if let Some(base_color) = files.base_color {
        jobs.push((path(ALBEDO_FILE), rgb(base_color)));
    }
    if let Some(radius_mm) = files.radius_mm {
        jobs.push((path(RADIUS_FILE), rgb(radius_mm)));
    }
    for &(kind, texels) in &files.surface {
        jobs.push((path(kind.file), vec![(kind.channels[0], texels)]));
    }
    stage_files(w, h, &jobs, exr)
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
pub(crate) fn inputs_json(inputs: &ParamInputs) -> serde_json::Value {
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
pub(crate) fn sidecar_json(
    report: &MapReport,
    inputs: &ParamInputs,
    surface: Option<SurfacePlan>,
    exr: ExrOptions,
    compressions: &[(String, Compression)],
) -> String {
    let inputs_json = inputs_json(inputs);
    // A tile set's outputs are named as Blender loads them: albedo.<UDIM>.exr.
    let key = |file: &str| if report.tiles.is_empty() { file.to_string() } else { tile_set_file_name(file) };
    let (albedo_key, radius_key) = (key(ALBEDO_FILE), key(RADIUS_FILE));
    let mut outputs = serde_json::json!({});
    if report.request.outputs.albedo {
        outputs[albedo_key.as_str()] = serde_json::json!({"channels": ["R", "G", "B"], "meaning": "Principled BSDF Base Color",
            "units": "reflectance", "color_space": report.color_space});
    }
    if report.request.outputs.radius {
        outputs[radius_key.as_str()] = serde_json::json!({"channels": ["R", "G", "B"],
            "meaning": "Principled BSDF Subsurface Radius x Subsurface Scale", "units": "mm", "color_space": RADIUS_MAP.color_space});
    }
    match surface {
        None => {}
        Some(SurfacePlan::Map { coat, constants }) => {
            for kind in if coat { &SURFACE_MAP_KINDS[..] } else { &SURFACE_MAP_KINDS[..1] } {
                outputs[key(kind.file).as_str()] = serde_json::json!({"channels": kind.channels,
                    "meaning": format!("Principled {}", kind.principled_input), "units": "dimensionless",
                    "color_space": kind.color_space, "surface": constants.surface, "roughness": constants.roughness,
                    "ior": constants.ior, "coat_ior": constants.coat_ior});
            }
        }
        Some(SurfacePlan::Constant(s)) => outputs["specular_constants"] = serde_json::json!(s),
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
