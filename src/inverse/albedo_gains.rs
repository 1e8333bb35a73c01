//! When a texture is not an albedo: the share of its texels outside skin's colours ([`outside_skin`]), the likely
//! reason, and the remedy measured on the texture: the exposure and white-balance gains (one factor per RGB channel)
//! that bring the most texels inside skin's colours, the exposure changed only as far as that pays.
//!
//! A photograph is lit: its colours are the albedo times the light (exposure, the light's colour when the camera's
//! white balance did not remove it) and shading. Gains undo the global part. They are found like a colour
//! calibration against the model: fit each sampled colour (times the gains) on the forward table, then solve the
//! per-channel least-squares gains that map the colours onto their fits' albedos (robustly weighted, so texels far
//! outside, such as hair or background, count little), and repeat. The gains cannot tell an exposure from melanin (a
//! darker photo of fair skin is a brighter photo of darker skin): they bring the texture inside skin's colours, they
//! do not prove its physiology. So the estimate changes the exposure only where that brings enough texels inside
//! ([`EXPOSURE_PRICE_PER_STOP`]): a texture inside skin's colours but for a minority (highlights, shading) keeps its
//! exposure, and its melanin.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use super::albedo::{
    cached_albedo_table_ticking, colour_key, fit_on_table_costed, refit_on_table, AlbedoFitOptions, AlbedoTable,
    GAIN_RANGE,
};
use crate::color::difference::LabConverter;
use crate::error::SkinError;

/// A texel farther than this (ΔE00) from every colour skin can have is outside skin's colours: plainly not skin's
/// albedo (the fit's own residual on measured albedos stays under it for 9 texels in 10: docs/skin-atlas.md, "When the
/// input is not an albedo"). The one definition of the count a fit reports ([`outside_skin`],
/// `AlbedoMapStats::outside_skin_texels`) and its diagnosis judges.
pub const OUTSIDE_SKIN_DELTA_E00: f64 = 2.0;
/// Above this share of texels outside skin's colours ([`OUTSIDE_SKIN_DELTA_E00`]), a fit reports that the input does
/// not look like an albedo: 200 measured albedos of eight ethnic groups in one texture have under 10 % there, a
/// simulated photograph under a tungsten lamp all of them.
pub const NOT_ALBEDO_SHARE: f64 = 0.25;
/// Texels the gains are estimated on (spread evenly over the texture; each distinct colour fitted once).
pub const GAIN_SAMPLE: usize = 2048;
/// Rounds of fit-then-solve per thickness; the gains settle in 5 to 10 on the textures tried.
const GAIN_ROUNDS: usize = 16;
/// A texture whose sampled texels are all reproduced (ΔE00 within the ambiguity) without gains but for this share
/// needs none, and gets none without a calibration: the standard error of a share measured on [`GAIN_SAMPLE`]
/// texels is up to sqrt(0.25 / 2048) = 1.1 %.
const GAIN_SHARE_TOLERANCE: f64 = 0.01;
/// What a stop of exposure costs the gains, in the units of their figures on the sample (the share not reproduced
/// plus the mean Cauchy cost, [`Candidate::cost`]). Inside skin's colours a darker exposure costs nothing (a darker
/// photograph of fair skin is a brighter one of darker skin), so without a price any minority that a darker exposure
/// brings inside (highlights, the bright side of the shading) moved the whole texture's exposure into melanin: a
/// well-exposed fair face with highlights on 5 % of its texels went 0.5 stops darker with three times its melanin
/// (tests/inverse/inverse_gains.rs; docs/skin-atlas.md, "The gains"). Of the prices tried (0.25, 0.5 and 1 per stop)
/// the least at which that face keeps its exposure (-0.03 stops; at 0.25, -0.13); a texture every texel of which is
/// 4 ΔE00 outside still pays for a correction of up to 2 (1 + ln 5) = 5.2 stops.
pub const EXPOSURE_PRICE_PER_STOP: f64 = 0.5;

/// Whether a texel `delta_e00` from the nearest skin colour is outside skin's colours ([`OUTSIDE_SKIN_DELTA_E00`]).
pub fn outside_skin(delta_e00: f64) -> bool {
    delta_e00 > OUTSIDE_SKIN_DELTA_E00
}

