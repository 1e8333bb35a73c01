//! The `spectral-skin` command line: evaluate the Donner & Jensen 2006 skin model, compute and fit texture maps.
//! One implementation for the program `src/bin/spectral-skin.rs` builds and for the `spectral-skin` command a
//! `pip install` of the wheel puts on PATH (the `spectral_skin._cli` entry point, which runs [`main`] in the
//! Python process).

use std::ffi::OsString;

use std::path::PathBuf;

use crate::accuracy::AccuracyLevel;
use crate::color::{RgbMapping, WavelengthPlacement};
use crate::diffusion::{Boundaries, Combination, MultipoleTerms};
use crate::error::SkinError;
use crate::evaluate::ProfileGrid;
use crate::evaluate::{evaluate, Evaluation, MaterialOutput, Outputs, Request};
use crate::fit::blender_target::{BlenderVersion, Engine, Target, CURRENT_RELEASE};
use crate::fit::{SubsurfaceMethod, DEFAULT_METHOD};
use crate::maps::example::{write_example_params_encoded, ExampleKind, EXAMPLE_EXR};
use crate::maps::io::{Compression, ExrOptions, Precision};
use crate::maps::request::{Combined, ParamRequest, Source};
use crate::maps::{MapSettings, StrategyChoice};
use crate::skin::params::{
    ParamSpec, BASELINE_ABSORPTION_SCALE, BLOOD_OXYGENATION, EPIDERMIS_THICKNESS, EXTENDED_PARAMS, HEMOGLOBIN, MELANIN,
    MELANIN_BLEND, OILINESS, PARAMS,
};
use crate::skin::{SkinModel, SkinParams, PRESETS};
use crate::surface::lobes::SurfaceModel;
use crate::transport::Transport;
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

