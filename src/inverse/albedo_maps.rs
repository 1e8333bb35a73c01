//! Fit an albedo texture: per texel, the parameters whose model albedo is closest in CIEDE2000 to the texel's colour
//! (src/inverse/albedo.rs), on the forward table only (coarse nearest node, then Levenberg-Marquardt in table
//! coordinates), each distinct colour once.

use std::sync::atomic::AtomicBool;

use rayon::prelude::*;
use serde::Serialize;

use super::albedo::{cached_albedo_table_cancellable, distinct_colours, fit_on_table, AlbedoFitOptions, AlbedoTable};
use crate::error::SkinError;
use crate::skin::params::{EPIDERMIS_THICKNESS, EXTENDED_DEFAULTS};

/// The fitted maps of an albedo texture, row-major like the input.
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoMapFit {
    pub width: usize,
    pub height: usize,
    /// C_m, beta_m, C_h, oiliness per texel (the four channels of a parameter map; the extended physiology is
    /// `options.extended` for every texel).
    pub params: Vec<[f32; 4]>,
    /// ΔE00 between each texel and the table's albedo of its parameters.
    pub residual_delta_e00: Vec<f32>,
    pub stats: AlbedoMapStats,
}

/// Figures of a map fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoMapStats {
    pub texels: usize,
    pub distinct_colours: usize,
    pub table_from_cache: bool,
    pub max_delta_e00: f64,
    pub mean_delta_e00: f64,
    /// Texels farther than the ambiguity ΔE00 from every reachable colour (a green texel, a tattoo).
    pub out_of_gamut_texels: usize,
    pub options: AlbedoFitOptions,
}

/// An error naming the first non-finite texel (x, y; y = 0 the first row) and how many there are.
fn check_texels(texels: &[[f32; 3]], width: usize, height: usize) -> Result<(), SkinError> {
    if width == 0 || height == 0 || texels.len() != width * height {
        return Err(SkinError::invalid(
            "albedo texture",
            format!("{} texels for {width} x {height} (need a non-empty texture, width * height texels)", texels.len()),
        ));
    }
    let bad = |t: &[f32; 3]| !t.iter().all(|v| v.is_finite());
    if let Some(first) = texels.iter().position(bad) {
        let count = texels.par_iter().filter(|t| bad(t)).count();
        return Err(SkinError::invalid(
            "albedo texture",
            format!(
                "texel (x, y) = ({}, {}) is {:?}: every channel must be finite ({count} texel(s) are not)",
                first % width,
                first / width,
                texels[first]
            ),
        ));
    }
    Ok(())
}

/// Fit every texel of a linear-RGB albedo texture (`width * height` texels, row-major) in `options.working_space`.
pub fn fit_albedo_map(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
) -> Result<AlbedoMapFit, SkinError> {
    fit_albedo_map_cancellable(texels, width, height, options, &AtomicBool::new(false))
}

/// [`fit_albedo_map`] that stops once `cancel` is set, with an error.
pub fn fit_albedo_map_cancellable(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<AlbedoMapFit, SkinError> {
    let options = options.validated()?;
    check_texels(texels, width, height)?;
    let (table, table_from_cache) = cached_albedo_table_cancellable(&options, cancel)?;
    let (colours, of_texel) = distinct_colours(texels);
    let fits = fit_colours(&table, &colours, &options, cancel)?;
    let oil = options.oiliness as f32;
    let (params, residual_delta_e00): (Vec<[f32; 4]>, Vec<f32>) = of_texel
        .par_iter()
        .map(|&i| {
            let (p, de) = fits[i as usize];
            ([p[0], p[1], p[2], oil], de)
        })
        .unzip();
    let max = fits.iter().map(|f| f.1 as f64).fold(0.0, f64::max);
    let mean = residual_delta_e00.par_iter().map(|&d| d as f64).sum::<f64>() / texels.len() as f64;
    let out = residual_delta_e00.par_iter().filter(|&&d| d as f64 > options.ambiguity_delta_e).count();
    Ok(AlbedoMapFit {
        width,
        height,
        params,
        residual_delta_e00,
        stats: AlbedoMapStats {
            texels: texels.len(),
            distinct_colours: colours.len(),
            table_from_cache,
            max_delta_e00: max,
            mean_delta_e00: mean,
            out_of_gamut_texels: out,
            options,
        },
    })
}

/// (C_m, beta_m, C_h) and the table's ΔE00 of each colour.
fn fit_colours(
    table: &AlbedoTable,
    colours: &[[f32; 3]],
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<Vec<([f32; 3], f32)>, SkinError> {
    colours
        .par_iter()
        .map(|c| {
            SkinError::check_cancel(cancel, "albedo map fit")?;
            let (u, de) = fit_on_table(table, c.map(f64::from), options);
            let p = options.params_at(u);
            Ok(([p.melanin, p.melanin_blend, p.hemoglobin].map(f32_not_above), de as f32))
        })
        .collect()
}

/// `x` (>= 0) as the nearest f32 not above it, so that a parameter at its range's maximum (0.1) stays in range.
fn f32_not_above(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x && f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f
    }
}

/// The epidermis thicknesses [`fit_epidermis_thickness`] tries, mm: the range of `EPIDERMIS_THICKNESS`.
pub const THICKNESS_CANDIDATES_MM: [f64; 6] = [0.05, 0.1, 0.15, 0.25, 0.35, 0.5];
/// Most distinct colours [`fit_epidermis_thickness`] fits per candidate (an even sample of them).
const THICKNESS_SAMPLE: usize = 2048;

/// One epidermis thickness for a whole texture: the candidate (`THICKNESS_CANDIDATES_MM`) whose fit has the
/// smallest mean ΔE00 over an even sample of the texture's distinct colours, with each candidate's mean. The other
/// options (including the other extended parameters) are held.
pub fn fit_epidermis_thickness(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
) -> Result<(f64, Vec<[f64; 2]>), SkinError> {
    fit_epidermis_thickness_cancellable(texels, width, height, options, &AtomicBool::new(false))
}

/// [`fit_epidermis_thickness`] that stops once `cancel` is set (its six tables' builds and fits read it).
pub fn fit_epidermis_thickness_cancellable(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<(f64, Vec<[f64; 2]>), SkinError> {
    check_texels(texels, width, height)?;
    let (colours, _) = distinct_colours(texels);
    let step = colours.len().div_ceil(THICKNESS_SAMPLE).max(1);
    let sample: Vec<[f32; 3]> = colours.iter().step_by(step).copied().collect();
    let mut means = Vec::new();
    for t in THICKNESS_CANDIDATES_MM {
        debug_assert!((EPIDERMIS_THICKNESS.min..=EPIDERMIS_THICKNESS.max).contains(&t));
        let o = AlbedoFitOptions { extended: [t, options.extended[1], options.extended[2]], ..*options }.validated()?;
        let (table, _) = cached_albedo_table_cancellable(&o, cancel)?;
        let fits = fit_colours(&table, &sample, &o, cancel)?;
        means.push([t, fits.iter().map(|f| f.1 as f64).sum::<f64>() / fits.len() as f64]);
    }
    let best = means.iter().fold(means[0], |b, m| if m[1] < b[1] { *m } else { b });
    Ok((best[0], means))
}

/// Whether the options' extended physiology is the paper's (a four-channel parameter map says everything).
pub fn is_paper_extended(options: &AlbedoFitOptions) -> bool {
    options.extended == EXTENDED_DEFAULTS
}
