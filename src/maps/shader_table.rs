//! The material table laid out as images for Blender's shader: Base Color and Subsurface Radius evaluated in the node
//! tree from live (C_m, beta_m, C_h) values, with no baking.
//!
//! A [`MaterialTable`]'s nodes (natural logarithms of Base Color and radius over cube-root-warped concentration axes)
//! become two RGB float images, `shader_base_color.exr` and `shader_radius.exr`, of the same layout:
//!
//! - one slice per melanin-blend node j, side by side along x; slice j occupies columns `j * (n_m + 2)` to
//!   `j * (n_m + 2) + n_m + 1`: a guard column, the n_m melanin nodes, a guard column (each guard a copy of its
//!   neighbouring node, so a bilinear sample that strays past the slice's outer texel centre by rounding reads the
//!   same value, never the next slice);
//! - haemoglobin node k on texel row k counted from the bottom, as Blender's Image Texture node indexes rows (v = 0 is
//!   the bottom; in the file and in the arrays returned, row 0 is the top, so node k is row `n_h - 1 - k` there).
//!
//! Texel centres sit exactly on the table's nodes, so the Image Texture node's Linear interpolation (bilinear between
//! texel centres, Extend extension) inside one slice reproduces the table's bilinear step in (u_m, u_h), and mixing
//! the samples of the two slices around beta_m reproduces its third, linear step. The node group computes:
//!
//! ```text
//! u_m = clamp(C_m / 0.5, 0, 1)^(1/3)        u_h = clamp(C_h / 0.1, 0, 1)^(1/3)
//! b = clamp(beta_m, 0, 1) * (n_b - 1)       j = min(floor(b), n_b - 2)         t = b - j
//! x(j) = (j * (n_m + 2) + 1 + u_m * (n_m - 1) + 0.5) / width
//! y = (u_h * (n_h - 1) + 0.5) / n_h
//! output = exp(mix(image(x(j), y), image(x(j + 1), y), t))
//! ```
//!
//! [`ShaderTable::sample`] does exactly that on the images (with the bilinear filter of Cycles' CPU image lookup), and
//! [`measure_shader_error`] measures it against direct evaluation. The surface's inputs need no table: they are linear
//! in the oiliness between `surface::principled::surface_input_nodes`, a few Math nodes.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::io::{commit_all, create_output_dir, stage_bytes, stage_rgb_exr, ExrOptions, Staged};
use super::lut::{check_point_params, check_points, with_extended, MaterialTable, TableResolution, TexelMaterial};
use super::pipeline::{check_prefix, output_name};
use crate::error::SkinError;
use crate::evaluate::Prepared;
use crate::fit::SubsurfaceMethod;
use crate::skin::params::{EXTENDED_DEFAULTS, EXTENDED_PARAMS, HEMOGLOBIN, MELANIN, MELANIN_BLEND};

/// The `format` of a shader table's metadata (changes when the layout does).
/// How the table's images are written: 32-bit float (PIZ). The images hold logarithms; half floats would round ln
/// values of a few units by up to 2^-11 of them (0.1 % and more in the outputs, a quarter of the table's own error),
/// where float adds 1e-7.
pub const SHADER_TABLE_EXR: ExrOptions = ExrOptions::FLOAT_PIZ;

pub const SHADER_TABLE_FORMAT: &str = "spectral-skin shader table v1";
/// File of ln Base Color (RGB), beside [`SHADER_RADIUS_FILE`] and [`SHADER_SIDECAR_FILE`].
pub const SHADER_BASE_COLOR_FILE: &str = "shader_base_color.exr";
/// File of ln Subsurface Radius in mm (RGB).
pub const SHADER_RADIUS_FILE: &str = "shader_radius.exr";
/// The metadata as JSON.
pub const SHADER_SIDECAR_FILE: &str = "shader_table.json";
/// Guard columns on each side of a slice.
pub const SHADER_TABLE_GUTTER: usize = 1;

/// Nodes per axis of a shader table unless asked otherwise: chosen on the error/size/time front of
/// docs/shader-table.md. The map table's default: its worst error over the domain is below 0.7 % in Base Color and
/// radius for Burley and Random Walk, in 98 KiB of float32 texels; more melanin-blend slices buy nothing, finer
/// concentration axes halve the error for three times the build; and the map pipeline's cached table is reused.
pub const DEFAULT_SHADER_TABLE_RESOLUTION: TableResolution =
    TableResolution { melanin: 33, melanin_blend: 9, hemoglobin: 17 };