#[derive(Parser)]
#[command(
    name = "spectral-skin",
    version,
    about = "Spectral skin BSSRDF (Donner & Jensen 2006) for Blender's Principled BSDF"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Every subcommand reads a negative number after an option as its value (so `--melanin -0.1` reaches the range
// check and its message), not as an unknown flag `-0`; `main` joins those clap does not know as numbers (`-1e-3`).
#[derive(Subcommand)]
enum Command {
    /// Albedo, Base Color and Subsurface Radius per subsurface method, and specular inputs, for one set of
    /// parameters and one Blender target.
    #[command(allow_negative_numbers = true)]
    Eval {
        #[command(flatten)]
        skin: SkinArgs,
        #[command(flatten)]
        accuracy: AccuracyArgs,
        #[command(flatten)]
        target: TargetArgs,
        /// Show only this subsurface method in the summary (an error if the target's Blender lacks it); the JSON
        /// always lists every method the target offers.
        #[arg(long, value_enum)]
        method: Option<SubsurfaceMethod>,
        #[command(flatten)]
        surface: SurfaceArgs,
        #[command(flatten)]
        model: ModelArgs,
        /// Print the stable JSON interface instead of a summary.
        #[arg(long)]
        json: bool,
    },
    /// Radial reflectance profile R(r) in mm^-2.
    ///
    /// R, G and B are the spectral profile mapped linearly into Linear Rec.709. At radii whose light lies outside
    /// that gamut (the far tail, where only red light is left: every preset has such radii) a channel is negative,
    /// as the exact colour demands. --rgb-mapping non-negative gives values that are never negative (each such
    /// colour moved towards the grey of the same luminance); --spectral profiles are never negative.
    #[command(allow_negative_numbers = true)]
    Profile {
        #[command(flatten)]
        skin: SkinArgs,
        #[command(flatten)]
        accuracy: AccuracyArgs,
        #[command(flatten)]
        model: ModelArgs,
        /// One column per wavelength instead of R, G, B.
        #[arg(long)]
        spectral: bool,
        /// How each radius's R, G, B are formed: linear (the exact colour; a channel is negative where the light is
        /// outside the gamut) or non_negative (such a colour moved towards the grey of the same luminance until no
        /// channel is negative; luminance and hue kept, radii inside the gamut unchanged).
        #[arg(long, value_enum, default_value_t = RgbMapping::Linear)]
        rgb_mapping: RgbMapping,
        /// Print CSV (the only format for now; accepted for explicitness).
        #[arg(long)]
        csv: bool,
        /// Smallest radius, mm.
        #[arg(long, default_value_t = ProfileGrid::default().r_min_mm)]
        r_min_mm: f64,
        /// Largest radius, mm.
        #[arg(long, default_value_t = ProfileGrid::default().r_max_mm)]
        r_max_mm: f64,
        /// Number of log-spaced radii.
        #[arg(long, default_value_t = ProfileGrid::default().count)]
        count: usize,
    },
    /// List the named presets.
    Presets,
    /// Parameter maps in, Principled texture maps out: albedo.exr, radius.exr, specular.exr, skin_maps.json.
    #[command(allow_negative_numbers = true)]
    Maps(Box<MapsArgs>),
    /// The lookup table as images for the add-on's live node group: shader_base_color.exr, shader_radius.exr (ln of
    /// Base Color and radius, float32) and shader_table.json (layout and axes).
    ShaderTable(ShaderTableArgs),
    /// Fit the model to a measured reflectance spectrum (docs/measured-skin.md); prints JSON.
    #[command(allow_negative_numbers = true)]
    Fit(FitArgs),
    /// Albedo texture in, parameter map out: the parameters whose model albedo is closest in CIEDE2000 to each texel
    /// (docs/skin-atlas.md, "Fitting a texture"), as the four-channel EXR `maps` reads, and residual.exr (ΔE00 per
    /// texel, channel Y).
    #[command(allow_negative_numbers = true)]
    FitMaps(FitMapsArgs),
    /// Write the built-in example parameter map (a face-like test card) as one four-channel EXR (PIZ, half floats
    /// unless --precision float).
    #[command(allow_negative_numbers = true)]
    Example {
        /// Output file.
        #[arg(long, default_value = "face_params.exr")]
        out: PathBuf,
        /// Width and height in texels.
        #[arg(long, default_value_t = 512)]
        size: usize,
        /// Which map: the face-like test card, a 16-tuple mask, or one value everywhere.
        #[arg(long, value_enum, default_value_t = ExampleKind::Face)]
        kind: ExampleKind,
        /// Sample precision of the file: half (the parameters rounded to 11 significant bits) or float (exact).
        #[arg(long, value_enum, default_value_t = Precision::Half)]
        precision: Precision,
    },
}

#[derive(Args)]
struct FitArgs {
    /// CSV file with columns wavelength_nm, reflectance (a header line; lines starting with '#' are comments);
    /// wavelengths 380..780 nm, increasing; reflectance a fraction 0..1.
    #[arg(long)]
    spectrum: PathBuf,
    /// Comma-separated free parameters (the parameters but oiliness, and epidermal_hemoglobin: blood in the
    /// epidermis, 0 when not free); default: the set docs/measured-skin.md chooses.
    #[arg(long, value_delimiter = ',')]
    free: Option<Vec<String>>,
    /// A value for a parameter that is not free, NAME=VALUE (repeatable).
    #[arg(long = "fixed", value_name = "NAME=VALUE")]
    fixed: Vec<String>,
    /// Surface reflection added to the model: free (fitted), fresnel (0.0278, index 1.4) or a number 0..0.1.
    #[arg(long, default_value = "free")]
    specular: String,
    /// The instrument's spectral bandpass the model is averaged over: spacing (a triangle as wide as the wavelength
    /// spacing, at most 20 nm) or its FWHM in nm, 0..20 (0: the model at the wavelengths themselves); default: the
    /// choice of docs/measured-skin.md (Instrument bandpass).
    #[arg(long)]
    bandpass: Option<String>,
    /// The instrument's lit and measured discs, to model the light the skin carries out of the measured one:
    /// cm2600d-mav, cm2600d-sav or the two radii in mm, LIT,MEASURED; default: none (the skin's total reflectance;
    /// docs/measured-skin.md, Instrument aperture).
    #[arg(long)]
    aperture: Option<String>,
    /// What is minimised.
    #[arg(long, value_enum, default_value_t = crate::inverse::Objective::Reflectance)]
    objective: crate::inverse::Objective,
    /// How many of the start table's best entries are refined.
    #[arg(long, default_value_t = crate::inverse::spectrum::DEFAULT_STARTS)]
    starts: usize,
    #[command(flatten)]
    transport: TransportArgs,
    #[command(flatten)]
    model: ModelArgs,
}

/// The model's options beyond the parameters (`skin::SkinModel`).
#[derive(Args)]
struct ModelArgs {
    /// The model's options beyond the parameters, a JSON object by name (docs/model.md), e.g.
    /// '{"epidermal_hemoglobin": 0.01}' for what `fit --free ...,epidermal_hemoglobin` fitted; options left out keep
    /// DJ2006's model [default: DJ2006's model].
    #[arg(long, value_name = "JSON", value_parser = parse_model)]
    model: Option<SkinModel>,
}

impl ModelArgs {
    fn model(&self) -> SkinModel {
        self.model.unwrap_or_default()
    }
}

/// `--model`'s JSON read as the model's options (an unknown name lists the known ones; the ranges are checked where
/// the model is used).
fn parse_model(text: &str) -> Result<SkinModel, String> {
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    if !value.is_object() {
        return Err(format!("expected a JSON object {{\"option\": value, ...}}; got {value}"));
    }
    serde_json::from_value(value.clone()).map_err(|e| {
        // serde_json's error names no field: the first entry that fails alone is the one.
        let fails_alone = |(name, v): &(&String, &serde_json::Value)| {
            serde_json::from_value::<SkinModel>(serde_json::json!({ *name: v })).is_err()
        };
        match value.as_object().and_then(|entries| entries.iter().find(fails_alone)) {
            Some((name, _)) => format!("{name}: {e}"),
            None => e.to_string(),
        }
    })
}

#[derive(Args)]
struct MapsArgs {
    #[arg(long, help = params_help(), conflicts_with_all = ["melanin_map", "melanin_blend_map", "hemoglobin_map", "oiliness_map"])]
    params: Option<PathBuf>,
    #[arg(long, help = map_help(&MELANIN), conflicts_with = "melanin")]
    melanin_map: Option<PathBuf>,
    #[arg(long, help = map_help(&MELANIN_BLEND), conflicts_with = "melanin_blend")]
    melanin_blend_map: Option<PathBuf>,
    #[arg(long, help = map_help(&HEMOGLOBIN), conflicts_with = "hemoglobin")]
    hemoglobin_map: Option<PathBuf>,
    #[arg(long, help = map_help(&OILINESS), conflicts_with = "oiliness")]
    oiliness_map: Option<PathBuf>,
    #[arg(long, help = constant_help(&MELANIN))]
    melanin: Option<f64>,
    #[arg(long, help = constant_help(&MELANIN_BLEND))]
    melanin_blend: Option<f64>,
    #[arg(long, help = constant_help(&HEMOGLOBIN))]
    hemoglobin: Option<f64>,
    #[arg(long, help = constant_help(&OILINESS))]
    oiliness: Option<f64>,
    #[arg(long, help = extended_map_help(&EPIDERMIS_THICKNESS), conflicts_with = "epidermis_thickness_mm")]
    epidermis_thickness_mm_map: Option<PathBuf>,
    #[arg(long, help = extended_map_help(&BASELINE_ABSORPTION_SCALE), conflicts_with = "baseline_absorption_scale")]
    baseline_absorption_scale_map: Option<PathBuf>,
    #[arg(long, help = extended_map_help(&BLOOD_OXYGENATION), conflicts_with = "blood_oxygenation")]
    blood_oxygenation_map: Option<PathBuf>,
    #[command(flatten)]
    extended: ExtendedArgs,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Subsurface method the maps are for (it must be one the target's Blender offers).
    #[arg(long, value_enum, default_value_t = DEFAULT_METHOD)]
    method: SubsurfaceMethod,
    #[command(flatten)]
    target: TargetArgs,
    /// Evaluate every texel directly instead of through the lookup table.
    #[arg(long)]
    exact: bool,
    /// The maps to compute, comma-separated: albedo (Base Color: albedo.exr), radius (radius.exr), specular
    /// (specular.exr when the oiliness varies, with coat_weight.exr and coat_roughness.exr for --surface measured). Without radius no radius is fitted and Base Color is the albedo
    /// whatever the method (a material without subsurface); without specular no specular input is computed.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "albedo,radius,specular")]
    outputs: Vec<MaterialOutput>,
    /// Clamp NaN, infinite and out-of-range texels (and report them) instead of failing.
    #[arg(long)]
    clamp: bool,
    /// Sample precision of the written EXRs: half (16-bit, within 0.049 % of the computed value) or float.
    #[arg(long, value_enum, default_value_t = Precision::default())]
    precision: Precision,
    /// Points at which a freshly built table is checked against direct evaluation (reported in the sidecar).
    #[arg(long, default_value_t = crate::maps::pipeline::DEFAULT_TABLE_CHECK_SAMPLES as u64,
          value_parser = clap::value_parser!(u64).range(0..=crate::maps::pipeline::MAX_TABLE_CHECK_SAMPLES as u64))]
    table_check: u64,
    /// Build the lookup table afresh instead of reusing one kept in the cache folder
    /// ($SPECTRAL_SKIN_CACHE_DIR, else spectral-skin in the platform's cache folder: $XDG_CACHE_HOME or ~/.cache on
    /// Linux, ~/Library/Caches on macOS, %LOCALAPPDATA% on Windows).
    #[arg(long)]
    no_cache: bool,
    /// EXR compression; auto: ZIPS for half, PIZ for float, or none for a file that would shrink by under 25 %.
    #[arg(long, value_enum, default_value_t = Compression::default())]
    compression: Compression,
    #[command(flatten)]
    accuracy: AccuracyArgs,
    #[command(flatten)]
    surface: SurfaceArgs,
    #[command(flatten)]
    model: ModelArgs,
}

/// The surface model of `eval` and `maps`.
#[derive(Args)]
struct SurfaceArgs {
    /// The surface reflection the specular inputs stand in for: paper (DJ2006's oil layer, one lobe scaled by the
    /// oiliness) or measured (a broad base lobe and a sharp Coat, a dielectric's reflection at every oiliness;
    /// docs/model.md, "Principled mapping of the measured surface").
    #[arg(long, value_enum, default_value_t = SurfaceModel::default())]
    surface: SurfaceModel,
}

