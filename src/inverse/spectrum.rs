//! Fitting the model to a measured reflectance spectrum (docs/measured-skin.md).
//!
//! The forward model is the model's total diffuse reflectance at the measured wavelengths
//! ([`crate::evaluate::diffuse_reflectance_at`]) plus a constant surface reflection ([`Specular`]): a spectrophotometer
//! with an integrating sphere (d/8 geometry, specular component included) sees the light the skin's surface reflects
//! as well as the light that entered it, and the model's diffuse reflectance holds only the latter.
//!
//! The fit is bounded (each parameter inside its [`PARAMS`] range) and global: every spectrum of a coarse table over
//! the free parameters is compared with the measurement (with its best offset), and the best start(s) are refined by
//! a bounded Levenberg-Marquardt ([`super::lm`]). The table depends on the wavelengths and on what is fixed, not on the
//! measurement: [`SpectrumFitter`] builds it once for many spectra.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::aperture::{Aperture, ApertureKernel};
use super::bandpass::{Bandpass, Sampling};
use super::lm::{minimize, LmResult, LmSettings};
use crate::color::spectrum::VISIBLE_RANGE_NM;
use crate::color::{ciede2000, lab_from_xyz, spectrum_to_xyz, WavelengthGrid};
use crate::error::SkinError;
use crate::evaluate::{diffuse_reflectance_at, Request};
use crate::skin::optics::{skin_layers, SkinModel, EPIDERMAL_HEMOGLOBIN, SKIN_IOR};
use crate::skin::params::{ParamSpec, SkinParams, OILINESS, PARAMS, PARAM_COUNT};
use crate::transport::profile_table::exact_shape;

/// The paper's parameters that change the diffuse reflectance (the oiliness scales only the specular lobe).
pub const PAPER_FREE: [&str; 3] = ["melanin", "melanin_blend", "hemoglobin"];

/// The parameters [`fit_spectrum`] fits unless told otherwise: the paper's three and the epidermis thickness and
/// the baseline absorption scale (the choice and its figures: docs/measured-skin.md).
pub const DEFAULT_FREE: [&str; 5] =
    ["melanin", "melanin_blend", "hemoglobin", "epidermis_thickness_mm", "baseline_absorption_scale"];

/// The model options a fit can free beside the parameters ([`PARAMS`] but the oiliness), by the same names: the
/// blood in the epidermis ([`SkinModel::epidermal_hemoglobin`](crate::skin::optics::SkinModel); docs/measured-skin.md,
/// Blood in the epidermis). Not free, each takes the value of [`FitOptions::request`]'s model.
pub const MODEL_FREE: [ParamSpec; 1] = [EPIDERMAL_HEMOGLOBIN];

/// What a fit can hold or free: the parameters in [`PARAMS`] order, then [`MODEL_FREE`].
const QUANTITIES: usize = PARAM_COUNT + MODEL_FREE.len();

/// The spec of quantity `k` ([`QUANTITIES`]).
fn quantity(k: usize) -> ParamSpec {
    if k < PARAM_COUNT {
        PARAMS[k]
    } else {
        MODEL_FREE[k - PARAM_COUNT]
    }
}

/// The number of start-table entries [`fit_spectrum`] refines by default: one start alone misses the best fit of
/// the default set on about 15 % of measured spectra, by up to 0.008 RMS (docs/measured-skin.md, the restart check).
pub const DEFAULT_STARTS: usize = 4;
/// The most table starts refined: beyond a few the restarts find nothing new (docs/measured-skin.md), and each is a
/// local fit of up to hundreds of forward spectra, minutes at 64 streams on a fine spectrum.
pub const MAX_STARTS: usize = 64;

/// The bandpass [`fit_spectrum`] assumes unless told otherwise: 1.5 times the wavelength spacing (the Q-band study
/// of docs/measured-skin.md, Instrument bandpass); `Bandpass::FwhmNm(0.0)` is the fit before (the model sampled at the
/// measured wavelengths).
pub const DEFAULT_BANDPASS: Bandpass = Bandpass::Spacing;

/// The oiliness a fit reports when none is given: the value of all three DJ2006 presets (it does not change the
/// diffuse reflectance, so a spectrum cannot tell it).
pub const DEFAULT_OILINESS: f64 = 0.3;

/// Normal-incidence Fresnel reflectance of the skin surface, ((n - 1) / (n + 1))^2 with n = [`SKIN_IOR`] (1.4):
/// 0.0278. A d/8 instrument views at 8°, where the Fresnel reflectance differs from this by under 0.1 %.
pub const FRESNEL_NORMAL_REFLECTANCE: f64 =
    ((SKIN_IOR - 1.0) / (SKIN_IOR + 1.0)) * ((SKIN_IOR - 1.0) / (SKIN_IOR + 1.0));

