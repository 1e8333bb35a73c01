//! Fit an albedo texture: per texel, the parameters whose model albedo is closest in CIEDE2000 to the texel's colour
//! (src/inverse/albedo.rs), on the forward table only (coarse nearest node, then Levenberg-Marquardt in table
//! coordinates), each distinct colour once, the texels in blocks of rows.

use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use super::albedo::{cached_albedo_table_ticking, colour_key, fit_on_table, AlbedoFitOptions, AlbedoTable};
use super::albedo_gains::{
    estimate_gains_of_sample, not_albedo_diagnosis, outside_skin, spread_sample_of, GainEstimate, GAIN_SAMPLE,
};
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
    /// Texels outside skin's colours (a green texel, a tattoo, a photograph's highlight), of those that count (the
    /// mask's skin): farther than [`super::albedo_gains::OUTSIDE_SKIN_DELTA_E00`] from every colour skin can have
    /// ([`outside_skin`]). The diagnosis judges this count.
    pub outside_skin_texels: usize,
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
    fit_albedo_tiles_with_progress(tiles, options, texture, None, cancel)
}

/// [`fit_albedo_tiles_cancellable`] that tells `progress(done, total)` how many more of the set's `total` texels are
/// done, as the maps pipeline's `compute_maps_cancellable` does: `(0, total)` while a forward table is built (about
/// once per percent of its nodes), the gains are estimated (each round) and the thickness is screened (each
/// candidate), then increments as the colours are fitted and the texels filled in, adding up to `total` when the fit
/// has succeeded, so that a front whose callback decides to cancel (and sets `cancel`) is asked at every stage. A
/// cancelled fit never returns a (partial) result.
///
/// The per-texel passes work in blocks of whole rows ([`BLOCK_TEXELS`]): beside its input and its output the fit
/// holds the distinct colours and their fits, and a block of cache keys per thread. Until the colours are fitted,
/// each texel's residual holds its colour's index.
pub fn fit_albedo_tiles_with_progress(
    tiles: &[AlbedoTile<'_>],
    options: &AlbedoFitOptions,
    texture: impl Into<TextureFit>,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
    cancel: &AtomicBool,
) -> Result<Vec<AlbedoMapFit>, SkinError> {
    let texture = texture.into();
    let mut options = options.validated()?;
    for tile in tiles {
        check_texels(&tile.label, tile.texels, tile.width, tile.height)?;
    }
    let set = TileSet::new(tiles)?;
    let ticks = &Ticks { progress, total: set.total, done: AtomicUsize::new(0), filled: AtomicUsize::new(0) };
    // The shares of the progress bar: the gains' estimate (when asked for), the distinct colours, their fits, the
    // texels filled in (the rest).
    let gains_end = if texture.auto_gains { 0.2 } else { 0.0 };
    let (colours_end, fits_end) = (gains_end + 0.05, 0.95);
    let mut gains = None;
    // The thicknesses the gains are estimated with: those the fit may choose from.
    let mut thicknesses = vec![options.extended[0]];
    if texture.thickness == EpidermisThickness::Chosen {
        thicknesses.extend(THICKNESS_CANDIDATES_MM.iter().filter(|&&t| t != options.extended[0]));
    }
    let skin_sample = || set.skin_sample(GAIN_SAMPLE);
    if texture.auto_gains {
        let part = |f: f64| ticks.reach(gains_end * f);
        let estimate = estimate_gains_of_sample(&skin_sample(), &options, &thicknesses, &part, cancel)?;
        options.rgb_gains = estimate.rgb_gains;
        gains = Some(estimate);
    }
    // The outputs, each texel's residual holding its colour's index until the colours are fitted.
    let params: Vec<Vec<[f32; 4]>> = tiles.iter().map(|t| vec![[0.0; 4]; t.texels.len()]).collect();
    let mut residuals: Vec<Vec<f32>> = tiles.iter().map(|t| vec![0.0; t.texels.len()]).collect();
    let (colours, counts) =
        set.distinct_colours(options.rgb_gains, &mut residuals, ticks, (gains_end, colours_end), cancel)?;
    let colour_of = |g: usize| {
        let (t, i) = set.locate(g);
        residuals[t][i].to_bits()
    };
    // The gains are estimated at the extended physiology given (before any thickness is chosen), as auto_gains does.
    let given = options;
    let fitting = |from: f64, to: f64| move |f: f64| ticks.reach(from + (to - from) * f);
    let (options, fits, table_from_cache, choice) = match texture.thickness {
        EpidermisThickness::Held => {
            let (table, cached) = cached_albedo_table_ticking(&options, cancel, Some(&|| ticks.tick()))?;
            let fits = fit_colours(&table, &colours, &options, &fitting(colours_end, fits_end), cancel)?;
            (options, fits, cached, None)
        }
        EpidermisThickness::Chosen => {
            let counted = |j: usize| colour_of(set.skin_texel(j));
            let (options, fits, cached, choice) = choose_thickness(
                &colours,
                &counts,
                (set.skin, &counted),
                &options,
                (ticks, colours_end, fits_end),
                cancel,
            )?;
            (options, fits, cached, Some(choice))
        }
    };
    // The diagnosis of the whole set, with the remedy measured when the gains were not estimated already.
    // The set's texels outside skin's colours: the sum of its tiles' `outside_skin_texels`.
    let outside =
        fits.iter().zip(&counts).filter(|(f, _)| outside_skin(f.1 as f64)).map(|(_, &c)| c as usize).sum::<usize>();
    let mut diagnosis = not_albedo_diagnosis(outside, set.skin, gains.as_ref(), texture.auto_gains);
    if diagnosis.is_some() && gains.is_none() {
        let estimate = estimate_gains_of_sample(&skin_sample(), &given, &thicknesses, &|_| ticks.tick(), cancel)?;
        diagnosis = not_albedo_diagnosis(outside, set.skin, Some(&estimate), false);
        gains = Some(estimate);
    }
    let shared = SetFit { options, choice, gains, diagnosis, distinct_colours: colours.len(), table_from_cache };
    let mut out = Vec::with_capacity(tiles.len());
    for ((tile, params), residual) in tiles.iter().zip(params).zip(residuals) {
        SkinError::check_cancel(cancel, "albedo map fit")?;
        out.push(tile_fit(tile, params, residual, &fits, &shared, &|n| ticks.advance(n, fits_end)));
    }
    ticks.reach(1.0);
    // A flag set by the last call is an interruption too (nothing returned).
    SkinError::check_cancel(cancel, "albedo map fit")?;
    Ok(out)
}

/// Texels per block of the per-texel passes (whole rows; one row at least).
pub const BLOCK_TEXELS: usize = 1 << 16;
/// Texels per entry of [`TileSet`]'s count of skin texels (the k-th skin texel is found by scanning at most this
/// many).
const SKIN_CHUNK: usize = 4096;

/// The progress of a set fit, in texels of the set ([`fit_albedo_tiles_with_progress`]).
struct Ticks<'a> {
    progress: Option<&'a (dyn Fn(usize, usize) + Sync)>,
    total: usize,
    /// Texels reported done so far (never back).
    done: AtomicUsize,
    /// Texels filled in by the last pass.
    filled: AtomicUsize,
}