#[derive(Args)]
struct SkinArgs {
    /// Named preset (caucasian, asian, african); explicit parameters override its values.
    #[arg(long)]
    preset: Option<String>,
    #[arg(long, help = param_help(&MELANIN))]
    melanin: Option<f64>,
    #[arg(long, help = param_help(&MELANIN_BLEND))]
    melanin_blend: Option<f64>,
    #[arg(long, help = param_help(&HEMOGLOBIN))]
    hemoglobin: Option<f64>,
    #[arg(long, help = param_help(&OILINESS))]
    oiliness: Option<f64>,
    #[command(flatten)]
    extended: ExtendedArgs,
}

/// The extended physiology (`EXTENDED_PARAMS`), each optional: unset is the default (the paper's value), or for
/// `maps` the channel of that name in `--params` if it has one.
#[derive(Args)]
struct ExtendedArgs {
    #[arg(long, help = extended_help(&EPIDERMIS_THICKNESS))]
    epidermis_thickness_mm: Option<f64>,
    #[arg(long, help = extended_help(&BASELINE_ABSORPTION_SCALE))]
    baseline_absorption_scale: Option<f64>,
    #[arg(long, help = extended_help(&BLOOD_OXYGENATION))]
    blood_oxygenation: Option<f64>,
}

impl ExtendedArgs {
    /// The values given, in `EXTENDED_PARAMS` order.
    fn values(&self) -> [Option<f64>; 3] {
        [self.epidermis_thickness_mm, self.baseline_absorption_scale, self.blood_oxygenation]
    }
}

#[derive(Args)]
struct AccuracyArgs {
    /// Named accuracy level (docs/accuracy-vs-time.md); the flags below override its settings.
    #[arg(long, value_enum, default_value_t = AccuracyLevel::Default)]
    accuracy: AccuracyLevel,
    /// Wavelength step, nm (380-780 nm); with cmf_adapted placement it sets the count [default: the level's].
    #[arg(long)]
    wavelength_step_nm: Option<f64>,
    /// Where the wavelengths lie [default: the level's, cmf_adapted at the default level].
    #[arg(long, value_enum)]
    wavelength_placement: Option<WavelengthPlacement>,
    /// Image-source pairs of the multipole (default: the whole series in closed form).
    #[arg(long)]
    multipole_pairs: Option<u32>,
    /// Layer combination.
    #[arg(long, value_enum, default_value_t = Combination::Directional)]
    combination: Combination,
    /// The layers' boundary conditions: the paper's, or capped (every profile non-negative and the total monotone in
    /// absorption by construction; docs/robustness.md, "Negative profile lobes").
    #[arg(long, value_enum, default_value_t = Boundaries::Paper)]
    boundaries: Boundaries,
    #[command(flatten)]
    transport: TransportArgs,
}

/// How the totals are computed (`crate::transport`).
#[derive(Args)]
struct TransportArgs {
    /// How each wavelength's total diffuse reflectance is computed: adding_doubling (exact radiative transfer; the
    /// profile and radius keep the multipole's shape scaled to it) or diffusion (the paper's layered multipole:
    /// reproduces DJ2006).
    #[arg(long, value_enum, default_value_t = Transport::default())]
    transport: Transport,
    /// Streams (directions per hemisphere) of the adding-doubling solver (the range and the levels' values from
    /// `transport::STREAMS_RANGE` and `accuracy`'s levels).
    #[arg(long, help = streams_help())]
    streams: Option<usize>,
}

/// `--streams`' help, from the constants it states.
fn streams_help() -> String {
    use crate::accuracy::{DRAFT_STREAMS, REFERENCE_STREAMS};
    let (lo, hi) = crate::transport::STREAMS_RANGE;
    format!(
        "Streams (directions per hemisphere) of the adding-doubling solver, even, {lo}..{hi} [default: the level's: \
         {DRAFT_STREAMS} draft, {} default, {REFERENCE_STREAMS} reference]. Given, every exact total is solved at \
         them; else skin's totals are read from the shipped table (32 streams) and only the others solved",
        crate::transport::DEFAULT_STREAMS
    )
}

impl TransportArgs {
    /// The transport and streams into `request` (the streams only where given).
    fn apply(&self, request: &mut Request) {
        request.transport = self.transport;
        if let Some(n) = self.streams {
            request.accuracy = request.accuracy.solved_at(n);
        }
    }
}

impl SkinArgs {
    fn params(&self) -> Result<SkinParams, SkinError> {
        let base = match &self.preset {
            Some(name) => Some(SkinParams::preset(name)?),
            None => None,
        };
        // A value given is checked before a missing one is asked for (`--melanin -0.1` alone is about the melanin).
        for (value, spec) in [
            (self.melanin, &MELANIN),
            (self.melanin_blend, &MELANIN_BLEND),
            (self.hemoglobin, &HEMOGLOBIN),
            (self.oiliness, &OILINESS),
        ] {
            if let Some(v) = value {
                spec.check(v)?;
            }
        }
        let pick = |explicit: Option<f64>, from_preset: Option<f64>, spec: &ParamSpec| {
            let flag = flag(spec);
            explicit.or(from_preset).ok_or_else(|| SkinError::Invalid {
                name: flag.to_string(),
                reason: format!("give --preset or --{flag}"),
            })
        };
        // The extended physiology: the flag, else the preset's, else the default.
        let extended = base.map_or(crate::skin::params::EXTENDED_DEFAULTS, |p| p.extended_values());
        let e = |k: usize| self.extended.values()[k].unwrap_or(extended[k]);
        SkinParams::from_values([
            pick(self.melanin, base.map(|p| p.melanin), &MELANIN)?,
            pick(self.melanin_blend, base.map(|p| p.melanin_blend), &MELANIN_BLEND)?,
            pick(self.hemoglobin, base.map(|p| p.hemoglobin), &HEMOGLOBIN)?,
            pick(self.oiliness, base.map(|p| p.oiliness), &OILINESS)?,
            e(0),
            e(1),
            e(2),
        ])
    }
}

/// The Blender target of the mapping.
#[derive(Args)]
struct TargetArgs {
    /// Blender version the inputs are for, MAJOR.MINOR or MAJOR.MINOR.PATCH (4.2 or newer; a patch release means its
    /// minor release, e.g. 5.3.1 is 5.3: patches do not change subsurface behaviour; a version newer than the tested
    /// ones uses the newest known behaviour and is reported as untested).
    #[arg(long, default_value_t = CURRENT_RELEASE)]
    blender: BlenderVersion,
    /// Render engine the inputs are for (EEVEE renders every subsurface method as Burley with its own radius).
    #[arg(long, value_enum, default_value_t = Engine::Cycles)]
    engine: Engine,
}

impl TargetArgs {
    fn target(&self) -> Target {
        Target { blender: self.blender, engine: self.engine }
    }
}

