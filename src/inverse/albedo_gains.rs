//! When a texture is not an albedo: the share of its texels that no skin of the model reproduces, the likely reason,
//! and the remedy measured on the texture: the exposure and white-balance gains (one factor per RGB channel) that
//! bring the most texels inside skin's colours.
//!
//! A photograph is lit: its colours are the albedo times the light (exposure, the light's colour when the camera's
//! white balance did not remove it) and shading. Gains undo the global part. They are found like a colour
//! calibration against the model: fit each sampled colour (times the gains) on the forward table, then solve the
//! per-channel least-squares gains that map the colours onto their fits' albedos (robustly weighted, so texels far
//! outside, such as hair or background, count little), and repeat. The gains cannot tell an exposure from melanin (a
//! darker photo of fair skin is a brighter photo of darker skin): they bring the texture inside skin's colours, they
//! do not prove its physiology.

use std::collections::HashMap;
use std::sync::atomic::AtomicBool;

use rayon::prelude::*;
use serde::Serialize;

use super::albedo::{
    cached_albedo_table_ticking, fit_on_table_costed, refit_on_table, AlbedoFitOptions, AlbedoTable, GAIN_RANGE,
};
use crate::error::SkinError;

/// A texel this far (ΔE00) from every colour skin can have is plainly not skin's albedo (the fit's own residual on
/// measured albedos stays under it for 9 texels in 10: docs/skin-atlas.md, "When the input is not an albedo").
pub const NOT_ALBEDO_DELTA_E00: f64 = 2.0;
/// Above this share of texels farther than [`NOT_ALBEDO_DELTA_E00`], a fit reports that the input does not look like
/// an albedo: 200 measured albedos of eight ethnic groups in one texture have under 10 % there, a simulated
/// photograph under a tungsten lamp all of them.
pub const NOT_ALBEDO_SHARE: f64 = 0.25;
/// Texels the gains are estimated on (spread evenly over the texture; each distinct colour fitted once).
pub const GAIN_SAMPLE: usize = 2048;
/// Rounds of fit-then-solve; the gains settle in 5 to 10 on the textures tried.
const GAIN_ROUNDS: usize = 16;

/// Gains found for a texture ([`estimate_gains`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GainEstimate {
    /// Per linear-RGB channel of the working space: multiply the texture by these before the fit.
    pub rgb_gains: [f64; 3],
    /// The exposure part, in stops: log2 of the gains' effect on luminance (Y).
    pub exposure_stops: f64,
    /// The epidermis thickness the gains were found with (the fit may still choose another for the gained texture).
    pub epidermis_thickness_mm: f64,
    /// Share of the sampled texels outside skin's colours before and after the gains.
    pub outside_share_before: f64,
    pub outside_share_after: f64,
    /// Median ΔE00 of the sampled texels before and after.
    pub median_delta_e00_before: f64,
    pub median_delta_e00_after: f64,
    pub sampled_texels: usize,
}

/// Texels spread evenly over `texels` (the golden-ratio sequence), as distinct colours with their counts.
pub(crate) fn spread_sample(texels: &[[f32; 3]], count: usize) -> Vec<([f32; 3], u32)> {
    spread_sample_of(texels.len(), count, |i| texels[i])
}

/// [`spread_sample`] of the `n` texels `texel(0)`, ..., `texel(n - 1)` (none: an empty sample).
pub(crate) fn spread_sample_of(n: usize, count: usize, texel: impl Fn(usize) -> [f32; 3]) -> Vec<([f32; 3], u32)> {
    let mut seen: HashMap<[u32; 3], ([f32; 3], u32)> = HashMap::new();
    for k in 0..count.min(n * 4) {
        let t = texel(crate::numeric::golden_index(k, n));
        seen.entry(t.map(f32::to_bits)).or_insert((t, 0)).1 += 1;
    }
    let mut sample: Vec<([f32; 3], u32)> = seen.into_values().collect();
    sample.sort_by(|a, b| a.0.map(f32::to_bits).cmp(&b.0.map(f32::to_bits)));
    sample
}

/// A sampled colour's fit: (ΔE00, the table's albedo there, (table coordinates, cost)).
type SampleFit = (f64, [f64; 3], ([f64; 3], f64));

/// Each sampled colour times `gains`, fitted on the table: (ΔE00, the table's albedo at the fit, the fit's table
/// coordinates and cost). With `previous` (each colour's fit under the last round's gains: coordinates and cost), each
/// is refitted from there ([`refit_on_table`]); without, fitted afresh.
fn fit_sample(
    table: &AlbedoTable,
    sample: &[([f32; 3], u32)],
    gains: [f64; 3],
    options: &AlbedoFitOptions,
    previous: Option<&[([f64; 3], f64)]>,
    cancel: &AtomicBool,
) -> Result<Vec<SampleFit>, SkinError> {
    sample
        .par_iter()
        .enumerate()
        .map(|(i, (c, _))| {
            SkinError::check_cancel(cancel, "gain estimate")?;
            let target = [0, 1, 2].map(|k| c[k] as f64 * gains[k]);
            let (u, de, cost) = match previous {
                Some(previous) => refit_on_table(table, target, options, previous[i]),
                None => fit_on_table_costed(table, target, options),
            };
            Ok((de, table.albedo(u), (u, cost)))
        })
        .collect()
}