/// The range of a fitted or given surface-reflection offset: none up to 0.1 (3.6 times the Fresnel reflectance of a
/// smooth n = 1.4 surface; more would be a glossy coating, not skin).
pub const SPECULAR_OFFSET_RANGE: (f64, f64) = (0.0, 0.1);

/// How the surface reflection in a measured spectrum is modelled: a constant added to the model's diffuse reflectance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Specular {
    /// Fitted, within [`SPECULAR_OFFSET_RANGE`] (the default; docs/measured-skin.md says why).
    #[default]
    Free,
    /// [`FRESNEL_NORMAL_REFLECTANCE`]: a smooth surface of index 1.4, specular component included.
    Fresnel,
    /// A given constant (0 for a measurement with the specular component excluded).
    Fixed(f64),
}

impl Specular {
    /// The name the fronts use: "free", "fresnel" or "fixed".
    pub fn name(&self) -> &'static str {
        match self {
            Specular::Free => "free",
            Specular::Fresnel => "fresnel",
            Specular::Fixed(_) => "fixed",
        }
    }
}

/// What the fit minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// The sum of squared reflectance differences over the wavelengths.
    #[default]
    Reflectance,
    /// The squared CIELAB difference (D65, CIE 1931 2°) of the spectra's colours, plus the reflectance differences
    /// unscaled, which only break ties between spectra of one colour (an RMS of 0.01 over 31 wavelengths weighs as a
    /// ΔE*ab of 0.06).
    Cielab,
}

/// Every objective, in the order the docs list them.
pub const ALL_OBJECTIVES: [Objective; 2] = [Objective::Reflectance, Objective::Cielab];

/// What to fit and how.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// The free parameters, by name ([`PARAMS`] but the oiliness, and [`MODEL_FREE`]).
    pub free: Vec<String>,
    /// Values of parameters that are not free, in [`PARAMS`] order; None takes the parameter's default (the paper's
    /// value of an extended parameter, [`DEFAULT_OILINESS`]); one of the paper's three without a default must be given
    /// if it is not free.
    pub fixed: [Option<f64>; PARAM_COUNT],
    pub specular: Specular,
    pub objective: Objective,
    /// The instrument's spectral bandpass the model spectrum is averaged over before it is compared with the
    /// measurement ([`Bandpass`]; docs/measured-skin.md, Instrument bandpass).
    pub bandpass: Bandpass,
    /// The instrument's lit and measured discs, if the light the skin carries out of the measured one is modelled
    /// ([`Aperture`]; docs/measured-skin.md, Instrument aperture): the model's diffuse reflectance at each wavelength
    /// times the fraction of it that leaves inside the measured disc (from the exact radial profile). None (the
    /// default): the total, an aperture large against the light's spread.
    pub aperture: Option<Aperture>,
    /// How many of the table's best starts are refined (the best result is kept); the default 4 leaves little for
    /// more starts to find on the measured skin spectra (docs/measured-skin.md, the restart check).
    pub starts: usize,
    /// The model choices (transport and its streams, model, combination, boundaries, multipole terms); outputs and
    /// wavelength grid unused.
    pub request: Request,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            free: DEFAULT_FREE.iter().map(|s| s.to_string()).collect(),
            fixed: [None; PARAM_COUNT],
            specular: Specular::Free,
            objective: Objective::Reflectance,
            bandpass: DEFAULT_BANDPASS,
            aperture: None,
            starts: DEFAULT_STARTS,
            request: Request::default(),
        }
    }
}