/// One parameter axis of a shader table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShaderAxis {
    /// Nodes along the axis.
    pub nodes: usize,
    /// The parameter's range; values outside are clamped into it.
    pub min: f64,
    pub max: f64,
    /// "cube_root": nodes at u = (value / max)^(1/3) = i / (nodes - 1); "linear": value = min + (max - min) i /
    /// (nodes - 1).
    pub warp: String,
}

/// What a shader table's images hold and how to sample them (the sidecar `shader_table.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShaderTableMeta {
    pub format: String,
    pub crate_version: String,
    /// The model's version (`crate::stamp::MODEL_VERSION`): the numbers the images hold. 0 in a sidecar written before it
    /// was recorded.
    #[serde(default)]
    pub model_version: u32,
    /// Subsurface method the Base Color and radius are for.
    pub method: String,
    /// Blender version (MAJOR.MINOR) and engine they are for.
    pub blender: String,
    pub engine: String,
    /// Linear RGB space of Base Color.
    pub color_space: String,
    /// Image size in texels, both images.
    pub width: usize,
    pub height: usize,
    /// Columns per melanin-blend slice: the melanin nodes and a guard column on each side.
    pub slice_width: usize,
    pub gutter: usize,
    /// Along x within a slice.
    pub melanin: ShaderAxis,
    /// One slice per node, side by side along x.
    pub melanin_blend: ShaderAxis,
    /// Along y, node 0 at the bottom row (Blender's v = 0).
    pub hemoglobin: ShaderAxis,
    /// "ln": each texel holds the natural logarithm of the output (Base Color, reflectance; radius, mm).
    pub stored: String,
    /// The request the table was evaluated with (accuracy, model, working space, target).
    pub request: serde_json::Value,
    /// The extended physiology baked into every node, by name (epidermis_thickness_mm, baseline_absorption_scale,
    /// blood_oxygenation): the table holds the material for these values only, so a front rebuilds it when they
    /// change. Metadata written before they existed reads as the defaults (the paper's values).
    #[serde(default = "default_extended_meta")]
    pub extended: std::collections::BTreeMap<String, f64>,
}

/// The extended physiology by name, from values in `EXTENDED_PARAMS` order.
pub fn extended_meta(values: [f64; 3]) -> std::collections::BTreeMap<String, f64> {
    EXTENDED_PARAMS.iter().zip(values).map(|(s, v)| (s.name.to_string(), v)).collect()
}

fn default_extended_meta() -> std::collections::BTreeMap<String, f64> {
    extended_meta(EXTENDED_DEFAULTS)
}

impl ShaderTableMeta {
    /// The baked extended physiology in `EXTENDED_PARAMS` order (a missing name: its default).
    pub fn extended_values(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.extended.get(EXTENDED_PARAMS[k].name).copied().unwrap_or(EXTENDED_DEFAULTS[k]))
    }
}

/// A [`MaterialTable`]'s Base Color and radius as two images for Blender (see the module documentation).
#[derive(Debug, Clone)]
pub struct ShaderTable {
    meta: ShaderTableMeta,
    method: SubsurfaceMethod,
    /// ln Base Color, R, G, B planes of width * height, row 0 at the top.
    base_color_log: [Vec<f32>; 3],
    /// ln radius (mm), as `base_color_log`.
    radius_log: [Vec<f32>; 3],
}

/// Worst relative error of a shader table's lookups against direct evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct ShaderTableError {
    pub samples: usize,
    pub max_base_color_relative: f64,
    pub max_radius_relative: f64,
}

impl ShaderTable {
    /// Build the table (`MaterialTable::build`, in parallel) and lay it out.
    pub fn build(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
    ) -> Result<ShaderTable, SkinError> {
        let table = MaterialTable::build(prepared, method, resolution)?;
        ShaderTable::from_table(&table, prepared)
    }

    /// [`ShaderTable::build`] through the map pipeline's table cache (`MaterialTable::load_or_build_outputs`:
    /// read from `cache_dir` when the same table is there, else built and stored), with the extended physiology
    /// `extended` (`EXTENDED_PARAMS` order) baked into every node, stopping once `cancel` is set.
    pub fn load_or_build_cancellable(
        prepared: &Prepared,
        method: SubsurfaceMethod,
        resolution: TableResolution,
        extended: [f64; 3],
        cache_dir: Option<&Path>,
        cancel: &AtomicBool,
    ) -> Result<ShaderTable, SkinError> {
        let (table, _) = MaterialTable::load_or_build_outputs(
            prepared, method, resolution, true, extended, cache_dir, cancel, None,
        )?;
        ShaderTable::from_table(&table, prepared)
    }

