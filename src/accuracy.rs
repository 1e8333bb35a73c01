//! Accuracy settings: every knob that trades time for accuracy, and the named levels (`draft`, `default`,
//! `reference`) that docs/accuracy-vs-time.md measured and chose.

use serde::{Deserialize, Serialize};

use crate::color::WavelengthPlacement;
use crate::diffusion::{HankelQuadrature, MultipoleTerms};
use crate::error::{check_range, SkinError};
use crate::fit::RadiusFit;
use crate::transport::adding_doubling::validate_streams;
use crate::transport::{ExactTotals, DEFAULT_STREAMS, STREAMS_RANGE};

/// Radii of radial profiles: `count` log-spaced values from `r_min_mm` to `r_max_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfileGrid {
    pub r_min_mm: f64,
    pub r_max_mm: f64,
    pub count: usize,
}

impl Default for ProfileGrid {
    /// 0.001 to 20 mm spans dark-skin blue (~0.02 mm wide) to light-skin red tails (docs/model.md, Radial profiles;
    /// Pitfalls 10).
    fn default() -> Self {
        ProfileGrid { r_min_mm: 0.001, r_max_mm: 20.0, count: 64 }
    }
}

impl ProfileGrid {
    pub fn radii_mm(&self) -> Vec<f64> {
        if self.count == 1 {
            return vec![self.r_min_mm];
        }
        let ratio = (self.r_max_mm / self.r_min_mm).ln() / (self.count - 1) as f64;
        (0..self.count).map(|i| self.r_min_mm * (ratio * i as f64).exp()).collect()
    }
}

/// Accuracy settings: every knob that trades time for accuracy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Accuracy {
    /// Wavelength step, nm (samples from 380 to 780 nm); with a non-uniform placement it sets the count.
    pub wavelength_step_nm: f64,
    /// Where the wavelengths lie (uniform, adapted to the colour-matching functions, or the RGB shortcut).
    #[serde(default)]
    pub wavelength_placement: WavelengthPlacement,
    /// Image-source pairs of the multipole.
    pub multipole_terms: MultipoleTerms,
    /// Radii of radial profiles.
    pub profile_grid: ProfileGrid,
    /// Inverse Hankel quadrature of radial profiles.
    pub hankel: HankelQuadrature,
    /// Frequencies per decade of the radius fit.
    pub fit_frequencies_per_decade: f64,
    /// How the Burley radius is fitted.
    #[serde(default)]
    pub radius_fit: RadiusFit,
    /// Streams (quadrature directions per hemisphere) of the adding-doubling solver that gives the totals with
    /// `Transport::AddingDoubling` ([`crate::transport`]); unused by `Transport::Diffusion`.
    #[serde(default = "default_streams")]
    pub streams: usize,
    /// Exact totals read from the shipped table (32 streams) or solved at `streams` ([`ExactTotals`]); a request
    /// written before the table reads as the table.
    #[serde(default)]
    pub exact_totals: ExactTotals,
}

/// [`DEFAULT_STREAMS`], for serde: a request written before the knob existed reads as the default level's.
fn default_streams() -> usize {
    DEFAULT_STREAMS
}

pub use crate::diffusion::MAX_PROFILE_RADII;
/// The most layers of a `layered_reflectance` call: skin models have 2 to 7; the adding-doubling reads the cancel
/// flag before each layer, the multipole's sums do not, so the count bounds their time: 16 layers at 64 streams are
/// about 0.23 s in all (64 were 0.9 s, measured on the shared 2-core machine; 10 streams: 0.03 s).
pub const MAX_LAYERS: usize = 16;

/// Streams of the draft level (half the default's; not yet on the fronts of docs/accuracy-vs-time.md).
pub const DRAFT_STREAMS: usize = 4;
/// Streams of the reference level (four times the default's; `reference().refined()` doubles them again).
pub const REFERENCE_STREAMS: usize = 32;

