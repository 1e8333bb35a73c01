//! Fit an albedo texture: per texel, the parameters whose model albedo is closest in CIEDE2000 to the texel's colour
//! (src/inverse/albedo.rs), on the forward table only (coarse nearest node, then Levenberg-Marquardt in table
//! coordinates), each distinct colour once.

use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;
use serde::Serialize;

use super::albedo::{cached_albedo_table_cancellable, distinct_colours, fit_on_table, AlbedoFitOptions, AlbedoTable};
use super::albedo_gains::{estimate_gains, not_albedo_diagnosis, GainEstimate, NOT_ALBEDO_DELTA_E00};
use crate::error::SkinError;
use crate::maps::io::{
    commit_all, create_output_dir, output_folder_of, stage_channels_exr, ExrOptions, Staged, EXTENDED_CHANNELS,
    PARAM_CHANNELS,
};
use crate::skin::params::EXTENDED_DEFAULTS;

/// The fitted maps of an albedo texture, row-major like the input.
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoMapFit {
    pub width: usize,
    pub height: usize,
    /// C_m, beta_m, C_h, oiliness per texel (the four channels of a parameter map; the extended physiology is
    /// `extended` for every texel).
    pub params: Vec<[f32; 4]>,
    /// ΔE00 between each texel and the table's albedo of its parameters.
    pub residual_delta_e00: Vec<f32>,
    /// The extended physiology the parameters hold for (the chosen or held epidermis thickness; the others held).
    pub extended: [f64; 3],
    /// How the epidermis thickness was chosen (None: held).
    pub thickness: Option<ThicknessChoice>,
    /// The exposure and white-balance gains estimated on the texture: applied (`TextureFit::auto_gains`; the
    /// options' `rgb_gains` are these), or measured as the remedy of a `diagnosis` (not applied).
    pub gains: Option<GainEstimate>,
    /// Set when the texture does not look like an albedo (over [`super::albedo_gains::NOT_ALBEDO_SHARE`] of its texels outside skin's
    /// colours, after any gains): the share, the likely reasons and the remedies, the gains measured.
    pub diagnosis: Option<String>,
    pub stats: AlbedoMapStats,
}