    /// Lay out `table`, built with `prepared`, as images.
    pub fn from_table(table: &MaterialTable, prepared: &Prepared) -> Result<ShaderTable, SkinError> {
        let r = table.resolution();
        let request = prepared.request();
        let slice_width = r.melanin + 2 * SHADER_TABLE_GUTTER;
        let (width, height) = (r.melanin_blend * slice_width, r.hemoglobin);
        let mut base_color_log: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0; width * height]);
        let mut radius_log: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0; width * height]);
        for k in 0..r.hemoglobin {
            let row = height - 1 - k;
            for j in 0..r.melanin_blend {
                for x in 0..slice_width {
                    // Guard columns copy the outer nodes.
                    let i = x.saturating_sub(SHADER_TABLE_GUTTER).min(r.melanin - 1);
                    let (bc, rad) = table.node_log_method(i, j, k);
                    let at = row * width + j * slice_width + x;
                    for c in 0..3 {
                        base_color_log[c][at] = bc[c];
                        radius_log[c][at] = rad[c];
                    }
                }
            }
        }
        let target = request.target.info();
        let axis = |nodes: usize, range: (f64, f64), warp: &str| ShaderAxis {
            nodes,
            min: range.0,
            max: range.1,
            warp: warp.to_string(),
        };
        let meta = ShaderTableMeta {
            format: SHADER_TABLE_FORMAT.to_string(),
            crate_version: env!("CARGO_PKG_VERSION").to_string(),
            model_version: crate::stamp::MODEL_VERSION,
            method: table.method().name().to_string(),
            blender: target.blender.to_string(),
            engine: target.engine.name().to_string(),
            color_space: request.working_space.name().to_string(),
            width,
            height,
            slice_width,
            gutter: SHADER_TABLE_GUTTER,
            melanin: axis(r.melanin, (MELANIN.min, MELANIN.max), "cube_root"),
            melanin_blend: axis(r.melanin_blend, (MELANIN_BLEND.min, MELANIN_BLEND.max), "linear"),
            hemoglobin: axis(r.hemoglobin, (HEMOGLOBIN.min, HEMOGLOBIN.max), "cube_root"),
            stored: "ln".to_string(),
            request: serde_json::to_value(request)
                .map_err(|e| SkinError::invalid("shader table request", e.to_string()))?,
            extended: extended_meta(table.extended()),
        };
        Ok(ShaderTable { meta, method: table.method(), base_color_log, radius_log })
    }

    /// A table from its parts (what `shader_table` returned, to be written): checks that the metadata is of this
    /// format and its layout consistent, and that each plane has width * height finite values.
    pub fn from_parts(
        meta: ShaderTableMeta,
        base_color_log: [Vec<f32>; 3],
        radius_log: [Vec<f32>; 3],
    ) -> Result<ShaderTable, SkinError> {
        let bad = |why: String| Err(SkinError::invalid("shader table", why));
        if meta.format != SHADER_TABLE_FORMAT {
            return bad(format!("metadata format must be {SHADER_TABLE_FORMAT:?}; got {:?}", meta.format));
        }
        let resolution = TableResolution {
            melanin: meta.melanin.nodes,
            melanin_blend: meta.melanin_blend.nodes,
            hemoglobin: meta.hemoglobin.nodes,
        };
        resolution.validate()?;
        let slice_width = resolution.melanin + 2 * SHADER_TABLE_GUTTER;
        let (w, h) = (resolution.melanin_blend * slice_width, resolution.hemoglobin);
        if (meta.width, meta.height, meta.slice_width, meta.gutter) != (w, h, slice_width, SHADER_TABLE_GUTTER) {
            return bad(format!(
                "metadata layout is inconsistent: nodes {resolution:?} need width {w}, height {h}, slice width \
                 {slice_width}, gutter {SHADER_TABLE_GUTTER}; got {}, {}, {}, {}",
                meta.width, meta.height, meta.slice_width, meta.gutter
            ));
        }
        for (name, planes) in [("base color", &base_color_log), ("radius", &radius_log)] {
            if planes.iter().any(|p| p.len() != w * h) {
                return bad(format!("{name} image must be {h} x {w} texels, as the metadata says"));
            }
            if planes.iter().flatten().any(|v| !v.is_finite()) {
                return bad(format!("{name} image holds a value that is not finite"));
            }
        }
        let method = SubsurfaceMethod::from_name(&meta.method)?;
        Ok(ShaderTable { meta, method, base_color_log, radius_log })
    }

    pub fn meta(&self) -> &ShaderTableMeta {
        &self.meta
    }

    pub fn method(&self) -> SubsurfaceMethod {
        self.method
    }

    /// ln Base Color: R, G, B planes of width * height values, row 0 at the top.
    pub fn base_color_log(&self) -> &[Vec<f32>; 3] {
        &self.base_color_log
    }

    /// ln Subsurface Radius (mm), as [`ShaderTable::base_color_log`].
    pub fn radius_log(&self) -> &[Vec<f32>; 3] {
        &self.radius_log
    }

    /// Bytes of the two images' float32 texels (what the renderer holds in memory).
    pub fn texel_bytes(&self) -> usize {
        2 * 3 * self.meta.width * self.meta.height * std::mem::size_of::<f32>()
    }

    /// Base Color and radius (mm) as the node group computes them (module documentation), in f32: the coordinate
    /// maths, Cycles' bilinear Image Texture lookup (Linear, Extend: `x * width - 0.5`, floor, clamped indices)
    /// of two slices, their linear mix and exp.
    pub fn sample(&self, melanin: f32, melanin_blend: f32, hemoglobin: f32) -> ([f32; 3], [f32; 3]) {
        let m = &self.meta;
        let (n_m, n_b, n_h) = (m.melanin.nodes as f32, m.melanin_blend.nodes as f32, m.hemoglobin.nodes as f32);
        let warp = |v: f32, max: f64| (v / max as f32).clamp(0.0, 1.0).powf(1.0 / 3.0);
        let u_m = warp(melanin, MELANIN.max);
        let u_h = warp(hemoglobin, HEMOGLOBIN.max);
        let lo = MELANIN_BLEND.min as f32;
        let span = (MELANIN_BLEND.max - MELANIN_BLEND.min) as f32;
        let b = ((melanin_blend - lo) / span).clamp(0.0, 1.0) * (n_b - 1.0);
        let j = b.floor().min(n_b - 2.0);
        let t = b - j;
        let (width, height) = (m.width as f32, m.height as f32);
        let y = (u_h * (n_h - 1.0) + 0.5) / height;
        let x = |slice: f32| (slice * m.slice_width as f32 + m.gutter as f32 + u_m * (n_m - 1.0) + 0.5) / width;
        let mut out = [[0.0f32; 3]; 2];
        for (q, planes) in [&self.base_color_log, &self.radius_log].into_iter().enumerate() {
            let s0 = self.bilinear(planes, x(j), y);
            let s1 = self.bilinear(planes, x(j + 1.0), y);
            out[q] = std::array::from_fn(|c| ((1.0 - t) * s0[c] + t * s1[c]).exp());
        }
        (out[0], out[1])
    }

    /// Cycles' CPU Image Texture lookup with Linear interpolation and Extend extension at (x, y) in [0, 1]^2, y = 0
    /// at the bottom row (`kernel/device/cpu/image.h`, `interp_linear`).
    fn bilinear(&self, planes: &[Vec<f32>; 3], x: f32, y: f32) -> [f32; 3] {
        let (w, h) = (self.meta.width, self.meta.height);
        let axis = |u: f32, n: usize| {
            let p = u * n as f32 - 0.5;
            let f = p.floor();
            let i = f as i64;
            let clamp = |i: i64| i.clamp(0, n as i64 - 1) as usize;
            (clamp(i), clamp(i + 1), p - f)
        };
        let (x0, x1, tx) = axis(x, w);
        let (y0, y1, ty) = axis(y, h);
        // Rows counted from the bottom; the planes store row 0 at the top.
        let at = |xi: usize, yi: usize| (h - 1 - yi) * w + xi;
        std::array::from_fn(|c| {
            let p = &planes[c];
            (1.0 - ty) * ((1.0 - tx) * p[at(x0, y0)] + tx * p[at(x1, y0)])
                + ty * ((1.0 - tx) * p[at(x0, y1)] + tx * p[at(x1, y1)])
        })
    }

    /// Stage the two EXRs ([`SHADER_TABLE_EXR`] unless `exr` says otherwise) and the sidecar in `out_dir` (created if missing),
    /// named with `prefix` as `pipeline::output_name` does; dropping the result deletes them.
    pub fn stage_files(&self, out_dir: &Path, prefix: Option<&str>, exr: ExrOptions) -> Result<Vec<Staged>, SkinError> {
        check_prefix(prefix)?;
        create_output_dir(out_dir)?;
        let path = |file: &str| out_dir.join(output_name(prefix, file));
        let (w, h) = (self.meta.width, self.meta.height);
        let mut staged = vec![
            stage_rgb_exr(&path(SHADER_BASE_COLOR_FILE), w, h, slices(&self.base_color_log), exr)?,
            stage_rgb_exr(&path(SHADER_RADIUS_FILE), w, h, slices(&self.radius_log), exr)?,
        ];
        let mut sidecar =
            serde_json::to_value(&self.meta).map_err(|e| SkinError::invalid("shader table", e.to_string()))?;
        sidecar["files"] = serde_json::json!({
            "base_color": {"file": output_name(prefix, SHADER_BASE_COLOR_FILE), "channels": ["R", "G", "B"],
                           "meaning": "ln Principled BSDF Base Color", "color_space": "Non-Color"},
            "radius": {"file": output_name(prefix, SHADER_RADIUS_FILE), "channels": ["R", "G", "B"],
                       "meaning": "ln (Principled BSDF Subsurface Radius x Subsurface Scale / 1 mm)",
                       "color_space": "Non-Color"},
            "encoding": exr,
        });
        let text =
            serde_json::to_string_pretty(&sidecar).map_err(|e| SkinError::invalid("shader table", e.to_string()))?;
        staged.push(stage_bytes(&path(SHADER_SIDECAR_FILE), text.as_bytes())?);
        Ok(staged)
    }

    /// Write the two EXRs and the sidecar (see [`ShaderTable::stage_files`]), renamed into place together once all
    /// are written. Returns their paths: base colour, radius, sidecar.
    pub fn write(&self, out_dir: &Path, prefix: Option<&str>, exr: ExrOptions) -> Result<Vec<PathBuf>, SkinError> {
        let staged = self.stage_files(out_dir, prefix, exr)?;
        let paths = staged.iter().map(|s| s.target().to_path_buf()).collect();
        commit_all(staged)?;
        Ok(paths)
    }
}