/// The result of a fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectrumFit {
    /// Every model parameter, fitted and fixed.
    pub params: SkinParams,
    /// The blood in the epidermis the fitted spectrum was computed with ([`SkinModel::epidermal_hemoglobin`]
    /// (crate::skin::optics::SkinModel)): fitted when free, else the request's model's (0, DJ2006's, by default).
    /// `params` and the request's model with this value reproduce `fitted_reflectance`.
    pub epidermal_hemoglobin: f64,
    /// The model the fitted spectrum was computed with: the request's options, those freed at their fitted values
    /// (`epidermal_hemoglobin` above among them). `params` and this model reproduce `fitted_reflectance`
    /// (`evaluate(**fit["params"], model=fit["model"])` in Python).
    pub model: SkinModel,
    /// The names of the fitted ones.
    pub free: Vec<&'static str>,
    /// "free", "fresnel" or "fixed".
    pub specular: &'static str,
    /// The surface reflection added to the model's diffuse reflectance.
    pub specular_offset: f64,
    pub objective: Objective,
    pub wavelengths_nm: Vec<f64>,
    /// "spacing" or "fwhm" ([`Bandpass`]) and the bandpass (FWHM, nm) at each wavelength; 0: the model sampled there.
    pub bandpass: &'static str,
    pub bandpass_nm: Vec<f64>,
    /// The instrument's discs the model's reflectance was measured through, if modelled ([`FitOptions::aperture`]).
    pub aperture: Option<Aperture>,
    /// The model's diffuse reflectance (averaged over the bandpass) plus the offset, at `wavelengths_nm`: what was
    /// compared with the measurement.
    pub fitted_reflectance: Vec<f64>,
    /// Root-mean-square difference of `fitted_reflectance` and the measurement.
    pub rms: f64,
    /// CIEDE2000 difference of their colours (D65, CIE 1931 2°; each spectrum held constant beyond its ends).
    pub delta_e00: f64,
    /// CIELAB of the measurement and of the fit.
    pub lab_measured: [f64; 3],
    pub lab_fitted: [f64; 3],
    /// Local refinements run (table starts) and forward spectra computed in them.
    pub starts: usize,
    pub evaluations: usize,
    /// How the model's totals were computed (`FitOptions::request`'s transport) and the adding-doubling streams.
    pub transport: crate::transport::Transport,
    pub streams: usize,
}

/// The solver's unknowns: every quantity but the oiliness (a fit frees each at most once) and the offset; a fit with
/// fewer holds the rest (`lm::minimize`: equal bounds, no evaluation).
const UNKNOWNS: usize = QUANTITIES;

/// One spectrum of the start table: the free parameters' values and the diffuse spectrum there.
type StartSpectrum = (Vec<f64>, Vec<f64>);

/// A fitter for spectra on one wavelength grid with one set of options: the validated options, the colour weights
/// and the table of forward spectra the starts come from.
#[derive(Debug, Clone)]
pub struct SpectrumFitter {
    wavelengths_nm: Vec<f64>,
    /// The bandpass at each wavelength and the model's wavelengths it averages over.
    bandpass_nm: Vec<f64>,
    sampling: Sampling,
    /// The aperture's quadrature, if one is modelled.
    aperture: Option<ApertureKernel>,
    options: FitOptions,
    /// Indices of the free quantities ([`quantity`]).
    free: Vec<usize>,
    /// Every quantity's value, the free ones at the middle of their grid (replaced in each evaluation).
    base: [f64; QUANTITIES],
    xyz_weights: Vec<[f64; 3]>,
    white_xyz: [f64; 3],
    /// (free parameter values, diffuse spectrum) for the coarse start.
    table: Vec<StartSpectrum>,
}

/// The start table's values of a parameter: spread over the range where measured skin lies, denser where the
/// reflectance changes fastest (small melanin, blood and thickness).
fn table_values(name: &str) -> &'static [f64] {
    match name {
        "melanin" => &[0.002, 0.006, 0.015, 0.03, 0.06, 0.12, 0.25, 0.45],
        "melanin_blend" => &[0.0, 0.25, 0.5, 0.75, 1.0],
        "hemoglobin" => &[0.001, 0.004, 0.01, 0.025, 0.06],
        "epidermis_thickness_mm" => &[0.02, 0.05, 0.1, 0.2, 0.4],
        "baseline_absorption_scale" => &[0.25, 1.0, 2.5, 6.0],
        "blood_oxygenation" => &[0.2, 0.5, 0.8, 1.0],
        "epidermal_hemoglobin" => &[0.0, 0.01],
        _ => &[],
    }
}

impl SpectrumFitter {
    /// Validate the wavelengths and options and build the start table.
    pub fn new(wavelengths_nm: &[f64], options: &FitOptions) -> Result<SpectrumFitter, SkinError> {
        SpectrumFitter::new_cancellable(wavelengths_nm, options, &AtomicBool::new(false))
    }