impl AlbedoMapFit {
    /// The parameter map's channels: the four of [`PARAM_CHANNELS`] per texel, then the extended physiology's
    /// ([`EXTENDED_CHANNELS`], one value each), so that the map alone reproduces the fit (`maps --params`).
    pub fn parameter_planes(&self) -> Vec<(&'static str, Vec<f32>)> {
        let mut planes: Vec<(&'static str, Vec<f32>)> =
            (0..4).map(|c| (PARAM_CHANNELS[c], self.params.par_iter().map(|p| p[c]).collect())).collect();
        for (name, value) in EXTENDED_CHANNELS.iter().zip(self.extended) {
            planes.push((name, vec![value as f32; self.params.len()]));
        }
        planes
    }

    /// Write the parameter EXR (float, PIZ; the channels of [`Self::parameter_planes`]) and, if asked, the residual
    /// EXR (ΔE00, channel Y), both staged and renamed into place together; their folders are created. Nothing is
    /// left behind on an error.
    pub fn write(&self, params_path: &Path, residual_path: Option<&Path>) -> Result<(), SkinError> {
        commit_all(self.stage(params_path, residual_path)?)
    }

    /// The fit of rows `first..first + rows` (a tile of a stacked tile set): the same fit, those texels.
    pub fn rows(&self, first: usize, rows: usize) -> Result<AlbedoMapFit, SkinError> {
        if rows == 0 || first + rows > self.height {
            return Err(SkinError::invalid(
                "tile rows",
                format!("rows {first} to {} of a {}-row fit", first + rows, self.height),
            ));
        }
        let range = first * self.width..(first + rows) * self.width;
        Ok(AlbedoMapFit {
            height: rows,
            params: self.params[range.clone()].to_vec(),
            residual_delta_e00: self.residual_delta_e00[range].to_vec(),
            ..self.clone()
        })
    }

    /// [`Self::write`]'s files staged, for a caller that renames several fits' files into place together (the tiles
    /// of a UDIM set) with [`crate::maps::io::commit_all`].
    pub fn stage(&self, params_path: &Path, residual_path: Option<&Path>) -> Result<Vec<Staged>, SkinError> {
        for file in std::iter::once(params_path).chain(residual_path) {
            check_output_name(file, false)?;
        }
        for file in std::iter::once(params_path).chain(residual_path) {
            create_output_dir(output_folder_of(file))?;
        }
        let planes = self.parameter_planes();
        let named: Vec<(&str, &[f32])> = planes.iter().map(|(n, v)| (*n, v.as_slice())).collect();
        let mut staged = vec![stage_channels_exr(params_path, self.width, self.height, &named, ExrOptions::FLOAT_PIZ)?];
        if let Some(path) = residual_path {
            staged.push(stage_channels_exr(
                path,
                self.width,
                self.height,
                &[("Y", &self.residual_delta_e00)],
                ExrOptions::FLOAT_PIZ,
            )?);
        }
        Ok(staged)
    }
}

/// A fit's files are OpenEXR: a name must end in `.exr` (a `.png` name got EXR bytes), and, unless it names a
/// `tile_set`, must not hold [`crate::maps::udim::UDIM_TOKEN`] (a tile's file is named by its tile; the token was
/// written literally). Checked by [`AlbedoMapFit::stage`], and by `fit-maps` before the fit.
pub fn check_output_name(path: &Path, tile_set: bool) -> Result<(), SkinError> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let what = format!("output {}", path.display());
    if !name.to_ascii_lowercase().ends_with(".exr") || name.len() <= ".exr".len() {
        return Err(SkinError::invalid(
            what,
            "the parameter and residual maps are OpenEXR: give a name ending in .exr",
        ));
    }
    if !tile_set && crate::maps::udim::is_tile_set(path) {
        return Err(SkinError::invalid(
            what,
            format!(
                "holds {}, which names a tile set: fit a tile set (CLI: an --albedo with {0}; Python: write(..., \
                 tiles=...)) or give one file's name",
                crate::maps::udim::UDIM_TOKEN
            ),
        ));
    }
    Ok(())
}

/// Figures of a map fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoMapStats {
    pub texels: usize,
    /// Texels outside the skin mask (fitted, but not in the figures, the thickness choice, the gains or the
    /// diagnosis); 0 without a mask.
    pub masked_out_texels: usize,
    /// Distinct colours of the texture (of the whole set, for the tiles of a set fitted together).
    pub distinct_colours: usize,
    pub table_from_cache: bool,
    pub max_delta_e00: f64,
    pub mean_delta_e00: f64,
    /// Texels farther than the ambiguity ΔE00 from every reachable colour (a green texel, a tattoo).
    pub out_of_gamut_texels: usize,
    pub options: AlbedoFitOptions,
}