impl Default for Accuracy {
    fn default() -> Self {
        Accuracy {
            // docs/accuracy-vs-time.md: 41 CMF-adapted wavelengths are as accurate as 81 uniform ones (albedo within
            // 0.03 % of the reference) at half the cost; the closed-form multipole and 4 fit frequencies per decade sit
            // on their fronts; the Hankel default is the cheapest quadrature whose error is negligible (see hankel.rs).
            wavelength_step_nm: 10.0,
            wavelength_placement: WavelengthPlacement::CmfAdapted,
            multipole_terms: MultipoleTerms::All,
            profile_grid: ProfileGrid::default(),
            hankel: HankelQuadrature::default(),
            fit_frequencies_per_decade: 4.0,
            radius_fit: RadiusFit::EdgeL2,
            streams: DEFAULT_STREAMS,
            // The table is closer to converged than a 10-stream solve (docs/accuracy-vs-time.md) and far cheaper.
            exact_totals: ExactTotals::Table,
        }
    }
}

impl Accuracy {
    /// The converged reference: 1 nm wavelength steps (the colour tables' own resolution: the spectrum is integrated
    /// against the 1 nm CMF x D65 product, so finer steps cannot change a colour), the whole multipole series, 16 fit
    /// frequencies per decade, and an inverse-Hankel grid twice as fine with 12-point panels and a 1e-15 cut-off.
    /// `tests/physics/accuracy.rs` checks that refining it further changes nothing and how far the default is from it.
    pub fn reference() -> Accuracy {
        Accuracy {
            wavelength_step_nm: 1.0,
            wavelength_placement: WavelengthPlacement::Uniform,
            multipole_terms: MultipoleTerms::All,
            profile_grid: ProfileGrid::default(),
            hankel: HankelQuadrature { gauss_order: 12, refinement: 2.0, cutoff: 1e-15 },
            fit_frequencies_per_decade: 16.0,
            radius_fit: RadiusFit::EdgeL2,
            streams: REFERENCE_STREAMS,
            // The reference solves every total afresh: the table is checked against it.
            exact_totals: ExactTotals::Solve,
        }
    }

    /// This accuracy with every exact total solved at `streams` (what giving streams asks for on every front: Python
    /// `streams=`, the CLI's `--streams`), not read from the table.
    pub fn solved_at(&self, streams: usize) -> Accuracy {
        Accuracy { streams, exact_totals: ExactTotals::Solve, ..*self }
    }

    /// Every knob refined once more: half the wavelength step, twice the fit frequencies, four more nodes per panel,
    /// panels half as wide, a cut-off ten times lower and twice the streams (at most `STREAMS_RANGE`'s maximum).
    /// `reference().refined()` is the check that the reference has converged (tests/physics/accuracy.rs,
    /// docs/accuracy-vs-time.md).
    pub fn refined(&self) -> Accuracy {
        let h = self.hankel;
        Accuracy {
            wavelength_step_nm: 0.5 * self.wavelength_step_nm,
            fit_frequencies_per_decade: 2.0 * self.fit_frequencies_per_decade,
            hankel: HankelQuadrature {
                gauss_order: h.gauss_order + 4,
                refinement: 2.0 * h.refinement,
                cutoff: 0.1 * h.cutoff,
            },
            streams: (2 * self.streams).min(STREAMS_RANGE.1),
            ..*self
        }
    }