/// Gains found for a texture ([`estimate_gains`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GainEstimate {
    /// Per linear-RGB channel of the working space: multiply the texture by these before the fit.
    pub rgb_gains: [f64; 3],
    /// The exposure part, in stops: log2 of the gains' effect on luminance (Y).
    pub exposure_stops: f64,
    /// The epidermis thickness the gains were found with (the fit may still choose another for the gained texture).
    pub epidermis_thickness_mm: f64,
    /// Median ΔE00 of the sampled texels before and after.
    pub median_delta_e00_before: f64,
    pub median_delta_e00_after: f64,
    pub sampled_texels: usize,
}

/// Texels spread evenly over `texels` (the golden-ratio sequence), as distinct colours with their counts.
pub(crate) fn spread_sample(texels: &[[f32; 3]], count: usize) -> Vec<([f32; 3], u32)> {
    spread_sample_of(texels.len(), count, |i| texels[i])
}

/// [`spread_sample`] of the `n` texels `texel(0)`, ..., `texel(n - 1)` (none: an empty sample). Colours that share a
/// cache key of the texture fit ([`colour_key`]: within one step of 10-bit sRGB) are one colour, the first drawn.
pub(crate) fn spread_sample_of(n: usize, count: usize, texel: impl Fn(usize) -> [f32; 3]) -> Vec<([f32; 3], u32)> {
    let mut seen: HashMap<[u32; 3], ([f32; 3], u32)> = HashMap::new();
    for k in 0..count.min(n * 4) {
        let t = texel(crate::numeric::golden_index(k, n));
        seen.entry(colour_key(&t)).or_insert((t, 0)).1 += 1;
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
    previous: Option<&[SampleFit]>,
    cancel: &AtomicBool,
) -> Result<Vec<SampleFit>, SkinError> {
    sample
        .par_iter()
        .enumerate()
        .map(|(i, (c, _))| {
            SkinError::check_cancel(cancel, "gain estimate")?;
            let target = [0, 1, 2].map(|k| c[k] as f64 * gains[k]);
            let (u, de, cost) = match previous {
                Some(previous) => refit_on_table(table, target, options, previous[i].2),
                None => fit_on_table_costed(table, target, options),
            };
            Ok((de, table.albedo(u), (u, cost)))
        })
        .collect()
}

/// A fitted sample's figures, each weighted by the colours' counts.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Figures {
    /// Share not reproduced: farther than the ambiguity ΔE00.
    missed_share: f64,
    median_delta_e00: f64,
    /// Mean Cauchy cost ln(1 + (ΔE00 / 2)²): what [`solved_gains`]' reweighted least squares lower, and how far the
    /// texels not reproduced are.
    robust_cost: f64,
}

fn figures(fits: &[SampleFit], sample: &[([f32; 3], u32)], ambiguity: f64) -> Figures {
    let total: f64 = sample.iter().map(|s| s.1 as f64).sum();
    let missed: f64 = fits.iter().zip(sample).filter(|(f, _)| f.0 > ambiguity).map(|(_, s)| s.1 as f64).sum();
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
    let robust: f64 = fits.iter().zip(sample).map(|(f, s)| (1.0 + (f.0 / 2.0).powi(2)).ln() * s.1 as f64).sum();
    // + 0.0: an empty sum is -0.0.
    Figures { missed_share: missed / total + 0.0, median_delta_e00: median, robust_cost: robust / total + 0.0 }
}

/// Gains tried on the sample: at which epidermis thickness, and their figures there.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    gains: [f64; 3],
    thickness_mm: f64,
    figures: Figures,
}

impl Candidate {
    /// The exposure part, in stops: log2 of the gains' effect on luminance (Y) in `conv`'s working space.
    fn exposure_stops(&self, conv: &LabConverter) -> f64 {
        (conv.luminance(self.gains) / conv.luminance([1.0; 3])).log2()
    }

    /// What the estimate lowers: the share of sampled texels not reproduced, their mean Cauchy cost (how far they
    /// are) and the exposure's price ([`EXPOSURE_PRICE_PER_STOP`]).
    fn cost(&self, conv: &LabConverter) -> f64 {
        let f = self.figures;
        f.missed_share + f.robust_cost + EXPOSURE_PRICE_PER_STOP * self.exposure_stops(conv).abs()
    }
}

/// The candidate of least [`Candidate::cost`] (the first such, no gains, on a tie).
fn cheapest(candidates: &[Candidate], conv: &LabConverter) -> Candidate {
    *candidates.iter().min_by(|a, b| a.cost(conv).total_cmp(&b.cost(conv))).expect("no gains is a candidate")
}