impl AccuracyArgs {
    fn request(&self, outputs: Outputs) -> Request {
        let mut r = Request::new(outputs);
        r.accuracy = self.accuracy.accuracy();
        if let Some(step) = self.wavelength_step_nm {
            r.accuracy.wavelength_step_nm = step;
        }
        if let Some(placement) = self.wavelength_placement {
            r.accuracy.wavelength_placement = placement;
        }
        if let Some(n) = self.multipole_pairs {
            r.accuracy.multipole_terms = MultipoleTerms::Pairs(n);
        }
        r.combination = self.combination;
        r.boundaries = self.boundaries;
        self.transport.apply(&mut r);
        r
    }
}

/// Run the command line on `args` (the program's name first, as `std::env::args_os` gives them) and return the exit
/// status: 0, 2 for an error (printed to stderr), 130 when stopped by Ctrl-C. Help, `--version` and argument errors
/// are clap's: printed, and the process exits.
pub fn main(args: impl IntoIterator<Item = OsString>) -> u8 {
    let args = joined_negative_numbers(args.into_iter());
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        // clap says only that "one or more arguments" are not UTF-8: name them.
        Err(e) if e.kind() == clap::error::ErrorKind::InvalidUtf8 => {
            eprintln!("error: {}", non_utf8_arguments(&args));
            return 2;
        }
        Err(e) => e.exit(),
    };
    match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            // 130 = 128 + SIGINT, the shells' code for a run stopped by Ctrl-C.
            if ctrl_c::INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed) {
                130
            } else {
                2
            }
        }
    }
}

/// The arguments that are not UTF-8, each named by the option it is the value of (or its position), for the error
/// clap gives without naming them: names, numbers and choices must be text (a path may be any bytes).
fn non_utf8_arguments(args: &[OsString]) -> String {
    let named: Vec<String> = args
        .iter()
        .enumerate()
        .skip(1)
        .filter(|(_, arg)| arg.to_str().is_none())
        .map(|(i, arg)| match args[i - 1].to_str().filter(|o| o.starts_with("--")) {
            Some(option) => format!("the value of {option}, {arg:?}"),
            None => format!("argument {i}, {arg:?}"),
        })
        .collect();
    format!(
        "{} not valid UTF-8 (names, numbers and choices must be text; only a path may be other bytes)",
        if named.is_empty() { "an argument is".to_string() } else { format!("{} is", named.join("; ")) }
    )
}

/// `--option -1e-3` as `--option=-1e-3`: clap's `allow_negative_numbers` knows `-0.1` and `-1e3` but not a negative
/// exponent, and would take `-1e-3` for the short flags `-1`, `-e`, ... A token that parses as a number and follows a
/// long option without `=` is joined to it; every other token passes unchanged.
fn joined_negative_numbers(args: impl Iterator<Item = OsString>) -> Vec<OsString> {
    let mut out: Vec<OsString> = Vec::new();
    for arg in args {
        // A number, or a comma-separated list of numbers (`--rgb-gains -1,1,1`).
        let negative_number = arg
            .to_str()
            .is_some_and(|s| s.starts_with('-') && s.split(',').all(|part| part.trim().parse::<f64>().is_ok()));
        match out.last_mut() {
            Some(option)
                if negative_number
                    && option.to_str().is_some_and(|o| o.starts_with("--") && o.len() > 2 && !o.contains('=')) =>
            {
                option.push("=");
                option.push(&arg);
            }
            _ => out.push(arg),
        }
    }
    out
}

/// Ctrl-C for `maps`, `shader-table`, `fit` and `fit-maps`: the first SIGINT sets [`ctrl_c::INTERRUPTED`], which the work reads
/// (the map pipeline before each row and before renaming its outputs into place, so the run stops without leaving
/// partial files; the spectrum fit at each forward spectrum); a second Ctrl-C ends the
/// process at once (the default action is restored by the first).
mod ctrl_c {
    use std::sync::atomic::AtomicBool;

    pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

    #[cfg(unix)]
    extern "C" fn on_sigint(_: libc::c_int) {
        INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: signal() is async-signal-safe (POSIX.1-2008, 2.4.3); an atomic store is too.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
        }
    }

    /// Install the handler (a no-op where there is no SIGINT).
    pub fn catch() {
        #[cfg(unix)]
        // SAFETY: the handler only stores to an atomic and calls signal(), both async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t);
        }
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Eval { skin, accuracy, target, method, surface: SurfaceArgs { surface }, model, json } => {
            let params = skin.params()?;
            let target = target.target();
            if let Some(m) = method {
                target.method_entry(m)?;
            }
            let request = Request { target, surface, model: model.model(), ..accuracy.request(Outputs::material()) };
            let ev = evaluate(&params, &request)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&ev)?);
            } else {
                print_summary(&ev, method);
            }
        }
        Command::Profile { skin, accuracy, model, spectral, rgb_mapping, csv: _, r_min_mm, r_max_mm, count } => {
            let params = skin.params()?;
            let outputs = Outputs { profile_rgb: !spectral, profile_spectral: spectral, ..Outputs::default() };
            let mut request = Request { rgb_mapping, model: model.model(), ..accuracy.request(outputs) };
            request.accuracy.profile_grid = ProfileGrid { r_min_mm, r_max_mm, count };
            let ev = evaluate(&params, &request)?;
            if let Some(lobe) = ev.profile.as_ref().and_then(|p| p.negative_lobe) {
                eprintln!("warning: {lobe}");
            }
            print_profile_csv(&ev);
        }
        Command::Maps(args) => run_maps(*args)?,
        Command::Fit(args) => run_fit(args)?,
        Command::FitMaps(args) => fit_maps::run(args)?,
        Command::ShaderTable(args) => run_shader_table(args)?,
        Command::Example { out, size, kind, precision } => {
            write_example_params_encoded(&out, kind, size, ExrOptions { precision, ..EXAMPLE_EXR })?;
            println!("wrote {} ({size}x{size}, channels melanin, melanin_blend, hemoglobin, oiliness)", out.display());
        }
        Command::Presets => {
            for p in PRESETS {
                let q = p.params;
                println!(
                    "{:<10} melanin {:<5} melanin_blend {:<4} hemoglobin {:<5} oiliness {:<4} ({})",
                    p.name, q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness, p.description
                );
            }
        }
    }
    Ok(())
}