    /// [`SpectrumFitter::new`] whose table build (up to 16,000 forward spectra) stops once `cancel` is set, with
    /// [`SkinError::interrupted`].
    pub fn new_cancellable(
        wavelengths_nm: &[f64],
        options: &FitOptions,
        cancel: &AtomicBool,
    ) -> Result<SpectrumFitter, SkinError> {
        check_wavelengths(wavelengths_nm)?;
        let mut free = Vec::new();
        for name in &options.free {
            let Some(index) = (0..QUANTITIES).find(|&k| quantity(k).name == name) else {
                let names: Vec<&str> =
                    (0..QUANTITIES).map(|k| quantity(k).name).filter(|n| *n != OILINESS.name).collect();
                return Err(SkinError::invalid(
                    "free",
                    format!("unknown parameter {name:?}; the parameters that can be fitted: {}", names.join(", ")),
                ));
            };
            if quantity(index).name == OILINESS.name {
                return Err(SkinError::invalid(
                    "free",
                    "oiliness cannot be fitted: it scales the specular lobe only, not the diffuse reflectance",
                ));
            }
            if free.contains(&index) {
                return Err(SkinError::invalid("free", format!("{name} is listed twice")));
            }
            if options.fixed.get(index).is_some_and(Option::is_some) {
                return Err(SkinError::invalid("fixed", format!("{name} is free and cannot have a fixed value too")));
            }
            if index >= PARAM_COUNT
                && Some(model_values(&options.request)[index - PARAM_COUNT]) != quantity(index).default
            {
                return Err(SkinError::invalid(
                    "free",
                    format!("{name} is free and cannot have a value in the request's model too"),
                ));
            }
            free.push(index);
        }
        if free.is_empty() {
            return Err(SkinError::invalid("free", "no parameter to fit"));
        }
        if wavelengths_nm.len() < free.len() + 1 {
            return Err(SkinError::invalid(
                "wavelengths_nm",
                format!(
                    "{} wavelengths cannot determine {} free parameters and the offset",
                    wavelengths_nm.len(),
                    free.len()
                ),
            ));
        }
        let mut base = [0.0; QUANTITIES];
        for (i, spec) in (0..QUANTITIES).map(|k| (k, quantity(k))) {
            base[i] = if free.contains(&i) {
                let values = table_values(spec.name);
                values[values.len() / 2]
            } else if i >= PARAM_COUNT {
                model_values(&options.request)[i - PARAM_COUNT]
            } else if let Some(v) = options.fixed[i] {
                spec.check(v)?
            } else if spec.name == OILINESS.name {
                DEFAULT_OILINESS
            } else if let Some(d) = spec.default {
                d
            } else {
                return Err(SkinError::invalid(
                    "fixed",
                    format!("{} is not free, so it needs a fixed value ({})", spec.name, spec.summary()),
                ));
            };
        }
        if let Specular::Fixed(v) = options.specular {
            let (lo, hi) = SPECULAR_OFFSET_RANGE;
            crate::error::check_range("specular", "surface reflection added to the diffuse reflectance", v, lo, hi)?;
        }
        if !(1..=MAX_STARTS).contains(&options.starts) {
            return Err(SkinError::invalid(
                "starts",
                format!(
                    "must be 1 to {MAX_STARTS} (table starts refined, each a local fit of many forward spectra); got {}",
                    options.starts
                ),
            ));
        }
        crate::transport::adding_doubling::validate_streams(options.request.accuracy.streams)?;
        crate::evaluate::validate_model(&options.request.model)?;
        let aperture = match options.aperture {
            Some(a) => {
                a.validate()?;
                if options.request.transport != crate::transport::Transport::AddingDoubling {
                    return Err(SkinError::invalid(
                        "aperture",
                        "the aperture needs the exact radial profile: transport adding_doubling",
                    ));
                }
                if options.request.model.dermis_thickness_mm.is_finite() {
                    return Err(SkinError::invalid(
                        "aperture",
                        "the aperture needs the exact radial profile, which is tabulated for a semi-infinite dermis \
                         only (dermis_thickness_mm = infinity)",
                    ));
                }
                Some(a.kernel())
            }
            None => None,
        };
        let bandpass_nm = options.bandpass.widths_nm(wavelengths_nm)?;
        let sampling = Sampling::new(wavelengths_nm, &bandpass_nm);
        let grid = WavelengthGrid { wavelengths_nm: wavelengths_nm.to_vec() };
        let xyz_weights = grid.xyz_weights();
        let white_xyz = spectrum_to_xyz(&vec![1.0; wavelengths_nm.len()], &xyz_weights);
        let mut fitter = SpectrumFitter {
            wavelengths_nm: wavelengths_nm.to_vec(),
            bandpass_nm,
            sampling,
            aperture,
            options: options.clone(),
            free,
            base,
            xyz_weights,
            white_xyz,
            table: Vec::new(),
        };
        fitter.table = fitter.build_table(cancel)?;
        // A forward spectrum cut short by the flag is missing from the table, not an error: read the flag once more.
        SkinError::check_cancel(cancel, "fit_spectrum's start table")?;
        if fitter.table.is_empty() {
            return Err(SkinError::invalid("fixed", "the fixed values leave no valid forward spectrum"));
        }
        Ok(fitter)
    }