/// The exposure and white-balance gains that bring the most of a texture's texels inside skin's colours, the exposure
/// changed only as far as that pays ([`EXPOSURE_PRICE_PER_STOP`]), at the options' extended physiology with each
/// epidermis thickness of `thicknesses_mm` in turn (the gains and the thickness are found together: a thinner
/// epidermis is a redder skin); any gains already in the options are replaced.
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
/// built), so that a front's progress callback is asked throughout. A sample whose colours are reproduced without
/// gains at the options' thickness (all but [`GAIN_SHARE_TOLERANCE`] of it) needs none: one pass of fits.
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
    // Progress in thicknesses: the figures before, then one calibration per thickness.
    let steps = (1 + thicknesses_mm.len()) as f64;
    let step = AtomicUsize::new(0);
    let tick = || part(step.load(Ordering::Relaxed) as f64 / steps);
    let (table, _) = cached_albedo_table_ticking(&options, cancel, Some(&tick))?;
    let before = fit_sample(&table, sample, [1.0; 3], &options, None, cancel)?;
    let figures_before = figures(&before, sample, options.ambiguity_delta_e);
    part(step.fetch_add(1, Ordering::Relaxed) as f64 / steps);
    let none = Candidate { gains: [1.0; 3], thickness_mm: options.extended[0], figures: figures_before };
    let mut candidates = vec![none];
    if figures_before.missed_share > GAIN_SHARE_TOLERANCE {
        // Two starts: the texture as it is, and scaled to skin's typical brightness, whose gains win only where they
        // bring enough more texels inside to pay for their exposure.
        let starts = [[1.0; 3], [typical_brightness_gain(sample, table.converter()); 3]];
        let mut before = Some(before);
        for &thickness in thicknesses_mm {
            let at = AlbedoFitOptions { extended: [thickness, options.extended[1], options.extended[2]], ..options }
                .validated()?;
            let (table, _) = cached_albedo_table_ticking(&at, cancel, Some(&tick))?;
            for start in starts {
                // The fits without gains at the options' own thickness are those made above.
                let first = match before.take_if(|_| thickness == options.extended[0] && start == [1.0; 3]) {
                    Some(fits) => fits,
                    None => fit_sample(&table, sample, start, &at, None, cancel)?,
                };
                candidates.extend(calibrate(&table, sample, (start, first), &at, &tick, cancel)?);
            }
            part(step.fetch_add(1, Ordering::Relaxed) as f64 / steps);
        }
    }
    part(1.0);
    let conv = *table.converter();
    let chosen = cheapest(&candidates, &conv);
    Ok(GainEstimate {
        rgb_gains: chosen.gains,
        exposure_stops: chosen.exposure_stops(&conv),
        epidermis_thickness_mm: chosen.thickness_mm,
        median_delta_e00_before: figures_before.median_delta_e00,
        median_delta_e00_after: chosen.figures.median_delta_e00,
        sampled_texels: sample.iter().map(|s| s.1 as usize).sum(),
    })
}

/// The gain that brings the sample's median luminance (Y) to 0.25, a typical skin's, within [`GAIN_RANGE`] (1 for a
/// black sample): a second start for a photograph far from skin's colours.
fn typical_brightness_gain(sample: &[([f32; 3], u32)], conv: &LabConverter) -> f64 {
    let mut luminances: Vec<f64> = sample.iter().map(|(c, _)| conv.luminance(c.map(f64::from))).collect();
    luminances.sort_by(f64::total_cmp);
    let median_y = luminances[luminances.len() / 2];
    if median_y > 0.0 {
        (0.25 / median_y).clamp(GAIN_RANGE.0, GAIN_RANGE.1)
    } else {
        1.0
    }
}

/// Fit, then solve the gains, from `start` (`first`: the sample fitted with them), until they settle: every round's
/// gains with its figures, for [`cheapest`]. Each round refits the colours from the round before (the gains move
/// little from round to round: [`refit_on_table`]).
fn calibrate(
    table: &AlbedoTable,
    sample: &[([f32; 3], u32)],
    (start, first): ([f64; 3], Vec<SampleFit>),
    options: &AlbedoFitOptions,
    round_done: &dyn Fn(),
    cancel: &AtomicBool,
) -> Result<Vec<Candidate>, SkinError> {
    let mut gains = start;
    let mut fits = first;
    let mut tried = Vec::with_capacity(GAIN_ROUNDS);
    for round in 0..GAIN_ROUNDS {
        let figures = figures(&fits, sample, options.ambiguity_delta_e);
        tried.push(Candidate { gains, thickness_mm: options.extended[0], figures });
        let next = solved_gains(&fits, sample, gains);
        let change = next.iter().zip(gains).map(|(a, b)| (a / b).ln().abs()).fold(0.0, f64::max);
        if change < 1e-3 || round + 1 == GAIN_ROUNDS {
            break;
        }
        gains = next;
        fits = fit_sample(table, sample, gains, options, Some(&fits), cancel)?;
        round_done();
    }
    Ok(tried)
}