/// (share outside, median ΔE00) of a fitted sample, weighted by the counts.
fn figures(fits: &[SampleFit], sample: &[([f32; 3], u32)], ambiguity: f64) -> (f64, f64) {
    let total: f64 = sample.iter().map(|s| s.1 as f64).sum();
    let outside: f64 = fits.iter().zip(sample).filter(|(f, _)| f.0 > ambiguity).map(|(_, s)| s.1 as f64).sum();
    let mut weighted: Vec<(f64, u32)> = fits.iter().zip(sample).map(|(f, s)| (f.0, s.1)).collect();
    weighted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut seen = 0.0;
    let median = weighted
        .iter()
        .find(|(_, c)| {
            seen += *c as f64;
            seen >= total / 2.0
        })
        .map_or(0.0, |w| w.0);
    // + 0.0: an empty sum is -0.0, which would print as "-0 %".
    (outside / total + 0.0, median)
}

/// The exposure and white-balance gains that bring the most of a texture's texels inside skin's colours (the least
/// share outside, then the least median ΔE00), at the options' extended physiology with each epidermis thickness of
/// `thicknesses_mm` in turn (the gains and the thickness are found together: a thinner epidermis is a redder skin);
/// any gains already in the options are replaced.
pub fn estimate_gains(
    texels: &[[f32; 3]],
    options: &AlbedoFitOptions,
    thicknesses_mm: &[f64],
    cancel: &AtomicBool,
) -> Result<GainEstimate, SkinError> {
    estimate_gains_of_sample(&spread_sample(texels, GAIN_SAMPLE), options, thicknesses_mm, &|_| {}, cancel)
}

/// [`estimate_gains`] on a texture's [`spread_sample`] (distinct colours with their counts; empty: an error), telling
/// `part(f)` the share `f` of the estimate done after each round of fits (and again, the same share, while a table is
/// built), so that a front's progress callback is asked throughout.
pub(crate) fn estimate_gains_of_sample(
    sample: &[([f32; 3], u32)],
    options: &AlbedoFitOptions,
    thicknesses_mm: &[f64],
    part: &(dyn Fn(f64) + Sync),
    cancel: &AtomicBool,
) -> Result<GainEstimate, SkinError> {
    let options = AlbedoFitOptions { rgb_gains: [1.0; 3], ..options.validated()? };
    if sample.is_empty() {
        return Err(SkinError::invalid("albedo texture", "has no texels to estimate gains on"));
    }
    let sampled: usize = sample.iter().map(|s| s.1 as usize).sum();
    let ambiguity = options.ambiguity_delta_e;
    // Progress in rounds of fits: the figures before, then up to GAIN_ROUNDS + 1 per start and thickness.
    let rounds = (1 + 2 * thicknesses_mm.len() * (GAIN_ROUNDS + 1)) as f64;
    let round = std::sync::atomic::AtomicUsize::new(0);
    let at_round = || round.load(std::sync::atomic::Ordering::Relaxed) as f64 / rounds;
    let next_round = || part(round.fetch_add(1, std::sync::atomic::Ordering::Relaxed) as f64 / rounds);
    let tick = || part(at_round());
    let (table, _) = cached_albedo_table_ticking(&options, cancel, Some(&tick))?;
    let (outside_before, median_before) =
        figures(&fit_sample(&table, sample, [1.0; 3], &options, None, cancel)?, sample, ambiguity);
    next_round();
    let conv = *table.converter();
    // Two starts: the texture as it is, and scaled to skin's typical brightness (Y 0.25).
    let mut luminances: Vec<f64> = sample.iter().map(|(c, _)| conv.luminance(c.map(f64::from))).collect();
    luminances.sort_by(f64::total_cmp);
    let median_y = luminances[luminances.len() / 2];
    let scaled = if median_y > 0.0 { (0.25 / median_y).clamp(GAIN_RANGE.0, GAIN_RANGE.1) } else { 1.0 };
    let mut best = ([1.0; 3], options.extended[0], (outside_before, median_before));
    for (k, &thickness) in thicknesses_mm.iter().enumerate() {
        let at = AlbedoFitOptions { extended: [thickness, options.extended[1], options.extended[2]], ..options }
            .validated()?;
        let (table, _) = cached_albedo_table_ticking(&at, cancel, Some(&tick))?;
        for (s, start) in [[1.0; 3], [scaled; 3]].into_iter().enumerate() {
            let (gains, here) = calibrate(&table, sample, start, &at, &next_round, cancel)?;
            if here < best.2 {
                best = (gains, thickness, here);
            }
            // The rounds this start did not need.
            round.store(1 + (2 * k + s + 1) * (GAIN_ROUNDS + 1), std::sync::atomic::Ordering::Relaxed);
        }
    }
    part(1.0);
    let (rgb_gains, epidermis_thickness_mm, (outside_after, median_after)) = best;
    Ok(GainEstimate {
        rgb_gains,
        exposure_stops: (conv.luminance(rgb_gains) / conv.luminance([1.0; 3])).log2(),
        epidermis_thickness_mm,
        outside_share_before: outside_before,
        outside_share_after: outside_after,
        median_delta_e00_before: median_before,
        median_delta_e00_after: median_after,
        sampled_texels: sampled,
    })
}