    /// The model's diffuse reflectance with the free parameters at `x`, averaged over the instrument's bandpass at
    /// each measured wavelength (None if the model rejects them, or once `cancel` is set: the callers read it again
    /// after).
    fn forward(&self, x: &[f64], cancel: &AtomicBool) -> Option<Vec<f64>> {
        let v = self.values_at(x);
        let params = params_of(&v).ok()?;
        let request = with_model_values(self.options.request, &v[PARAM_COUNT..]);
        let mut at_nodes = diffuse_reflectance_at(&params, &request, &self.sampling.nodes_nm, cancel).ok()?;
        if let Some(kernel) = &self.aperture {
            // What the instrument measures at a node: the reflectance times the fraction leaving inside its measured
            // disc, averaged over the bandpass below. A stack the profile table does not hold (an epidermis over 10
            // mean free paths thick) is rejected.
            let model = &request.model;
            let shape_at = |nm: f64| exact_shape(&skin_layers(&params, model, nm));
            let fractions = kernel.fractions(&self.sampling.nodes_nm, shape_at)?;
            at_nodes.iter_mut().zip(fractions).for_each(|(r, f)| *r *= f);
        }
        Some(self.sampling.apply(&at_nodes))
    }

    /// Every quantity's value with the free ones at `x`.
    fn values_at(&self, x: &[f64]) -> [f64; QUANTITIES] {
        let mut v = self.base;
        for (&k, &value) in self.free.iter().zip(x) {
            v[k] = value;
        }
        v
    }

    fn build_table(&self, cancel: &AtomicBool) -> Result<Vec<StartSpectrum>, SkinError> {
        let axes: Vec<&[f64]> = self.free.iter().map(|&k| table_values(quantity(k).name)).collect();
        let count: usize = axes.iter().map(|a| a.len()).product();
        let spectra: Vec<Option<StartSpectrum>> = (0..count)
            .into_par_iter()
            .map(|mut index| {
                SkinError::check_cancel(cancel, "fit_spectrum's start table")?;
                let x: Vec<f64> = axes
                    .iter()
                    .map(|a| {
                        let v = a[index % a.len()];
                        index /= a.len();
                        v
                    })
                    .collect();
                Ok(self.forward(&x, cancel).map(|r| (x, r)))
            })
            .collect::<Result<_, SkinError>>()?;
        Ok(spectra.into_iter().flatten().collect())
    }

    /// The wavelengths the fitter was built for.
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// The number of spectra in the start table.
    pub fn table_len(&self) -> usize {
        self.table.len()
    }

    /// The offset for a diffuse spectrum: fixed, or (free) the least-squares one clipped to its range.
    fn offset_for(&self, diffuse: &[f64], measured: &[f64]) -> f64 {
        match self.options.specular {
            Specular::Fresnel => FRESNEL_NORMAL_REFLECTANCE,
            Specular::Fixed(v) => v,
            Specular::Free => {
                let mean = measured.iter().zip(diffuse).map(|(m, d)| m - d).sum::<f64>() / measured.len() as f64;
                mean.clamp(SPECULAR_OFFSET_RANGE.0, SPECULAR_OFFSET_RANGE.1)
            }
        }
    }

    /// CIELAB (D65, CIE 1931 2°) of a spectrum on the fitter's wavelengths, as the fit's `lab_measured`.
    pub fn lab(&self, spectrum: &[f64]) -> [f64; 3] {
        lab_from_xyz(spectrum_to_xyz(spectrum, &self.xyz_weights), self.white_xyz)
    }

    /// Fit one measured spectrum (on the fitter's wavelengths).
    pub fn fit(&self, reflectance: &[f64]) -> Result<SpectrumFit, SkinError> {
        self.fit_cancellable(reflectance, &AtomicBool::new(false))
    }