    pub(crate) fn validate(&self) -> Result<(), SkinError> {
        check_range("wavelength_step_nm", "wavelength step", self.wavelength_step_nm, 0.5, 100.0)?;
        if let MultipoleTerms::Pairs(n) = self.multipole_terms {
            check_range("multipole_pairs", "image pairs per side", n as f64, 0.0, 10_000.0)?;
        }
        let g = &self.profile_grid;
        check_range("profile_r_min_mm", "smallest profile radius", g.r_min_mm, 1e-6, 1e4)?;
        check_range("profile_r_max_mm", "largest profile radius", g.r_max_mm, g.r_min_mm, 1e4)?;
        check_range("profile_count", "number of profile radii", g.count as f64, 1.0, MAX_PROFILE_RADII as f64)?;
        check_range("hankel_gauss_order", "nodes per panel", self.hankel.gauss_order as f64, 2.0, 64.0)?;
        check_range("hankel_refinement", "panel refinement", self.hankel.refinement, 0.1, 100.0)?;
        check_range("hankel_cutoff", "transform cutoff", self.hankel.cutoff, 1e-20, 1e-3)?;
        check_range(
            "fit_frequencies_per_decade",
            "fit frequencies per decade",
            self.fit_frequencies_per_decade,
            2.0,
            200.0,
        )?;
        validate_streams(self.streams)
    }
}

/// Named accuracy levels, each a point on the error-time fronts of docs/accuracy-vs-time.md.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum AccuracyLevel {
    /// [`Accuracy::draft`]; what it is for: [`AccuracyLevel::description`].
    #[cfg_attr(feature = "cli", value(help = AccuracyLevel::Draft.description()))]
    Draft,
    /// [`Accuracy::default`].
    #[default]
    #[cfg_attr(feature = "cli", value(help = AccuracyLevel::Default.description()))]
    Default,
    /// [`Accuracy::reference`].
    #[cfg_attr(feature = "cli", value(help = AccuracyLevel::Reference.description()))]
    Reference,
}

/// Every level, cheapest first.
pub const ALL_ACCURACY_LEVELS: [AccuracyLevel; 3] =
    [AccuracyLevel::Draft, AccuracyLevel::Default, AccuracyLevel::Reference];

impl AccuracyLevel {
    pub fn name(self) -> &'static str {
        match self {
            AccuracyLevel::Draft => "draft",
            AccuracyLevel::Default => "default",
            AccuracyLevel::Reference => "reference",
        }
    }

    /// What the level is for, one line, for every front (the CLI's help, Python's `accuracy_levels()`, the add-on's
    /// menu). The figures are those of docs/accuracy-vs-time.md (worst over the presets, against the reference).
    pub fn description(self) -> &'static str {
        match self {
            AccuracyLevel::Draft => {
                "For interactive previews: 1.5-2x faster than default; albedo within 0.1 % and radius within 1 % of \
                 the reference"
            }
            AccuracyLevel::Default => {
                "The best trade-off: albedo within 0.2 % and radius within 1 % of the reference for every preset"
            }
            AccuracyLevel::Reference => {
                "The converged reference (1 nm wavelength steps), for checking the others: about 20x slower per material than \
                 default"
            }
        }
    }

    /// The level called `name` (draft, default, reference).
    pub fn from_name(name: &str) -> Result<AccuracyLevel, SkinError> {
        ALL_ACCURACY_LEVELS.into_iter().find(|l| l.name() == name).ok_or_else(|| {
            SkinError::invalid(
                "accuracy",
                format!("unknown accuracy level {name:?}; expected one of draft, default, reference"),
            )
        })
    }

    /// The settings of the level.
    pub fn accuracy(self) -> Accuracy {
        match self {
            AccuracyLevel::Draft => Accuracy::draft(),
            AccuracyLevel::Default => Accuracy::default(),
            AccuracyLevel::Reference => Accuracy::reference(),
        }
    }
}

impl Accuracy {
    /// The draft level: 21 CMF-adapted wavelengths and 2 fit frequencies per decade. Measured (docs/accuracy-vs-time.md):
    /// albedo within 0.081 % and radius within 0.85 % of the reference, 1.5-2x faster than the default per evaluation
    /// and per table build; its radial profiles are coarse in the far tail.
    pub fn draft() -> Accuracy {
        Accuracy {
            wavelength_step_nm: 20.0,
            wavelength_placement: WavelengthPlacement::CmfAdapted,
            fit_frequencies_per_decade: 2.0,
            streams: DRAFT_STREAMS,
            ..Accuracy::default()
        }
    }
}