fn slices(p: &[Vec<f32>; 3]) -> [&[f32]; 3] {
    [&p[0], &p[1], &p[2]]
}

/// Worst relative error of [`ShaderTable::sample`] against `prepared.material` evaluated directly, at the points
/// `lut::measure_error` uses (cell centres and a low-discrepancy sequence), per output.
pub fn measure_shader_error(
    shader: &ShaderTable,
    prepared: &Prepared,
    samples: usize,
) -> Result<ShaderTableError, SkinError> {
    if samples > super::lut::MAX_TABLE_CHECK_SAMPLES {
        return Err(SkinError::invalid(
            "shader table check samples",
            format!("at most {} points; got {samples}", super::lut::MAX_TABLE_CHECK_SAMPLES),
        ));
    }
    let m = shader.meta();
    let r = TableResolution {
        melanin: m.melanin.nodes,
        melanin_blend: m.melanin_blend.nodes,
        hemoglobin: m.hemoglobin.nodes,
    };
    let errors = check_points(r, samples)
        .par_iter()
        .map(|u| {
            let p = with_extended(check_point_params(*u), m.extended_values());
            let exact = TexelMaterial::of(&prepared.material(&p)?, shader.method())?;
            let (base_color, radius_mm) = shader.sample(p.melanin as f32, p.melanin_blend as f32, p.hemoglobin as f32);
            let rel =
                |a: [f32; 3], b: [f32; 3]| (0..3).map(|c| ((a[c] - b[c]) / b[c]).abs() as f64).fold(0.0, f64::max);
            Ok([rel(base_color, exact.base_color), rel(radius_mm, exact.radius_mm)])
        })
        .collect::<Result<Vec<_>, SkinError>>()?;
    let max = |q: usize| errors.iter().map(|e| e[q]).fold(0.0, f64::max);
    Ok(ShaderTableError { samples, max_base_color_relative: max(0), max_radius_relative: max(1) })
}