    /// [`SpectrumFitter::fit`] that stops once `cancel` is set (read before each start's refinement and at every
    /// forward spectrum inside it), with [`SkinError::interrupted`].
    pub fn fit_cancellable(&self, reflectance: &[f64], cancel: &AtomicBool) -> Result<SpectrumFit, SkinError> {
        check_reflectance(reflectance, self.wavelengths_nm.len())?;
        let n_free = self.free.len();
        let fit_offset = self.options.specular == Specular::Free;
        // Coarse start: the table's best spectra, each with its best offset.
        let mut scored: Vec<(f64, usize)> = self
            .table
            .iter()
            .enumerate()
            .map(|(i, (_, diffuse))| {
                let off = self.offset_for(diffuse, reflectance);
                let sse: f64 = diffuse.iter().zip(reflectance).map(|(d, m)| (d + off - m).powi(2)).sum();
                (sse, i)
            })
            .collect();
        let starts = self.options.starts.min(scored.len());
        scored.select_nth_unstable_by(starts - 1, |a, b| a.0.total_cmp(&b.0));
        scored[..starts].sort_by(|a, b| a.0.total_cmp(&b.0));
        // Local refinement in the free parameters (and the offset when it is free), the unknowns after them held at 0.
        let mut lower = [0.0; UNKNOWNS];
        let mut upper = [0.0; UNKNOWNS];
        for (q, &k) in self.free.iter().enumerate() {
            (lower[q], upper[q]) = quantity(k).range();
        }
        if fit_offset {
            (lower[n_free], upper[n_free]) = SPECULAR_OFFSET_RANGE;
        }
        let lab_measured = self.lab(reflectance);
        let residuals = |x: &[f64; UNKNOWNS]| -> Vec<f64> {
            // Cancelled: a NaN residual ends the refinement at once (the solver takes no step to it).
            if cancel.load(Ordering::Relaxed) {
                return vec![f64::NAN; reflectance.len()];
            }
            let Some(diffuse) = self.forward(&x[..n_free], cancel) else {
                return vec![f64::NAN; reflectance.len()];
            };
            let off = if fit_offset { x[n_free] } else { self.offset_for(&diffuse, reflectance) };
            let diff = diffuse.iter().zip(reflectance).map(|(d, m)| d + off - m);
            match self.options.objective {
                Objective::Reflectance => diff.collect(),
                Objective::Cielab => {
                    let fitted: Vec<f64> = diffuse.iter().map(|d| d + off).collect();
                    let lab = self.lab(&fitted);
                    (0..3).map(|c| lab[c] - lab_measured[c]).chain(diff).collect()
                }
            }
        };
        let mut best: Option<LmResult<UNKNOWNS, Vec<f64>>> = None;
        let mut evaluations = 0;
        for &(_, i) in &scored[..starts] {
            SkinError::check_cancel(cancel, "fit_spectrum")?;
            let (x_table, diffuse) = &self.table[i];
            let mut x0 = [0.0; UNKNOWNS];
            x0[..n_free].copy_from_slice(x_table);
            if fit_offset {
                x0[n_free] = self.offset_for(diffuse, reflectance);
            }
            let result = minimize(residuals, x0, lower, upper, &LmSettings::default());
            evaluations += result.evaluations;
            if best.as_ref().map_or(true, |b| result.cost < b.cost) {
                best = Some(result);
            }
        }
        SkinError::check_cancel(cancel, "fit_spectrum")?;
        let best = best.expect("at least one start");
        let Some(diffuse) = self.forward(&best.x[..n_free], cancel) else {
            SkinError::check_cancel(cancel, "fit_spectrum")?;
            return Err(SkinError::invalid(
                "reflectance",
                "the fit ended on parameters the model rejects (please report this)",
            ));
        };
        let specular_offset = if fit_offset { best.x[n_free] } else { self.offset_for(&diffuse, reflectance) };
        let fitted: Vec<f64> = diffuse.iter().map(|d| d + specular_offset).collect();
        let rms =
            (fitted.iter().zip(reflectance).map(|(f, m)| (f - m).powi(2)).sum::<f64>() / fitted.len() as f64).sqrt();
        let lab_fitted = self.lab(&fitted);
        let values = self.values_at(&best.x[..n_free]);
        Ok(SpectrumFit {
            params: params_of(&values)?,
            epidermal_hemoglobin: values[PARAM_COUNT],
            model: with_model_values(self.options.request, &values[PARAM_COUNT..]).model,
            free: self.free.iter().map(|&k| quantity(k).name).collect(),
            specular: self.options.specular.name(),
            specular_offset,
            objective: self.options.objective,
            wavelengths_nm: self.wavelengths_nm.clone(),
            bandpass: self.options.bandpass.name(),
            bandpass_nm: self.bandpass_nm.clone(),
            aperture: self.options.aperture,
            fitted_reflectance: fitted,
            rms,
            delta_e00: ciede2000(lab_measured, lab_fitted),
            lab_measured,
            lab_fitted,
            starts,
            evaluations,
            transport: self.options.request.transport,
            streams: self.options.request.accuracy.streams,
        })
    }