fn run_fit(args: FitArgs) -> Result<(), Box<dyn std::error::Error>> {
    use crate::inverse::{FitOptions, Specular};
    let path = args.spectrum.display().to_string();
    let text = std::fs::read_to_string(&args.spectrum).map_err(|e| format!("{path}: {e}"))?;
    let mut rows = crate::table::strip_utf8_bom(&text)
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let header = rows.next().map(|(_, l)| l.trim()).unwrap_or("");
    if header.replace(' ', "") != "wavelength_nm,reflectance" {
        return Err(
            format!("{path}: the first line must be the header wavelength_nm,reflectance; got {header:?}").into()
        );
    }
    let (mut wavelengths, mut reflectance) = (Vec::new(), Vec::new());
    let most = crate::inverse::spectrum::MAX_SPECTRUM_WAVELENGTHS;
    for (i, line) in rows {
        if wavelengths.len() == most {
            return Err(format!(
                "{path}: more than {most} data rows; a spectrum has at most {most} wavelengths (the visible range every \
                 {} nm): resample the measurement",
                crate::inverse::spectrum::MIN_WAVELENGTH_SPACING_NM
            )
            .into());
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let parse = |c: &str| c.parse::<f64>().map_err(|_| format!("{path}, line {}: {c:?} is not a number", i + 1));
        match cells.as_slice() {
            [w, r] => {
                wavelengths.push(parse(w)?);
                reflectance.push(parse(r)?);
            }
            _ => return Err(format!("{path}, line {}: expected 2 columns, got {}", i + 1, cells.len()).into()),
        }
    }
    let mut options = FitOptions { objective: args.objective, starts: args.starts, ..FitOptions::default() };
    args.transport.apply(&mut options.request);
    options.request.model = args.model.model();
    if let Some(free) = args.free {
        options.free = free;
    }
    for item in &args.fixed {
        let (name, value) = item.split_once('=').ok_or_else(|| format!("--fixed {item:?}: expected NAME=VALUE"))?;
        let i =
            PARAMS.iter().position(|p| p.name == name).ok_or_else(|| format!("--fixed: unknown parameter {name:?}"))?;
        options.fixed[i] = Some(value.parse().map_err(|_| format!("--fixed {item:?}: {value:?} is not a number"))?);
    }
    options.specular = match args.specular.as_str() {
        "free" => Specular::Free,
        "fresnel" => Specular::Fresnel,
        v => Specular::Fixed(
            v.parse().map_err(|_| format!("--specular: expected free, fresnel or a number; got {v:?}"))?,
        ),
    };
    if let Some(b) = args.bandpass.as_deref() {
        options.bandpass = match b {
            "spacing" => crate::inverse::Bandpass::Spacing,
            v => crate::inverse::Bandpass::FwhmNm(
                v.parse().map_err(|_| format!("--bandpass: expected spacing or a number; got {v:?}"))?,
            ),
        };
    }
    if let Some(spec) = args.aperture.as_deref() {
        options.aperture = Some(crate::inverse::Aperture::parse(spec)?);
    }
    ctrl_c::catch();
    let fit =
        crate::inverse::spectrum::fit_spectrum_cancellable(&wavelengths, &reflectance, &options, &ctrl_c::INTERRUPTED)?;
    println!("{}", serde_json::to_string_pretty(&fit)?);
    Ok(())
}

impl MapsArgs {
    /// The parameter sources, translated: `--params`, and per parameter its map (`--melanin-map`) or its constant
    /// (`--melanin`); the core's request holds the rules (`crate::maps::request`).
    fn param_request(&self) -> ParamRequest {
        let maps = [
            &self.melanin_map,
            &self.melanin_blend_map,
            &self.hemoglobin_map,
            &self.oiliness_map,
            &self.epidermis_thickness_mm_map,
            &self.baseline_absorption_scale_map,
            &self.blood_oxygenation_map,
        ];
        let [e0, e1, e2] = self.extended.values();
        let constants = [self.melanin, self.melanin_blend, self.hemoglobin, self.oiliness, e0, e1, e2];
        let mut request = ParamRequest::new(self.params.clone().map(Combined::File));
        for ((spec, map), constant) in PARAMS.iter().zip(maps).zip(constants) {
            match (map, constant) {
                (Some(file), _) => request = request.with(spec, Source::File(file.clone())),
                (None, Some(value)) => request = request.with(spec, Source::Constant(value)),
                (None, None) => {}
            }
        }
        request
    }

    /// The run's settings: method, strategy, clamping, table and request.
    fn settings(&self) -> Result<MapSettings, SkinError> {
        let target = self.target.target();
        target.method_entry(self.method)?;
        let outputs = Outputs::of_material(&self.outputs);
        Ok(MapSettings {
            method: self.method,
            strategy: if self.exact { StrategyChoice::Exact } else { StrategyChoice::Auto },
            clamp: self.clamp,
            table_check_samples: self.table_check as usize,
            table_cache: if self.no_cache { None } else { crate::maps::lut::default_cache_dir() },
            request: Request {
                target,
                surface: self.surface.surface,
                model: self.model.model(),
                ..self.accuracy.request(outputs)
            },
            ..MapSettings::default()
        })
    }
}

fn run_maps(args: MapsArgs) -> Result<(), Box<dyn std::error::Error>> {
    // The settings first: a target that lacks the method is refused before the inputs are looked at.
    let settings = args.settings()?;
    let clamp_advice = |e: SkinError| e.with_clamp_advice("use --clamp");
    let inputs = args.param_request().file_inputs(args.clamp).map_err(clamp_advice)?;
    let exr = ExrOptions { precision: args.precision, compression: args.compression };
    // A progress bar for work that lasts over a second (hidden until then).
    let bar = ProgressBar::hidden();
    let started = std::time::Instant::now();
    let shown = std::sync::OnceLock::new();
    let progress = |done: usize, total: usize| {
        if started.elapsed().as_secs_f64() > 1.0 {
            shown.get_or_init(|| {
                bar.set_length(total as u64);
                bar.set_style(
                    ProgressStyle::with_template("{bar:40} {percent}% of {len} texels, eta {eta}")
                        .unwrap_or_else(|_| ProgressStyle::default_bar()),
                );
                bar.set_draw_target(ProgressDrawTarget::stderr());
            });
        }
        bar.inc(done as u64);
    };
    ctrl_c::catch();
    let report = crate::maps::pipeline::run_maps_cancellable(
        &inputs,
        &args.out,
        &settings,
        exr,
        Some(&progress),
        &ctrl_c::INTERRUPTED,
    )
    .map_err(clamp_advice)?;
    bar.finish_and_clear();
    for note in &report.input_notes {
        eprintln!("warning: {note}");
    }
    println!(
        "{}x{} texels, strategy {}, {:.2} s (read {:.2}, compute {:.2}, write {:.2}); wrote {}",
        report.width,
        report.height,
        serde_json::to_value(&report.strategy)?["name"].as_str().unwrap_or("?"),
        report.seconds.total,
        report.seconds.read,
        report.seconds.compute,
        report.seconds.write,
        args.out.display()
    );
    for bad in &report.clamped {
        println!(
            "clamped {}: {} NaN, {} infinite, {} out of range",
            bad.parameter, bad.nan, bad.infinite, bad.out_of_range
        );
    }
    Ok(())
}

/// The CLI flag stem of a parameter: its name with `-` for `_` ("melanin-blend").
fn flag(spec: &ParamSpec) -> String {
    spec.name.replace('_', "-")
}

/// The help of a parameter's flag, from the core's parameter table: "Melanin volume fraction of the epidermis, C_m,
/// 0..0.5."
fn param_help(spec: &ParamSpec) -> String {
    let summary = spec.summary();
    let mut chars = summary.chars();
    let first = chars.next().map(|c| c.to_uppercase().collect::<String>()).unwrap_or_default();
    format!("{first}{}", chars.as_str())
}

/// The help of a constant for `maps`.
fn constant_help(spec: &ParamSpec) -> String {
    format!("Constant {}", spec.summary())
}

/// The help of an extended parameter's flag: its summary and default.
fn extended_help(spec: &ParamSpec) -> String {
    format!("{} [default: {}, the paper's]", param_help(spec), spec.default.unwrap_or(f64::NAN))
}

/// The help of `maps --params`.
fn params_help() -> String {
    let four: Vec<&str> = PARAMS.iter().filter(|p| p.default.is_none()).map(|p| p.name).collect();
    let extended: Vec<&str> = EXTENDED_PARAMS.iter().map(|p| p.name).collect();
    format!(
        "One EXR with channels {} and optionally {}; a constant (--melanin etc.) fills a channel it lacks (an extended \
         one it lacks is the default without). A file name with {token} (params.{token}.exr) is a UDIM tile set: its \
         tiles are computed as one texture and each output is a tile set of the same tiles (albedo.{token}.exr); any \
         map may be a tile set",
        four.join(", "),
        extended.join(", "),
        token = crate::maps::udim::UDIM_TOKEN
    )
}

/// The help of an extended parameter's map for `maps`.
fn extended_map_help(spec: &ParamSpec) -> String {
    format!("{}; without it and --{}: the channel of --params, else the default", map_help(spec), flag(spec))
}

/// The help of a parameter's map for `maps`.
fn map_help(spec: &ParamSpec) -> String {
    format!(
        "{} map (single-channel or grey RGB EXR, or 8/16-bit greyscale or grey RGB PNG/TIFF/JPEG mapped 0..1 onto \
         {}..{}), or use --{}",
        spec.label,
        spec.min,
        spec.max,
        flag(spec)
    )
}

fn print_summary(ev: &Evaluation, only: Option<SubsurfaceMethod>) {
    let values: Vec<String> = PARAMS.iter().zip(ev.params.values()).map(|(s, v)| format!("{} {v}", s.name)).collect();
    println!("parameters: {}", values.join(" "));
    println!("colour space: {}", ev.color_space);
    let t = ev.target;
    let tested = t.untested_reason().unwrap_or_else(|| "tested".into());
    println!("target: Blender {} {} ({tested})", t.blender, t.engine.name());
    let streams = match (ev.transport.exact_total(), ev.accuracy.exact_totals) {
        (true, crate::transport::ExactTotals::Solve) => format!(", {} streams", ev.accuracy.streams),
        (true, crate::transport::ExactTotals::Table) => format!(
            ", totals from the table ({} streams; {} streams where it holds no stack)",
            crate::transport::total_table::TABLE_STREAMS,
            ev.accuracy.streams
        ),
        (false, _) => String::new(),
    };
    println!("transport: {}{streams}", ev.transport.name());
    if let Some(a) = ev.diffuse_reflectance_rgb {
        println!("diffuse reflectance (RGB): {:.4} {:.4} {:.4}", a[0], a[1], a[2]);
    }
    if let Some(m) = ev.methods {
        for (method, mp) in m.iter().filter(|(method, _)| !matches!(only, Some(o) if o != *method)) {
            let name = method.name();
            let tag = if name == ev.default_method { " (default)" } else { "" };
            println!(
                "{name}{tag}: base color {:.4} {:.4} {:.4}, subsurface radius {:.4} {:.4} {:.4} mm",
                mp.base_color[0],
                mp.base_color[1],
                mp.base_color[2],
                mp.subsurface_radius_mm[0],
                mp.subsurface_radius_mm[1],
                mp.subsurface_radius_mm[2]
            );
        }
    }
    if let Some(s) = &ev.specular {
        println!("specular: IOR level {:.4}, roughness {:.4}, IOR {}", s.specular_ior_level, s.roughness, s.ior);
        if s.coat_weight > 0.0 {
            println!("coat: weight {:.4}, roughness {:.4}, IOR {}", s.coat_weight, s.coat_roughness, s.coat_ior);
        }
    }
    println!("computed in {:.1} ms", 1e3 * ev.seconds);
}

fn print_profile_csv(ev: &Evaluation) {
    let Some(profile) = &ev.profile else { return };
    if let Some(rgb) = &profile.rgb_per_mm2 {
        println!("r_mm,r_per_mm2,g_per_mm2,b_per_mm2");
        for (r, v) in profile.radii_mm.iter().zip(rgb) {
            println!("{r:.6e},{:.6e},{:.6e},{:.6e}", v[0], v[1], v[2]);
        }
    }
    if let (Some(spectral), Some(wavelengths)) = (&profile.spectral_per_mm2, &ev.wavelengths_nm) {
        // Whole nanometres as integers (uniform grids), others to 0.01 nm (CMF-adapted grids).
        let name = |w: f64| if w.fract() == 0.0 { format!("nm{w:.0}_per_mm2") } else { format!("nm{w:.2}_per_mm2") };
        let header: Vec<String> = wavelengths.iter().map(|&w| name(w)).collect();
        println!("r_mm,{}", header.join(","));
        for (i, r) in profile.radii_mm.iter().enumerate() {
            let row: Vec<String> = spectral.iter().map(|p| format!("{:.6e}", p[i])).collect();
            println!("{r:.6e},{}", row.join(","));
        }
    }
}

#[derive(Args)]
struct ShaderTableArgs {
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// File-name prefix: <PREFIX>_shader_base_color.exr etc.
    #[arg(long)]
    prefix: Option<String>,
    /// Subsurface method the table is for (it must be one the target's Blender offers).
    #[arg(long, value_enum, default_value_t = DEFAULT_METHOD)]
    method: SubsurfaceMethod,
    #[command(flatten)]
    target: TargetArgs,
    /// Nodes along melanin, melanin blend and haemoglobin [default: 33 7 17, docs/shader-table.md].
    #[arg(long, num_args = 3, value_names = ["MELANIN", "BLEND", "HEMOGLOBIN"])]
    resolution: Option<Vec<usize>>,
    /// Build the table afresh instead of reusing one kept in the cache folder (as for `maps`).
    #[arg(long)]
    no_cache: bool,
    /// The extended physiology baked into the table (it is over melanin, melanin blend and haemoglobin only).
    #[command(flatten)]
    extended: ExtendedArgs,
    #[command(flatten)]
    accuracy: AccuracyArgs,
}

fn run_shader_table(args: ShaderTableArgs) -> Result<(), Box<dyn std::error::Error>> {
    use crate::maps::lut::TableResolution;
    use crate::maps::shader_table::{ShaderTable, DEFAULT_SHADER_TABLE_RESOLUTION, SHADER_TABLE_EXR};
    let target = args.target.target();
    target.method_entry(args.method)?;
    let resolution = match args.resolution.as_deref() {
        Some(&[melanin, melanin_blend, hemoglobin]) => TableResolution { melanin, melanin_blend, hemoglobin },
        _ => DEFAULT_SHADER_TABLE_RESOLUTION,
    };
    let request = Request { target, ..args.accuracy.request(Outputs::material()) };
    let prepared = crate::evaluate::Prepared::new(&request)?;
    let cache = if args.no_cache { None } else { crate::maps::lut::default_cache_dir() };
    // The output folder is checked before the table is built (and created only to write).
    crate::maps::io::check_output_dir(&args.out)?;
    ctrl_c::catch();
    let started = std::time::Instant::now();
    let table = ShaderTable::load_or_build_cancellable(
        &prepared,
        args.method,
        resolution,
        std::array::from_fn(|k| args.extended.values()[k].unwrap_or(crate::skin::params::EXTENDED_DEFAULTS[k])),
        cache.as_deref(),
        &ctrl_c::INTERRUPTED,
    )?;
    let paths = table.write(&args.out, args.prefix.as_deref(), SHADER_TABLE_EXR)?;
    let m = table.meta();
    println!(
        "{}x{}x{} nodes as {}x{} texels, {:.2} s; wrote {}",
        m.melanin.nodes,
        m.melanin_blend.nodes,
        m.hemoglobin.nodes,
        m.width,
        m.height,
        started.elapsed().as_secs_f64(),
        paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}

#[derive(Args)]
struct FitMapsArgs {
    /// The albedo texture: an EXR with channels R, G, B (linear in --working-space), or an 8/16-bit PNG, TIFF or JPEG
    /// (sRGB-encoded, decoded to linear; --working-space must then be linear_rec709, sRGB's primaries). A name with
    /// <UDIM> (face.<UDIM>.png) is a UDIM tile set, fitted as one texture (one thickness); --out (and --residual) must
    /// then hold <UDIM> too, and get the same tiles.
    #[arg(long)]
    albedo: PathBuf,
    /// The parameter map to write (channels melanin, melanin_blend, hemoglobin, oiliness per texel, and the extended
    /// physiology the fit holds for: epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation); its folder
    /// is created if missing.
    #[arg(long, default_value = "params.exr")]
    out: PathBuf,
    /// The residual map to write (ΔE00 per texel, channel Y); default: residual.exr (residual.<UDIM>.exr for a tile
    /// set) beside --out.
    #[arg(long)]
    residual: Option<PathBuf>,
    /// The albedo's linear RGB working space.
    #[arg(long, value_enum, default_value_t = fit_maps::Space::LinearRec709)]
    working_space: fit_maps::Space,
    /// Epidermis thickness held for every texel, mm (0.01..0.5). Default: one thickness chosen for the whole texture
    /// (0.05..0.5 mm, the least mean ΔE00 over its texels, never worse than the paper's 0.25 on it). Either way the
    /// value is written into the parameter map as the channel epidermis_thickness_mm, which `maps --params` reads.
    #[arg(long)]
    epidermis_thickness_mm: Option<f64>,
    /// Exposure and white balance: multiply the texture's linear RGB by these three gains before the fit (R,G,B).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, conflicts_with = "auto_gains")]
    rgb_gains: Option<Vec<f64>>,
    /// Estimate the exposure and white-balance gains that bring the most texels inside skin's colours (for a
    /// photograph) and apply them; they are printed and recorded in --json.
    #[arg(long)]
    auto_gains: bool,
    /// A skin mask of the albedo's size: a black-and-white image (PNG, TIFF, JPEG or an RGB EXR; white, over half,
    /// is skin; a tile set with <UDIM> for a tile set). Only the skin takes part in the thickness choice, the gains,
    /// the diagnosis and the figures; the other texels are fitted to the skin colour nearest them.
    #[arg(long)]
    mask: Option<PathBuf>,
    /// Oiliness written into every texel (0..1; the albedo does not depend on it); default 0.3.
    #[arg(long)]
    oiliness: Option<f64>,
    /// The melanin blend the prior pulls toward (0..1); default 0.7.
    #[arg(long)]
    melanin_blend_prior: Option<f64>,
    #[command(flatten)]
    transport: TransportArgs,
    /// Print the figures of the fit as JSON.
    #[arg(long)]
    json: bool,
}

/// `fit-maps`: albedo texture -> parameter EXR + residual EXR, both staged and renamed into place together.
mod fit_maps {
    use crate::color::WorkingSpace;
    use std::path::{Path, PathBuf};

    use crate::inverse::albedo::AlbedoFitOptions;
    use crate::inverse::albedo_gains::OUTSIDE_SKIN_DELTA_E00;
    use crate::inverse::albedo_maps::{
        fit_albedo_tiles_cancellable, AlbedoMapFit, AlbedoMapStats, AlbedoTile, EpidermisThickness, TextureFit,
    };
    use crate::maps::io::{check_output_dir, commit_all, output_folder_of, read_albedo_texture, AlbedoTexture};
    use crate::maps::udim::{find_tiles, is_tile_set, tile_path, UDIM_TOKEN};

    #[derive(Clone, Copy, clap::ValueEnum)]
    #[value(rename_all = "snake_case")]
    pub enum Space {
        LinearRec709,
        LinearRec2020,
        Acescg,
    }

    type CliResult<T> = Result<T, Box<dyn std::error::Error>>;

    /// One tile's texture (or the single texture): its tile, path, texels and skin mask.
    type Texture = (Option<u32>, PathBuf, AlbedoTexture, Option<Vec<bool>>);

    pub fn run(args: super::FitMapsArgs) -> CliResult<()> {
        let rgb_gains = rgb_gains_of(&args)?;
        // A UDIM tile set in: a tile set out, with the same tiles.
        let tiles: Option<Vec<u32>> = if is_tile_set(&args.albedo) { Some(find_tiles(&args.albedo)?) } else { None };
        let residual_path = checked_outputs(&args, tiles.is_some())?;
        let textures = read_textures(&args, &tiles)?;
        let options = fit_options(&args, rgb_gains)?;
        let thickness =
            if args.epidermis_thickness_mm.is_some() { EpidermisThickness::Held } else { EpidermisThickness::Chosen };
        let texture = TextureFit { thickness, auto_gains: args.auto_gains };
        let start = std::time::Instant::now();
        super::ctrl_c::catch();
        let pieces: Vec<AlbedoTile<'_>> = textures
            .iter()
            .map(|(_, path, t, mask)| AlbedoTile {
                label: format!("albedo texture {}", path.display()),
                width: t.width,
                height: t.height,
                texels: &t.texels,
                mask: mask.as_deref(),
            })
            .collect();
        let fits = fit_albedo_tiles_cancellable(&pieces, &options, texture, &super::ctrl_c::INTERRUPTED)?;
        let seconds = start.elapsed().as_secs_f64();
        let mut staged = Vec::new();
        for ((tile, _, _, _), fit) in textures.iter().zip(&fits) {
            let at = |p: &Path| tile.map_or(p.to_path_buf(), |t| tile_path(p, t));
            staged.extend(fit.stage(&at(&args.out), Some(&at(&residual_path)))?);
        }
        commit_all(staged)?;
        report(&args, &residual_path, &tiles, &fits, seconds);
        Ok(())
    }

    /// The residual's path (its default beside `--out`), after checking that both outputs' names fit the input (a
    /// tile set for a tile set) and that their folders can be written: before the fit, not after it.
    fn checked_outputs(args: &super::FitMapsArgs, tile_set: bool) -> CliResult<PathBuf> {
        if tile_set != is_tile_set(&args.out) {
            return Err(format!(
                "--albedo {} and --out {} must both name a tile set with {UDIM_TOKEN} (e.g. face.{UDIM_TOKEN}.png and \
                 params.{UDIM_TOKEN}.exr) or neither",
                args.albedo.display(),
                args.out.display()
            )
            .into());
        }
        let residual_default = if tile_set { format!("residual.{UDIM_TOKEN}.exr") } else { "residual.exr".into() };
        let residual_path = args.residual.clone().unwrap_or_else(|| args.out.with_file_name(residual_default));
        if tile_set && !is_tile_set(&residual_path) {
            return Err(format!("--residual {} must name a tile set with {UDIM_TOKEN}", residual_path.display()).into());
        }
        for file in [&args.out, &residual_path] {
            crate::inverse::albedo_maps::check_output_name(file, tile_set)?;
            check_output_dir(output_folder_of(file))?;
        }
        Ok(residual_path)
    }

    /// Each tile's albedo texture (the single texture when `tiles` is None) and its skin mask, read and checked.
    fn read_textures(args: &super::FitMapsArgs, tiles: &Option<Vec<u32>>) -> CliResult<Vec<Texture>> {
        let mut textures = Vec::new();
        for tile in tiles.clone().map_or(vec![None], |t| t.into_iter().map(Some).collect()) {
            let path = tile.map_or(args.albedo.clone(), |t| tile_path(&args.albedo, t));
            let albedo = read_albedo_texture(&path)?;
            for note in &albedo.notes {
                eprintln!("warning: {note}");
            }
            if albedo.srgb_decoded && !matches!(args.working_space, Space::LinearRec709) {
                return Err(format!(
                    "{} ({}) is sRGB-encoded, with Rec.709 primaries; --working-space must be linear_rec709 for it \
                     (or give a linear EXR in the working space)",
                    path.display(),
                    albedo.encoding
                )
                .into());
            }
            let mask = match &args.mask {
                Some(pattern) => {
                    Some(read_mask(&tile.map_or(pattern.clone(), |t| tile_path(pattern, t)), &path, &albedo)?)
                }
                None => None,
            };
            textures.push((tile, path, albedo, mask));
        }
        Ok(textures)
    }

    /// The skin mask `file` for the albedo at `albedo_path` (one size): a texel is skin where its mean is above 0.5.
    fn read_mask(file: &Path, albedo_path: &Path, albedo: &AlbedoTexture) -> CliResult<Vec<bool>> {
        let m = crate::maps::io::read_rgb_image(file, "skin mask (--mask)")?;
        if (m.width, m.height) != (albedo.width, albedo.height) {
            return Err(format!(
                "--mask {} is {}x{}; the albedo {} is {}x{}: they must have one size",
                file.display(),
                m.width,
                m.height,
                albedo_path.display(),
                albedo.width,
                albedo.height
            )
            .into());
        }
        Ok(m.texels.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0 > 0.5).collect())
    }

    /// `--rgb-gains` as three gains (read before anything else, as its own argument's error).
    fn rgb_gains_of(args: &super::FitMapsArgs) -> CliResult<Option<[f64; 3]>> {
        let Some(g) = &args.rgb_gains else { return Ok(None) };
        let gains: [f64; 3] = g.as_slice().try_into().map_err(|_| {
            format!("--rgb-gains takes three gains, R,G,B (e.g. --rgb-gains 0.8,1,1.6); got {} value(s)", g.len())
        })?;
        Ok(Some(gains))
    }

    /// The fit's options from the arguments, validated.
    fn fit_options(args: &super::FitMapsArgs, rgb_gains: Option<[f64; 3]>) -> CliResult<AlbedoFitOptions> {
        let mut options = AlbedoFitOptions {
            working_space: match args.working_space {
                Space::LinearRec709 => WorkingSpace::LinearRec709,
                Space::LinearRec2020 => WorkingSpace::LinearRec2020,
                Space::Acescg => WorkingSpace::AcesCg,
            },
            ..AlbedoFitOptions::default()
        };
        if let Some(t) = args.epidermis_thickness_mm {
            options.extended[0] = t;
        }
        if let Some(o) = args.oiliness {
            options.oiliness = o;
        }
        if let Some(p) = args.melanin_blend_prior {
            options.melanin_blend_prior = p;
        }
        options.transport = args.transport.transport;
        if let Some(n) = args.transport.streams {
            options.streams = n;
            options.exact_totals = crate::transport::ExactTotals::Solve;
        }
        if let Some(g) = rgb_gains {
            options.rgb_gains = g;
        }
        Ok(options.validated()?)
    }

    /// The tiles' statistics as one texture's: texels and the texels outside skin's colours summed, the worst ΔE00,
    /// the mean weighted by texels.
    fn combined_stats(fits: &[AlbedoMapFit]) -> AlbedoMapStats {
        let texels: usize = fits.iter().map(|f| f.stats.texels).sum();
        let mut s = fits[0].stats;
        s.texels = texels;
        s.max_delta_e00 = fits.iter().map(|f| f.stats.max_delta_e00).fold(0.0, f64::max);
        s.mean_delta_e00 =
            fits.iter().map(|f| f.stats.mean_delta_e00 * f.stats.texels as f64).sum::<f64>() / texels as f64;
        s.outside_skin_texels = fits.iter().map(|f| f.stats.outside_skin_texels).sum();
        s
    }

    /// What the run did, on stderr (the diagnosis, the gains applied) and stdout (the summary, or JSON).
    fn report(
        args: &super::FitMapsArgs,
        residual_path: &Path,
        tiles: &Option<Vec<u32>>,
        fits: &[AlbedoMapFit],
        seconds: f64,
    ) {
        let fit = &fits[0];
        let s = &combined_stats(fits);
        let size = match tiles {
            Some(t) => format!("{} tiles {:?}", t.len(), t),
            None => format!("{}x{}", fit.width, fit.height),
        };
        if let Some(diagnosis) = &fit.diagnosis {
            let hint = if args.auto_gains { "" } else { " (--auto-gains applies the gains)" };
            eprintln!("warning: {diagnosis}{hint}");
        }
        if let Some(g) = fit.gains.as_ref().filter(|_| args.auto_gains) {
            eprintln!(
                "applied gains R G B x {:.4} {:.4} {:.4} ({:+.2} stops): median ΔE00 of {} sampled texels {:.2} -> \
                 {:.2}",
                g.rgb_gains[0],
                g.rgb_gains[1],
                g.rgb_gains[2],
                g.exposure_stops,
                g.sampled_texels,
                g.median_delta_e00_before,
                g.median_delta_e00_after
            );
        }
        if args.json {
            println!(
                "{}",
                serde_json::json!({ "stats": s, "extended": fit.extended, "thickness": fit.thickness,
                    "gains": fit.gains, "diagnosis": fit.diagnosis, "tiles": tiles, "seconds": seconds })
            );
            return;
        }
        println!(
            "wrote {} and {} ({size}, {} distinct colours, {seconds:.2} s): ΔE00 mean {:.3}, max {:.3}; \
             {} texel(s) outside skin's colours (more than {OUTSIDE_SKIN_DELTA_E00} ΔE00 from every colour skin \
             can have)",
            args.out.display(),
            residual_path.display(),
            s.distinct_colours,
            s.mean_delta_e00,
            s.max_delta_e00,
            s.outside_skin_texels,
        );
        if let Some(choice) = &fit.thickness {
            println!(
                "epidermis thickness {} mm chosen for the texture (mean ΔE00 per candidate [mm, ΔE00]: {:?}{}); \
                 written into {} with the other extended physiology",
                choice.chosen_mm,
                choice.screened,
                choice.sampled_texels.map_or(String::new(), |n| format!(", screened on {n} texels")),
                args.out.display()
            );
        }
    }
}