/// An error naming `what` (the texture, or a tile of one), the first non-finite texel (x, y; y = 0 the first row) and
/// how many there are.
fn check_texels(what: &str, texels: &[[f32; 3]], width: usize, height: usize) -> Result<(), SkinError> {
    if width == 0 || height == 0 || texels.len() != width * height {
        return Err(SkinError::invalid(
            what,
            format!("{} texels for {width} x {height} (need a non-empty texture, width * height texels)", texels.len()),
        ));
    }
    let bad = |t: &[f32; 3]| !t.iter().all(|v| v.is_finite());
    if let Some(first) = texels.iter().position(bad) {
        let count = texels.par_iter().filter(|t| bad(t)).count();
        return Err(SkinError::invalid(
            what,
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

/// How a texture fit sets the epidermis thickness (the extended parameter a texture's colours decide: 200 measured
/// skin colours fit within ΔE00 0.008 median with it chosen and 1.32 at the paper's 0.25 mm: docs/skin-atlas.md,
/// "The epidermis thickness").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EpidermisThickness {
    /// One value for the whole texture (the default): the candidate of [`THICKNESS_CANDIDATES_MM`] or the held value
    /// (`options.extended[0]`) with the least mean ΔE00 over the texture's texels, never worse on the texture than the
    /// held value ([`ThicknessChoice`] says how it was judged).
    #[default]
    Chosen,
    /// `options.extended[0]` for every texel.
    Held,
}

/// How a texture fit treats the texture beyond [`AlbedoFitOptions`]: the thickness, and whether it estimates the
/// exposure and white-balance gains first ([`super::albedo_gains::estimate_gains`]; they replace the options'
/// `rgb_gains` and are reported).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct TextureFit {
    pub thickness: EpidermisThickness,
    pub auto_gains: bool,
}

impl From<EpidermisThickness> for TextureFit {
    fn from(thickness: EpidermisThickness) -> TextureFit {
        TextureFit { thickness, auto_gains: false }
    }
}

/// How [`EpidermisThickness::Chosen`] chose, for the fit's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ThicknessChoice {
    /// [mm, mean ΔE00] per candidate: over every texel of the texture when `sampled_texels` is None, else over that
    /// many texels spread evenly over it (a texture of more than [`SCREEN_COLOURS`] distinct colours).
    pub screened: Vec<[f64; 2]>,
    pub sampled_texels: Option<usize>,
    /// [mm, mean ΔE00 over every texel] of the candidates fitted in full (after a sampled screen: the screen's best
    /// and the held value), the chosen one's the least.
    pub whole_texture: Vec<[f64; 2]>,
    pub chosen_mm: f64,
}

/// Fit every texel of a linear-RGB albedo texture (`width * height` texels, row-major) in `options.working_space`,
/// with the epidermis thickness chosen for the texture or held (`thickness`).
pub fn fit_albedo_map(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
    texture: impl Into<TextureFit>,
) -> Result<AlbedoMapFit, SkinError> {
    fit_albedo_map_cancellable(texels, width, height, options, texture, &AtomicBool::new(false))
}

/// [`fit_albedo_map`] that stops once `cancel` is set, with an error.
pub fn fit_albedo_map_cancellable(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    options: &AlbedoFitOptions,
    texture: impl Into<TextureFit>,
    cancel: &AtomicBool,
) -> Result<AlbedoMapFit, SkinError> {
    let tile = AlbedoTile { label: "albedo texture".into(), width, height, texels, mask: None };
    let mut fits = fit_albedo_tiles_cancellable(&[tile], options, texture, cancel)?;
    Ok(fits.remove(0))
}

/// One texture of a set fitted together (a UDIM tile), `label` naming it in messages.
pub struct AlbedoTile<'a> {
    pub label: String,
    pub width: usize,
    pub height: usize,
    pub texels: &'a [[f32; 3]],
    /// Which texels are skin (row-major, one per texel; None: all). Texels outside the mask are fitted too (each
    /// gets the parameters of the skin colour nearest it) but take no part in the thickness choice, the gains, the
    /// diagnosis or the figures: hair, eyes, background.
    pub mask: Option<&'a [bool]>,
}