impl Ticks<'_> {
    /// `(0, total)`: nothing more done, but the front is asked.
    fn tick(&self) {
        if let Some(p) = self.progress {
            p(0, self.total);
        }
    }

    /// The fit is `fraction` (0..1) of the way: the texels done go up to that share of the total (a tick when that is
    /// no more than before).
    fn reach(&self, fraction: f64) {
        let Some(p) = self.progress else { return };
        let target = ((fraction.clamp(0.0, 1.0) * self.total as f64).round() as usize).min(self.total);
        let before = self.done.fetch_max(target, Ordering::Relaxed);
        p(target.saturating_sub(before), self.total);
    }

    /// `texels` more of the set filled in, the filling being the share of the progress after `from`.
    fn advance(&self, texels: usize, from: f64) {
        let filled = self.filled.fetch_add(texels, Ordering::Relaxed) + texels;
        self.reach(from + (1.0 - from) * filled as f64 / self.total.max(1) as f64);
    }
}

/// The tiles of a set as one texture, their rows one after another: where each global texel is, which are skin, and
/// the blocks of rows the per-texel passes work in.
struct TileSet<'a, 't> {
    tiles: &'a [AlbedoTile<'t>],
    /// The first global texel of each tile.
    starts: Vec<usize>,
    total: usize,
    /// Skin texels (all of them without a mask).
    skin: usize,
    /// With a mask: the skin texels before each [`SKIN_CHUNK`] of global texels.
    skin_before: Option<Vec<usize>>,
}