/// Per channel, the least squares of gain × colour against the fit's albedo, Cauchy-weighted by ΔE00 (scale 2:
/// texels far outside count little), each kept in [`GAIN_RANGE`] (`gains`' where no texel has that channel).
fn solved_gains(fits: &[SampleFit], sample: &[([f32; 3], u32)], gains: [f64; 3]) -> [f64; 3] {
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
    next
}

/// What a fit says about its input when much of it lies outside skin's colours (`outside_texels` of `texels`,
/// [`outside_skin`], over [`NOT_ALBEDO_SHARE`] of them): the count, the likely reasons and the remedies, with `gains`
/// (measured on the texture, when the caller estimated them) stated. None for an input that looks like an albedo.
/// With `applied`, the gains were applied before the fit already, and the message says so.
pub fn not_albedo_diagnosis(
    outside_texels: usize,
    texels: usize,
    gains: Option<&GainEstimate>,
    applied: bool,
) -> Option<String> {
    let share = outside_texels as f64 / texels.max(1) as f64;
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
            "exposure and white-balance gains measured on it, R G B x {:.3} {:.3} {:.3} ({:+.2} stops), bring the \
             median ΔE00 of {} sampled texels from {:.2} to {:.2}: apply them",
            g.rgb_gains[0],
            g.rgb_gains[1],
            g.rgb_gains[2],
            g.exposure_stops,
            g.sampled_texels,
            g.median_delta_e00_before,
            g.median_delta_e00_after
        ),
        None => "estimate exposure and white-balance gains and apply them".to_string(),
    };
    Some(format!(
        "{outside_texels} of {texels} texels ({:.0} %) are outside skin's colours (more than {OUTSIDE_SKIN_DELTA_E00} \
         ΔE00 from every colour skin can have): this does not look like an albedo texture. Likely: a photograph (its \
         light's exposure and colour, shading and highlights are in the colours), parts that are not skin (hair, eyes, \
         background), a working space other than the texture's, or an extended value held (an epidermis thickness) \
         that the skin does not have. Remedies: {remedy}; fit only the skin (a mask); check the working space. The \
         residual map shows where.",
        100.0 * share
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::WorkingSpace;

    fn candidate(gains: [f64; 3], missed_share: f64) -> Candidate {
        Candidate {
            gains,
            thickness_mm: 0.25,
            figures: Figures { missed_share, median_delta_e00: 0.0, robust_cost: 0.0 },
        }
    }

    /// Half a stop darker (a gain of 2^-0.5 on every channel) is priced at a quarter: it does not pay for bringing a
    /// highlight's 5 % inside, and does for a photograph whose every texel it brings inside; a white balance that keeps
    /// the luminance costs nothing.
    #[test]
    fn an_exposure_pays_only_for_enough_texels() {
        let conv = LabConverter::new(WorkingSpace::LinearRec709);
        let darker = [0.5f64.sqrt(); 3];
        assert!((candidate(darker, 0.0).exposure_stops(&conv) + 0.5).abs() < 1e-12);
        assert_eq!(cheapest(&[candidate([1.0; 3], 0.05), candidate(darker, 0.0)], &conv).gains, [1.0; 3]);
        assert_eq!(cheapest(&[candidate([1.0; 3], 1.0), candidate(darker, 0.0)], &conv).gains, darker);
        // R x 1.2 and B x 0.6 with G keeping the luminance (ITU-R BT.709 weights 0.2126, 0.7152, 0.0722: the working
        // space's own, to four digits).
        let g = (1.0 - 0.2126 * 1.2 - 0.0722 * 0.6) / 0.7152;
        let balance = [1.2, g, 0.6];
        assert!(candidate(balance, 0.0).exposure_stops(&conv).abs() < 1e-4);
        assert_eq!(cheapest(&[candidate([1.0; 3], 0.01), candidate(balance, 0.0)], &conv).gains, balance);
    }
}