/// Fit a set of textures as one (the tiles of a UDIM set: one epidermis thickness chosen for all of them, each colour
/// fitted once), a fit per tile in order; each tile's figures are its own, but `distinct_colours` and the thickness
/// choice are the set's.
pub fn fit_albedo_tiles_cancellable(
    tiles: &[AlbedoTile<'_>],
    options: &AlbedoFitOptions,
    texture: impl Into<TextureFit>,
    cancel: &AtomicBool,
) -> Result<Vec<AlbedoMapFit>, SkinError> {
    let texture = texture.into();
    let mut options = options.validated()?;
    for tile in tiles {
        check_texels(&tile.label, tile.texels, tile.width, tile.height)?;
    }
    let joined;
    let texels: &[[f32; 3]] = if let [one] = tiles {
        one.texels
    } else {
        joined = tiles.iter().flat_map(|t| t.texels.iter().copied()).collect::<Vec<_>>();
        &joined
    };
    crate::maps::io::check_texel_count("albedo tile set", texels.len(), 1)?;
    let mask = set_mask(tiles, texels.len())?;
    let counts_in = |i: usize| !matches!(&mask, Some(m) if !m[i]);
    let skin_texels: Vec<[f32; 3]> = match &mask {
        Some(m) => texels.iter().zip(m).filter(|(_, &k)| k).map(|(t, _)| *t).collect(),
        None => Vec::new(),
    };
    let skin: &[[f32; 3]] = if mask.is_some() { &skin_texels } else { texels };
    let mut gains = None;
    // The thicknesses the gains are estimated with: those the fit may choose from.
    let mut thicknesses = vec![options.extended[0]];
    if texture.thickness == EpidermisThickness::Chosen {
        thicknesses.extend(THICKNESS_CANDIDATES_MM.iter().filter(|&&t| t != options.extended[0]));
    }
    if texture.auto_gains {
        let estimate = estimate_gains(skin, &options, &thicknesses, cancel)?;
        options.rgb_gains = estimate.rgb_gains;
        gains = Some(estimate);
    }
    let gained;
    let texels: &[[f32; 3]] = if options.rgb_gains == [1.0; 3] {
        texels
    } else {
        let g = options.rgb_gains.map(|v| v as f32);
        gained = texels.par_iter().map(|t| [t[0] * g[0], t[1] * g[1], t[2] * g[2]]).collect::<Vec<_>>();
        &gained
    };
    let (colours, of_texel) = distinct_colours(texels);
    // The colour of each texel that counts (the mask's skin).
    let counted: Vec<u32> = match &mask {
        Some(m) => of_texel.iter().zip(m).filter(|(_, &k)| k).map(|(&i, _)| i).collect(),
        None => Vec::new(),
    };
    let counted: &[u32] = if mask.is_some() { &counted } else { &of_texel };
    // The gains are estimated at the extended physiology given (before any thickness is chosen), as auto_gains does.
    let given = options;
    let (options, fits, table_from_cache, choice) = match texture.thickness {
        EpidermisThickness::Held => {
            let (table, cached) = cached_albedo_table_cancellable(&options, cancel)?;
            (options, fit_colours(&table, &colours, &options, cancel)?, cached, None)
        }
        EpidermisThickness::Chosen => {
            let (options, fits, cached, choice) = choose_thickness(&colours, counted, &options, cancel)?;
            (options, fits, cached, Some(choice))
        }
    };
    // The diagnosis of the whole set, with the remedy measured when the gains were not estimated already.
    let far = fits
        .iter()
        .zip(colour_counts(counted, colours.len()))
        .filter(|(f, _)| f.1 as f64 > NOT_ALBEDO_DELTA_E00)
        .map(|(_, c)| c as usize)
        .sum::<usize>();
    let mut diagnosis = not_albedo_diagnosis(far, counted.len(), gains.as_ref(), texture.auto_gains);
    if diagnosis.is_some() && gains.is_none() {
        let estimate = estimate_gains(skin, &given, &thicknesses, cancel)?;
        diagnosis = not_albedo_diagnosis(far, counted.len(), Some(&estimate), false);
        gains = Some(estimate);
    }
    let set = SetFit { options, choice, gains, diagnosis, distinct_colours: colours.len(), table_from_cache };
    let mut start = 0;
    let mut out = Vec::with_capacity(tiles.len());
    for tile in tiles {
        let range = start..start + tile.texels.len();
        start += tile.texels.len();
        out.push(tile_fit(tile, &of_texel[range.clone()], &fits, |i| counts_in(range.start + i), &set));
    }
    Ok(out)
}

/// The skin mask of a tile set, the tiles' masks joined (a tile without one: all skin); None when no tile has one.
fn set_mask(tiles: &[AlbedoTile<'_>], texel_count: usize) -> Result<Option<Vec<bool>>, SkinError> {
    if tiles.iter().all(|t| t.mask.is_none()) {
        return Ok(None);
    }
    let mut joined_mask = Vec::with_capacity(texel_count);
    for tile in tiles {
        match tile.mask {
            Some(m) if m.len() != tile.texels.len() => {
                return Err(SkinError::invalid(
                    format!("mask of {}", tile.label),
                    format!("has {} values for {} texels (one per texel, row-major)", m.len(), tile.texels.len()),
                ))
            }
            Some(m) => joined_mask.extend_from_slice(m),
            None => joined_mask.extend(std::iter::repeat(true).take(tile.texels.len())),
        }
    }
    if !joined_mask.contains(&true) {
        return Err(SkinError::invalid("mask", "marks no texel as skin: at least one texel must be fitted"));
    }
    Ok(Some(joined_mask))
}

/// What every tile of a set shares: the options fitted with (the chosen thickness in them), the choice, the gains,
/// the diagnosis and the set's figures.
struct SetFit {
    options: AlbedoFitOptions,
    choice: Option<ThicknessChoice>,
    gains: Option<GainEstimate>,
    diagnosis: Option<String>,
    distinct_colours: usize,
    table_from_cache: bool,
}

/// One tile's fit: its texels' parameters and residuals from their colours' fits (`of_tile`: each texel's colour),
/// and the figures of its texels that count (`counts_in(i)`, i within the tile: the mask's skin; none: zeros).
fn tile_fit(
    tile: &AlbedoTile<'_>,
    of_tile: &[u32],
    fits: &[([f32; 3], f32)],
    counts_in: impl Fn(usize) -> bool,
    set: &SetFit,
) -> AlbedoMapFit {
    let oil = set.options.oiliness as f32;
    let (params, residual_delta_e00): (Vec<[f32; 4]>, Vec<f32>) = of_tile
        .par_iter()
        .map(|&i| {
            let (p, de) = fits[i as usize];
            ([p[0], p[1], p[2], oil], de)
        })
        .unzip();
    let counted_de: Vec<f64> =
        residual_delta_e00.iter().enumerate().filter(|(i, _)| counts_in(*i)).map(|(_, &d)| d as f64).collect();
    let max = counted_de.iter().copied().fold(0.0, f64::max);
    let mean = if counted_de.is_empty() { 0.0 } else { counted_de.iter().sum::<f64>() / counted_de.len() as f64 };
    let outside = counted_de.iter().filter(|&&d| d > set.options.ambiguity_delta_e).count();
    AlbedoMapFit {
        width: tile.width,
        height: tile.height,
        params,
        residual_delta_e00,
        extended: set.options.extended,
        thickness: set.choice.clone(),
        gains: set.gains.clone(),
        diagnosis: set.diagnosis.clone(),
        stats: AlbedoMapStats {
            texels: of_tile.len(),
            masked_out_texels: of_tile.len() - counted_de.len(),
            distinct_colours: set.distinct_colours,
            table_from_cache: set.table_from_cache,
            max_delta_e00: max,
            mean_delta_e00: mean,
            out_of_gamut_texels: outside,
            options: set.options,
        },
    }
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

/// The epidermis thicknesses [`EpidermisThickness::Chosen`] tries besides the held value, mm: the range of
/// `EPIDERMIS_THICKNESS` (0.01 mm, its minimum, is thinner than any skin's colour asks for).
pub const THICKNESS_CANDIDATES_MM: [f64; 6] = [0.05, 0.1, 0.15, 0.25, 0.35, 0.5];
/// Up to this many distinct colours, every candidate is fitted on all of them and judged on every texel; a texture
/// with more is screened on [`SCREEN_COLOURS`] texels spread over it, then the screen's best and the held value are
/// fitted in full and the better on every texel is kept.
pub const SCREEN_COLOURS: usize = 4096;

/// How many texels have each colour (`of_texel`: each texel's colour index).
fn colour_counts(of_texel: &[u32], colours: usize) -> Vec<u32> {
    let mut counts = vec![0u32; colours];
    for &i in of_texel {
        counts[i as usize] += 1;
    }
    counts
}

/// The mean over the texture's texels of per-colour values (`count[i]` texels of colour i).
fn texel_mean(values: &[([f32; 3], f32)], counts: &[u32]) -> f64 {
    let total: f64 = counts.iter().map(|&c| c as f64).sum();
    values.iter().zip(counts).map(|(v, &c)| v.1 as f64 * c as f64).sum::<f64>() / total
}

/// [`EpidermisThickness::Chosen`]: the options at the chosen thickness, every colour's fit at it, whether every
/// table came from the cache, and the report.
#[allow(clippy::type_complexity)]
fn choose_thickness(
    colours: &[[f32; 3]],
    of_texel: &[u32],
    options: &AlbedoFitOptions,
    cancel: &AtomicBool,
) -> Result<(AlbedoFitOptions, Vec<([f32; 3], f32)>, bool, ThicknessChoice), SkinError> {
    let held = options.extended[0];
    let mut candidates: Vec<f64> = THICKNESS_CANDIDATES_MM.to_vec();
    if !candidates.contains(&held) {
        candidates.push(held);
        candidates.sort_by(f64::total_cmp);
    }
    let at = |t: f64| AlbedoFitOptions { extended: [t, options.extended[1], options.extended[2]], ..*options };
    let all_cached = std::cell::Cell::new(true);
    let fit_all = |t: f64, colours: &[[f32; 3]]| -> Result<Vec<([f32; 3], f32)>, SkinError> {
        let o = at(t).validated()?;
        let (table, cached) = cached_albedo_table_cancellable(&o, cancel)?;
        all_cached.set(all_cached.get() && cached);
        fit_colours(&table, colours, &o, cancel)
    };
    let counts = colour_counts(of_texel, colours.len());
    if colours.len() <= SCREEN_COLOURS {
        // Every colour at every candidate: the means are the texture's own, and the best's fits are the result.
        let mut best: Option<(f64, f64, Vec<([f32; 3], f32)>)> = None;
        let mut screened = Vec::new();
        for &t in &candidates {
            let fits = fit_all(t, colours)?;
            let mean = texel_mean(&fits, &counts);
            screened.push([t, mean]);
            if !matches!(&best, Some(b) if b.1 <= mean) {
                best = Some((t, mean, fits));
            }
        }
        let (t, _, fits) = best.expect("at least one candidate");
        let choice = ThicknessChoice { whole_texture: screened.clone(), screened, sampled_texels: None, chosen_mm: t };
        return Ok((at(t), fits, all_cached.get(), choice));
    }
    // Screen on texels spread evenly over the texture (the golden-ratio sequence: no row or column pattern), each
    // distinct colour fitted once with its multiplicity.
    let mut weight: HashMap<u32, u32> = HashMap::new();
    for k in 0..SCREEN_COLOURS {
        *weight.entry(of_texel[crate::numeric::golden_index(k, of_texel.len())]).or_default() += 1;
    }
    let mut sample: Vec<(u32, u32)> = weight.into_iter().collect();
    sample.sort_unstable();
    let sample_colours: Vec<[f32; 3]> = sample.iter().map(|&(i, _)| colours[i as usize]).collect();
    let sample_counts: Vec<u32> = sample.iter().map(|&(_, c)| c).collect();
    let mut screened = Vec::new();
    for &t in &candidates {
        screened.push([t, texel_mean(&fit_all(t, &sample_colours)?, &sample_counts)]);
    }
    let best = screened.iter().fold(screened[0], |b, m| if m[1] < b[1] { *m } else { b })[0];
    let mut whole_texture = Vec::new();
    let mut kept: Option<(f64, f64, Vec<([f32; 3], f32)>)> = None;
    for t in if best == held { vec![held] } else { vec![best, held] } {
        let fits = fit_all(t, colours)?;
        let mean = texel_mean(&fits, &counts);
        whole_texture.push([t, mean]);
        if !matches!(&kept, Some(k) if k.1 <= mean) {
            kept = Some((t, mean, fits));
        }
    }
    let (t, _, fits) = kept.expect("at least one candidate");
    let choice = ThicknessChoice { screened, sampled_texels: Some(SCREEN_COLOURS), whole_texture, chosen_mm: t };
    Ok((at(t), fits, all_cached.get(), choice))
}

/// Whether the options' extended physiology is the paper's (a four-channel parameter map says everything).
pub fn is_paper_extended(options: &AlbedoFitOptions) -> bool {
    options.extended == EXTENDED_DEFAULTS
}