impl<'a, 't> TileSet<'a, 't> {
    /// The set, its size checked ([`crate::maps::io::check_texel_count`]) and its masks (one value per texel, at
    /// least one skin texel).
    fn new(tiles: &'a [AlbedoTile<'t>]) -> Result<Self, SkinError> {
        let mut starts = Vec::with_capacity(tiles.len());
        let mut total = 0;
        for tile in tiles {
            starts.push(total);
            total += tile.texels.len();
        }
        crate::maps::io::check_texel_count("albedo tile set", total, 1)?;
        let mut set = TileSet { tiles, starts, total, skin: total, skin_before: None };
        if tiles.iter().all(|t| t.mask.is_none()) {
            return Ok(set);
        }
        for tile in tiles {
            if let Some(m) = tile.mask.filter(|m| m.len() != tile.texels.len()) {
                return Err(SkinError::invalid(
                    format!("mask of {}", tile.label),
                    format!("has {} values for {} texels (one per texel, row-major)", m.len(), tile.texels.len()),
                ));
            }
        }
        let mut before = Vec::with_capacity(total / SKIN_CHUNK + 1);
        let mut skin = 0;
        for g in 0..total {
            if g % SKIN_CHUNK == 0 {
                before.push(skin);
            }
            skin += set.is_skin(g) as usize;
        }
        if skin == 0 {
            return Err(SkinError::invalid("mask", "marks no texel as skin: at least one texel must be fitted"));
        }
        set.skin = skin;
        set.skin_before = Some(before);
        Ok(set)
    }

    /// (tile, texel within it) of global texel `g`.
    fn locate(&self, g: usize) -> (usize, usize) {
        let t = self.starts.partition_point(|&s| s <= g) - 1;
        (t, g - self.starts[t])
    }

    fn is_skin(&self, g: usize) -> bool {
        let (t, i) = self.locate(g);
        self.tiles[t].mask.map_or(true, |m| m[i])
    }

    /// The global index of the `j`-th skin texel (`j < skin`).
    fn skin_texel(&self, j: usize) -> usize {
        let Some(before) = &self.skin_before else { return j };
        let chunk = before.partition_point(|&b| b <= j) - 1;
        let mut seen = before[chunk];
        let mut g = chunk * SKIN_CHUNK;
        loop {
            if self.is_skin(g) {
                if seen == j {
                    return g;
                }
                seen += 1;
            }
            g += 1;
        }
    }

    /// The skin texels spread over the set that the gains are estimated on ([`spread_sample`]'s).
    fn skin_sample(&self, count: usize) -> Vec<([f32; 3], u32)> {
        spread_sample_of(self.skin, count, |j| {
            let (t, i) = self.locate(self.skin_texel(j));
            self.tiles[t].texels[i]
        })
    }

    /// The blocks of the per-texel passes in order: (tile, its texels), whole rows, [`BLOCK_TEXELS`] at most unless
    /// a row is longer.
    fn blocks(&self) -> Vec<(usize, std::ops::Range<usize>)> {
        let mut blocks = Vec::new();
        for (t, tile) in self.tiles.iter().enumerate() {
            let step = (BLOCK_TEXELS / tile.width).max(1) * tile.width;
            blocks.extend((0..tile.texels.len()).step_by(step).map(|s| (t, s..(s + step).min(tile.texels.len()))));
        }
        blocks
    }

    /// The distinct colours of the set times `gains` (up to the cache key's quantisation, [`colour_key`]: the first
    /// texel's colour of each key, scanning the tiles in order) and how many skin texels have each; each texel's
    /// colour index is written into `index` (per tile, as the bits of an f32). The keys are computed a few blocks at
    /// a time in parallel and entered in order; a texel whose key is its left neighbour's skips the hash.
    fn distinct_colours(
        &self,
        gains: [f64; 3],
        index: &mut [Vec<f32>],
        ticks: &Ticks<'_>,
        (from, to): (f64, f64),
        cancel: &AtomicBool,
    ) -> Result<(Vec<[f32; 3]>, Vec<u32>), SkinError> {
        let g = gains.map(|v| v as f32);
        let gained = |t: &[f32; 3]| if gains == [1.0; 3] { *t } else { [t[0] * g[0], t[1] * g[1], t[2] * g[2]] };
        let mut lookup: HashMap<[u32; 3], u32, fnv::FnvBuildHasher> = HashMap::default();
        let mut colours = Vec::new();
        let mut counts: Vec<u32> = Vec::new();
        let blocks = self.blocks();
        let group = 2 * rayon::current_num_threads().max(1);
        let mut done = 0;
        for run in blocks.chunks(group) {
            SkinError::check_cancel(cancel, "albedo map fit")?;
            let keys: Vec<Vec<[u32; 3]>> = run
                .par_iter()
                .map(|(t, range)| self.tiles[*t].texels[range.clone()].iter().map(|x| colour_key(&gained(x))).collect())
                .collect();
            for ((t, range), keys) in run.iter().zip(keys) {
                let tile = &self.tiles[*t];
                let mut last: Option<([u32; 3], u32)> = None;
                for (i, key) in range.clone().zip(keys) {
                    let c = match last {
                        Some((k, c)) if k == key => c,
                        _ => {
                            let next = colours.len() as u32;
                            let c = *lookup.entry(key).or_insert_with(|| {
                                colours.push(gained(&tile.texels[i]));
                                counts.push(0);
                                next
                            });
                            last = Some((key, c));
                            c
                        }
                    };
                    index[*t][i] = f32::from_bits(c);
                    if tile.mask.map_or(true, |m| m[i]) {
                        counts[c as usize] += 1;
                    }
                }
                done += range.len();
            }
            ticks.reach(from + (to - from) * done as f64 / self.total as f64);
        }
        Ok((colours, counts))
    }
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