/// Fit, then solve the gains, from `start`, until they settle: the best gains seen and their figures. The first
/// round fits the colours afresh, each later one refits them from the round before (the gains move little from round
/// to round: [`refit_on_table`]).
fn calibrate(
    table: &AlbedoTable,
    sample: &[([f32; 3], u32)],
    start: [f64; 3],
    options: &AlbedoFitOptions,
    round_done: &dyn Fn(),
    cancel: &AtomicBool,
) -> Result<([f64; 3], (f64, f64)), SkinError> {
    let mut gains = start;
    let mut best: Option<([f64; 3], (f64, f64))> = None;
    let mut previous: Option<Vec<([f64; 3], f64)>> = None;
    for _ in 0..GAIN_ROUNDS {
        let fits = fit_sample(table, sample, gains, options, previous.as_deref(), cancel)?;
        previous = Some(fits.iter().map(|f| f.2).collect());
        round_done();
        let here = figures(&fits, sample, options.ambiguity_delta_e);
        if !matches!(best, Some((_, b)) if b <= here) {
            best = Some((gains, here));
        }
        // Per channel, least squares of gains[c] * colour[c] against the fit's albedo, Cauchy-weighted by ΔE00
        // (scale 2): texels far outside count little.
        let mut next = gains;
        for (c, g) in next.iter_mut().enumerate() {
            let (mut num, mut den) = (0.0, 0.0);
            for ((de, model, _), (colour, count)) in fits.iter().zip(sample) {
                let w = *count as f64 / (1.0 + (de / 2.0).powi(2));
                let a = colour[c] as f64;
                num += w * a * model[c];
                den += w * a * a;
            }
            if den > 0.0 {
                *g = (num / den).clamp(GAIN_RANGE.0, GAIN_RANGE.1);
            }
        }
        let change = next.iter().zip(gains).map(|(a, b)| (a / b).ln().abs()).fold(0.0, f64::max);
        gains = next;
        if change < 1e-3 {
            break;
        }
    }
    let fits = fit_sample(table, sample, gains, options, previous.as_deref(), cancel)?;
    let here = figures(&fits, sample, options.ambiguity_delta_e);
    Ok(match best {
        Some((g, b)) if b <= here => (g, b),
        _ => (gains, here),
    })
}

/// What a fit says about its input when much of it lies far outside skin's colours (`far_texels` farther than
/// [`NOT_ALBEDO_DELTA_E00`], over [`NOT_ALBEDO_SHARE`] of the texels): the share, the likely reasons and the
/// remedies, with `gains` (measured on the texture, when the caller estimated them) stated. None for an input that
/// looks like an albedo.
/// With `applied`, the gains were applied before the fit already, and the message says so.
pub fn not_albedo_diagnosis(
    far_texels: usize,
    texels: usize,
    gains: Option<&GainEstimate>,
    applied: bool,
) -> Option<String> {
    let share = far_texels as f64 / texels.max(1) as f64;
    if share <= NOT_ALBEDO_SHARE {
        return None;
    }
    let remedy = match gains {
        Some(g) if applied => format!(
            "exposure and white-balance gains were estimated and applied already (R G B x {:.3} {:.3} {:.3}): what is \
             left is not a global light",
            g.rgb_gains[0], g.rgb_gains[1], g.rgb_gains[2]
        ),
        Some(g) => format!(
            "exposure and white-balance gains measured on it, R G B x {:.3} {:.3} {:.3} ({:+.2} stops), bring the share \
             of sampled texels outside skin's colours (ΔE00 over 0.5) from {:.0} % to {:.0} % (median ΔE00 {:.2} -> \
             {:.2}): apply them",
            g.rgb_gains[0],
            g.rgb_gains[1],
            g.rgb_gains[2],
            g.exposure_stops,
            100.0 * g.outside_share_before,
            100.0 * g.outside_share_after,
            g.median_delta_e00_before,
            g.median_delta_e00_after
        ),
        None => "estimate exposure and white-balance gains and apply them".to_string(),
    };
    Some(format!(
        "{far_texels} of {texels} texels ({:.0} %) are more than {NOT_ALBEDO_DELTA_E00} ΔE00 from every colour skin can \
         have: this does not look like an albedo texture. Likely: a photograph (its light's exposure and colour, shading and highlights are in the \
         colours), parts that are not skin (hair, eyes, background), a working space other than the texture's, or an \
         extended value held (an epidermis thickness) that the skin does not have. \
         Remedies: {remedy}; fit only the skin (a mask); check the working space. The residual map shows where.",
        100.0 * share
    ))
}