    /// Fit many spectra in parallel (rayon), each as [`SpectrumFitter::fit`].
    pub fn fit_many(&self, spectra: &[Vec<f64>]) -> Vec<Result<SpectrumFit, SkinError>> {
        spectra.par_iter().map(|s| self.fit(s)).collect()
    }

    /// Fit a batch of spectra with this one fitter (its start table built once), in parallel, calling `done` after
    /// each; stops once `cancel` is set ([`SkinError::interrupted`]). Every spectrum is checked before any is fitted;
    /// a bad one is an error naming it, `reflectances[i]`. At most [`MAX_SPECTRA`].
    pub fn fit_batch_cancellable(
        &self,
        spectra: &[Vec<f64>],
        cancel: &AtomicBool,
        done: &(dyn Fn() + Sync),
    ) -> Result<Vec<SpectrumFit>, SkinError> {
        check_spectra(spectra, self.wavelengths_nm.len())?;
        let fits: Vec<Result<SpectrumFit, SkinError>> = spectra
            .par_iter()
            .map(|s| {
                let fit = self.fit_cancellable(s, cancel);
                done();
                fit
            })
            .collect();
        SkinError::check_cancel(cancel, "fit_spectra")?;
        fits.into_iter().collect()
    }
}

/// The parameters among `values` (the first [`PARAM_COUNT`] quantities), validated.
fn params_of(values: &[f64; QUANTITIES]) -> Result<SkinParams, SkinError> {
    let mut params = [0.0; PARAM_COUNT];
    params.copy_from_slice(&values[..PARAM_COUNT]);
    SkinParams::from_values(params)
}

/// The values of [`MODEL_FREE`] in `request`'s model, in its order.
fn model_values(request: &Request) -> [f64; MODEL_FREE.len()] {
    [request.model.epidermal_hemoglobin]
}

/// `request` with the model options of [`MODEL_FREE`] at `values`.
fn with_model_values(mut request: Request, values: &[f64]) -> Request {
    request.model.epidermal_hemoglobin = values[0];
    request
}

/// Fit one measured spectrum: [`SpectrumFitter::new`] then [`SpectrumFitter::fit`].
pub fn fit_spectrum(
    wavelengths_nm: &[f64],
    reflectance: &[f64],
    options: &FitOptions,
) -> Result<SpectrumFit, SkinError> {
    fit_spectrum_cancellable(wavelengths_nm, reflectance, options, &AtomicBool::new(false))
}

/// [`fit_spectrum`] that stops once `cancel` is set (in the start table's build and in the refinements), with
/// [`SkinError::interrupted`].
pub fn fit_spectrum_cancellable(
    wavelengths_nm: &[f64],
    reflectance: &[f64],
    options: &FitOptions,
    cancel: &AtomicBool,
) -> Result<SpectrumFit, SkinError> {
    // The wavelengths first: with none, the reflectance's checks would speak of a flat spectrum from inf to -inf.
    check_wavelengths(wavelengths_nm)?;
    check_reflectance(reflectance, wavelengths_nm.len())?;
    SpectrumFitter::new_cancellable(wavelengths_nm, options, cancel)?.fit_cancellable(reflectance, cancel)
}

/// Fit a batch of measured spectra on the same wavelengths: the inputs checked first (a bad row named before the
/// start table is built), then one [`SpectrumFitter`] for all of them ([`SpectrumFitter::fit_batch_cancellable`],
/// `done` called after each spectrum); stops once `cancel` is set. Python's `fit_spectra`.
pub fn fit_spectra_cancellable(
    wavelengths_nm: &[f64],
    spectra: &[Vec<f64>],
    options: &FitOptions,
    cancel: &AtomicBool,
    done: &(dyn Fn() + Sync),
) -> Result<Vec<SpectrumFit>, SkinError> {
    check_wavelengths(wavelengths_nm)?;
    check_spectra(spectra, wavelengths_nm.len())?;
    SpectrumFitter::new_cancellable(wavelengths_nm, options, cancel)?.fit_batch_cancellable(spectra, cancel, done)
}

/// The closest two measured wavelengths may be: spectrophotometers report every 1-10 nm; closer points carry no
/// independent skin information (skin's chromophores vary over tens of nm) and only multiply the work.
pub const MIN_WAVELENGTH_SPACING_NM: f64 = 0.5;
/// The most wavelengths a spectrum may have: the visible range at [`MIN_WAVELENGTH_SPACING_NM`] (801).
pub const MAX_SPECTRUM_WAVELENGTHS: usize =
    ((VISIBLE_RANGE_NM.1 - VISIBLE_RANGE_NM.0) / MIN_WAVELENGTH_SPACING_NM) as usize + 1;