/// One tile's fit: its texels' parameters and residuals from their colours' fits (`residual` holds each texel's
/// colour index on the way in), filled in blocks of rows in parallel (`filled(texels)` after each), and the figures
/// of its texels that count (the mask's skin; none: zeros).
fn tile_fit(
    tile: &AlbedoTile<'_>,
    mut params: Vec<[f32; 4]>,
    mut residual: Vec<f32>,
    fits: &[([f32; 3], f32)],
    set: &SetFit,
    filled: &(dyn Fn(usize) + Sync),
) -> AlbedoMapFit {
    let oil = set.options.oiliness as f32;
    let step = (BLOCK_TEXELS / tile.width).max(1) * tile.width;
    // (sum, max, count outside skin's colours, count) of the ΔE00 of the texels that count.
    let (sum, max, outside, counted) = params
        .par_chunks_mut(step)
        .zip(residual.par_chunks_mut(step))
        .enumerate()
        .map(|(b, (params, residual))| {
            let mut figures = (0.0f64, 0.0f64, 0usize, 0usize);
            for (k, (p, r)) in params.iter_mut().zip(residual.iter_mut()).enumerate() {
                let (q, de) = fits[r.to_bits() as usize];
                *p = [q[0], q[1], q[2], oil];
                *r = de;
                if tile.mask.map_or(true, |m| m[b * step + k]) {
                    let d = de as f64;
                    figures = (figures.0 + d, figures.1.max(d), figures.2 + outside_skin(d) as usize, figures.3 + 1);
                }
            }
            filled(params.len());
            figures
        })
        .reduce(|| (0.0, 0.0, 0, 0), |a, b| (a.0 + b.0, a.1.max(b.1), a.2 + b.2, a.3 + b.3));
    AlbedoMapFit {
        width: tile.width,
        height: tile.height,
        params,
        residual_delta_e00: residual,
        extended: set.options.extended,
        thickness: set.choice.clone(),
        gains: set.gains.clone(),
        diagnosis: set.diagnosis.clone(),
        stats: AlbedoMapStats {
            texels: tile.texels.len(),
            masked_out_texels: tile.texels.len() - counted,
            distinct_colours: set.distinct_colours,
            table_from_cache: set.table_from_cache,
            max_delta_e00: max,
            mean_delta_e00: if counted == 0 { 0.0 } else { sum / counted as f64 },
            outside_skin_texels: outside,
            options: set.options,
        },
    }
}

