//! The settings of a map run and what it gives back: the strategy chosen, the work counted, the maps computed and
//! the report the sidecar records. Below the plan, the output and the pipeline, which all read them.

use std::path::PathBuf;

use serde::Serialize;

use super::kinds::{MapKind, COAT_ROUGHNESS_MAP, COAT_WEIGHT_MAP, SPECULAR_MAP};
use super::lut::{TableError, TableResolution};
use crate::evaluate::{Outputs, Request};
use crate::fit::blender_target::TargetInfo;
use crate::fit::SubsurfaceMethod;
use crate::surface::principled::SpecularParams;

/// At most this many distinct (C_m, beta_m, C_h) tuples (with the extended physiology, when it varies) are evaluated
/// one by one; more use the table (a stack of tables over thickness when the epidermis thickness varies, or direct
/// evaluation of every texel when another extended parameter varies).
pub const MAX_DISTINCT_TUPLES: usize = 2048;
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
    /// The model's version (`crate::stamp::MODEL_VERSION`): which numbers the maps hold.
    pub model_version: u32,
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