/// The most spectra one batch fit takes ([`SpectrumFitter::fit_batch_cancellable`], Python's `fit_spectra`): they
/// are held in memory, up to [`MAX_SPECTRUM_WAVELENGTHS`] values each (640 MB at both bounds), and each costs about
/// 0.15 s of one core once the fitter's table is built (the Xiao spectra, docs/measured-skin.md).
pub const MAX_SPECTRA: usize = 100_000;
/// A spectrum whose values span less than this (flat white, grey or black) has no chromophore's mark to fit.
pub const MIN_SPECTRUM_VARIATION: f64 = 1e-3;

/// Wavelengths must be finite, strictly increasing, at least [`MIN_WAVELENGTH_SPACING_NM`] apart and inside the
/// visible range the colour is integrated over ([`VISIBLE_RANGE_NM`]), at least three and at most
/// [`MAX_SPECTRUM_WAVELENGTHS`] of them.
fn check_wavelengths(w: &[f64]) -> Result<(), SkinError> {
    let (lo, hi) = VISIBLE_RANGE_NM;
    if w.len() < 3 {
        return Err(SkinError::invalid("wavelengths_nm", format!("need at least 3 wavelengths, got {}", w.len())));
    }
    if w.len() > MAX_SPECTRUM_WAVELENGTHS {
        return Err(SkinError::invalid(
            "wavelengths_nm",
            format!(
                "{} wavelengths; at most {MAX_SPECTRUM_WAVELENGTHS} (the visible range every {MIN_WAVELENGTH_SPACING_NM} \
                 nm): resample the measurement",
                w.len()
            ),
        ));
    }
    if let Some((i, v)) = w.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= lo && **v <= hi)) {
        return Err(SkinError::invalid(
            "wavelengths_nm",
            format!("wavelength {i} is {v}; each must be in [{lo}, {hi}] nm (the model's visible range)"),
        ));
    }
    if let Some(i) = (1..w.len()).find(|&i| w[i] <= w[i - 1]) {
        return Err(SkinError::invalid(
            "wavelengths_nm",
            format!("must be strictly increasing; wavelength {i} ({}) follows {}", w[i], w[i - 1]),
        ));
    }
    if let Some(i) = (1..w.len()).find(|&i| w[i] - w[i - 1] < MIN_WAVELENGTH_SPACING_NM) {
        return Err(SkinError::invalid(
            "wavelengths_nm",
            format!(
                "wavelength {i} ({} nm) is {:e} nm after the one before; they must be at least \
                 {MIN_WAVELENGTH_SPACING_NM} nm apart: resample the measurement",
                w[i],
                w[i] - w[i - 1]
            ),
        ));
    }
    Ok(())
}

/// The measurement must have one finite value in [0, 1] per wavelength.
/// A batch of spectra as [`SpectrumFitter::fit_batch_cancellable`] takes them: 1 to [`MAX_SPECTRA`], each one value
/// in [0, 1] per wavelength and not flat; a bad one is an error naming it, `reflectances[i]`.
fn check_spectra(spectra: &[Vec<f64>], wavelengths: usize) -> Result<(), SkinError> {
    if spectra.is_empty() || spectra.len() > MAX_SPECTRA {
        let reason = format!("must hold 1 to {MAX_SPECTRA} spectra; got {}", spectra.len());
        return Err(SkinError::invalid("reflectances", reason));
    }
    for (i, spectrum) in spectra.iter().enumerate() {
        check_reflectance(spectrum, wavelengths)
            .map_err(|e| SkinError::invalid(format!("reflectances[{i}]"), e.to_string()))?;
    }
    Ok(())
}

fn check_reflectance(r: &[f64], wavelengths: usize) -> Result<(), SkinError> {
    if r.len() != wavelengths {
        return Err(SkinError::invalid(
            "reflectance",
            format!("has {} values for {wavelengths} wavelengths; give one per wavelength", r.len()),
        ));
    }
    if let Some((i, v)) = r.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0 && **v <= 1.0)) {
        return Err(SkinError::invalid("reflectance", format!("value {i} is {v}; each must be in [0, 1]")));
    }
    let (min, max) = r.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if max - min < MIN_SPECTRUM_VARIATION {
        return Err(SkinError::invalid(
            "reflectance",
            format!(
                "is flat ({min} to {max}); a spectrum that varies by less than {MIN_SPECTRUM_VARIATION} (white, grey or \
                 black) has no mark of melanin or blood to fit"
            ),
        ));
    }
    Ok(())
}