/// (C_m, beta_m, C_h) and the table's ΔE00 of each colour, fitted in parallel in chunks; `part(f)` is told the
/// share `f` of the colours done after each chunk.
fn fit_colours(
    table: &AlbedoTable,
    colours: &[[f32; 3]],
    options: &AlbedoFitOptions,
    part: &(dyn Fn(f64) + Sync),
    cancel: &AtomicBool,
) -> Result<Vec<([f32; 3], f32)>, SkinError> {
    let done = AtomicUsize::new(0);
    let chunk = (colours.len() / 200).clamp(16, 1024);
    let chunks = colours
        .par_chunks(chunk)
        .map(|chunk| {
            let fits = chunk
                .iter()
                .map(|c| {
                    SkinError::check_cancel(cancel, "albedo map fit")?;
                    let (u, de) = fit_on_table(table, c.map(f64::from), options);
                    let p = options.params_at(u);
                    Ok(([p.melanin, p.melanin_blend, p.hemoglobin].map(f32_not_above), de as f32))
                })
                .collect::<Result<Vec<_>, SkinError>>()?;
            part((done.fetch_add(chunk.len(), Ordering::Relaxed) + chunk.len()) as f64 / colours.len() as f64);
            Ok(fits)
        })
        .collect::<Result<Vec<_>, SkinError>>()?;
    Ok(chunks.concat())
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

/// The mean over the texture's texels of per-colour values (`count[i]` texels of colour i).
fn texel_mean(values: &[([f32; 3], f32)], counts: &[u32]) -> f64 {
    let total: f64 = counts.iter().map(|&c| c as f64).sum();
    values.iter().zip(counts).map(|(v, &c)| v.1 as f64 * c as f64).sum::<f64>() / total
}

/// [`EpidermisThickness::Chosen`]: the options at the chosen thickness, every colour's fit at it, whether every
/// table came from the cache, and the report. `counts`: the skin texels of each colour; `colour_of_skin(j)`: the
/// colour of the `j`-th of the `skin` texels (for the screen); the progress goes from `from` to `to` of the way.
#[allow(clippy::type_complexity)]
fn choose_thickness(
    colours: &[[f32; 3]],
    counts: &[u32],
    (skin, colour_of_skin): (usize, &dyn Fn(usize) -> u32),
    options: &AlbedoFitOptions,
    (ticks, from, to): (&Ticks<'_>, f64, f64),
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
    let fit_all = |t: f64, colours: &[[f32; 3]], part: &(dyn Fn(f64) + Sync)| {
        let o = at(t).validated()?;
        let (table, cached) = cached_albedo_table_ticking(&o, cancel, Some(&|| ticks.tick()))?;
        all_cached.set(all_cached.get() && cached);
        fit_colours(&table, colours, &o, part, cancel)
    };
    // The k-th of n passes over every colour: its share of the way from `from` to `to`.
    let pass = |k: usize, n: usize| move |f: f64| ticks.reach(from + (to - from) * (k as f64 + f) / n as f64);
    if colours.len() <= SCREEN_COLOURS {
        // Every colour at every candidate: the means are the texture's own, and the best's fits are the result.
        let mut best: Option<(f64, f64, Vec<([f32; 3], f32)>)> = None;
        let mut screened = Vec::new();
        for (k, &t) in candidates.iter().enumerate() {
            let fits = fit_all(t, colours, &pass(k, candidates.len()))?;
            let mean = texel_mean(&fits, counts);
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
        *weight.entry(colour_of_skin(crate::numeric::golden_index(k, skin))).or_default() += 1;
    }
    let mut sample: Vec<(u32, u32)> = weight.into_iter().collect();
    sample.sort_unstable();
    let sample_colours: Vec<[f32; 3]> = sample.iter().map(|&(i, _)| colours[i as usize]).collect();
    let sample_counts: Vec<u32> = sample.iter().map(|&(_, c)| c).collect();
    let mut screened = Vec::new();
    for &t in &candidates {
        screened.push([t, texel_mean(&fit_all(t, &sample_colours, &|_| ticks.tick())?, &sample_counts)]);
    }
    let best = screened.iter().fold(screened[0], |b, m| if m[1] < b[1] { *m } else { b })[0];
    let mut whole_texture = Vec::new();
    let mut kept: Option<(f64, f64, Vec<([f32; 3], f32)>)> = None;
    let full = if best == held { vec![held] } else { vec![best, held] };
    for (k, &t) in full.iter().enumerate() {
        let fits = fit_all(t, colours, &pass(k, full.len()))?;
        let mean = texel_mean(&fits, counts);
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
