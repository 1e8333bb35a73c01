//! The measuring instrument's spectral bandpass (docs/measured-skin.md, Instrument bandpass).
//!
//! A grating spectrophotometer does not sample the reflectance at its nominal wavelengths: each reported value is the
//! reflectance weighted by the instrument's slit function, close to a triangle whose full width at half maximum
//! (FWHM) is the bandpass (ASTM E308-18, "Standard Practice for Computing the Colors of Objects by Using the CIE
//! System", section 7.5 and its Tables 5-6, which assume a triangle with the bandpass equal to the measurement
//! interval). The Konica Minolta CM-2600d of the Xiao et al. 2016 spectra reports every 10 nm with a "half bandwidth
//! approx. 10 nm" (Konica Minolta, CM-2600d/CM-2500d specifications). Haemoglobin's Q bands are about as narrow
//! (oxyhaemoglobin's 577 nm peak falls to half in about 12 nm: Prahl's table, data/hemoglobin_extinction.csv), so
//! a model sampled at points draws them deeper than such an instrument records them.
//!
//! In effect the CM-2600d data average over more than the nominal 10 nm: the mean residual of the fits in the Q bands
//! shrinks as the modelled bandpass widens to 15 nm and overshoots beyond (docs/measured-skin.md, Instrument
//! bandpass), hence the default [`Bandpass::Spacing`] of 1.5 times the spacing.
//!
//! [`Sampling`] computes the model on a finer grid of nodes and averages it with triangle weights, exact for a
//! reflectance linear between nodes.

use crate::error::SkinError;

/// The widest bandpass accepted, nm: twice the 10 nm of common skin spectrophotometers; wider would smear the Q
/// bands (32 nm apart) into one.
pub const MAX_BANDPASS_NM: f64 = 20.0;

/// The widest spacing of the nodes the model is computed at under a bandpass, nm (narrower for a bandpass under twice
/// as wide). At 1 nm, a 15 nm average of the model's reflectance is within 1e-4 of the converged one; at 2 nm (the
/// haemoglobin table's step) it is off by up to 3.7e-4 on the steep edge of the Q bands at 590 nm
/// (tests/inverse/measured_spectra.rs, `bandpass_quadrature_converges`).
pub const MAX_NODE_STEP_NM: f64 = 1.0;

/// The bandpass (FWHM) of [`Bandpass::Spacing`] over the wavelength spacing: ASTM E308 assumes 1 (a bandpass equal
/// to the measurement interval), and the CM-2600d states about 10 nm at its 10 nm interval; its data's Q-band residual
/// shrinks to a third by 15 nm and turns over beyond (0 / 10 / 15 / 20 nm: docs/measured-skin.md, Instrument
/// bandpass), so 1.5.
pub const SPACING_TO_FWHM: f64 = 1.5;

/// How the measured values relate to the model's spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bandpass {
    /// A triangle [`SPACING_TO_FWHM`] times as wide (FWHM) as the spacing of the measured wavelengths there (the
    /// mean of the two neighbouring gaps; the one gap at each end), at most [`MAX_BANDPASS_NM`]: 15 nm for spectra
    /// every 10 nm, what the Xiao et al. CM-2600d spectra show; narrow, and of little effect, for finely sampled
    /// spectra.
    Spacing,
    /// A triangle of this FWHM, nm, at every wavelength, in 0..=[`MAX_BANDPASS_NM`]; 0 samples the model at the
    /// measured wavelengths themselves (the fit before the bandpass was modelled).
    FwhmNm(f64),
}

impl Bandpass {
    /// The name the fronts use: "spacing" or "fwhm".
    pub fn name(&self) -> &'static str {
        match self {
            Bandpass::Spacing => "spacing",
            Bandpass::FwhmNm(_) => "fwhm",
        }
    }

    /// The FWHM at each of `wavelengths_nm` (increasing, at least 2), nm; an out-of-range width is an error naming
    /// `bandpass`.
    pub fn widths_nm(&self, wavelengths_nm: &[f64]) -> Result<Vec<f64>, SkinError> {
        match *self {
            Bandpass::FwhmNm(w) => {
                crate::error::check_range("bandpass", "instrument bandpass FWHM, nm", w, 0.0, MAX_BANDPASS_NM)?;
                Ok(vec![w; wavelengths_nm.len()])
            }
            Bandpass::Spacing => {
                let n = wavelengths_nm.len();
                let gap = |i: usize| wavelengths_nm[i + 1] - wavelengths_nm[i];
                Ok((0..n)
                    .map(|k| {
                        let spacing = match k {
                            0 => gap(0),
                            _ if k == n - 1 => gap(n - 2),
                            _ => 0.5 * (gap(k - 1) + gap(k)),
                        };
                        (SPACING_TO_FWHM * spacing).min(MAX_BANDPASS_NM)
                    })
                    .collect())
            }
        }
    }
}

/// The model's wavelengths (nodes) and each measured value's weights on them.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampling {
    /// Where the model is computed, increasing.
    pub nodes_nm: Vec<f64>,
    /// Per measured wavelength: (node index, weight), weights summing to 1.
    rows: Vec<Vec<(usize, f64)>>,
}

impl Sampling {
    /// Triangles of FWHM `widths_nm[k]` centred on `wavelengths_nm[k]` (a width of 0: the point itself). The model
    /// is taken as linear between nodes on one grid from the first wavelength (so neighbouring triangles share their
    /// nodes whatever their width), of step [`MAX_NODE_STEP_NM`] or half the narrowest bandpass if less, and each
    /// triangle's weights are the exact integrals of the triangle times each node's hat function.
    pub fn new(wavelengths_nm: &[f64], widths_nm: &[f64]) -> Sampling {
        let origin = wavelengths_nm.first().copied().unwrap_or(0.0);
        let step = widths_nm.iter().filter(|&&w| w > 0.0).fold(MAX_NODE_STEP_NM, |s, &w| s.min(0.5 * w));
        let points: Vec<Vec<(f64, f64)>> = wavelengths_nm
            .iter()
            .zip(widths_nm)
            .map(|(&centre, &width)| triangle_weights(centre, width, origin, step))
            .collect();
        let mut nodes_nm: Vec<f64> = points.iter().flatten().map(|&(x, _)| x).collect();
        nodes_nm.sort_by(f64::total_cmp);
        nodes_nm.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        let index = |x: f64| nodes_nm.partition_point(|&n| n < x - 1e-9);
        let rows = points.iter().map(|row| row.iter().map(|&(x, w)| (index(x), w)).collect()).collect();
        Sampling { nodes_nm, rows }
    }

    /// The measured values of a model spectrum given at [`Sampling::nodes_nm`].
    pub fn apply(&self, at_nodes: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|row| row.iter().map(|&(i, w)| w * at_nodes[i]).sum()).collect()
    }
}

/// The nodes (on the grid `origin + j step`) and normalised weights of a triangle of FWHM `width` (base twice as
/// wide) at `centre`: weight j is the integral of the triangle times node j's hat function over the triangle's.
fn triangle_weights(centre: f64, width: f64, origin: f64, step: f64) -> Vec<(f64, f64)> {
    if width <= 0.0 {
        return vec![(centre, 1.0)];
    }
    let (lo, hi) = (centre - width, centre + width);
    let triangle = |x: f64| (1.0 - (x - centre).abs() / width).max(0.0);
    let first = ((lo - origin) / step).floor() as i64;
    let last = ((hi - origin) / step).ceil() as i64;
    let node = |j: i64| origin + j as f64 * step;
    let mut weights = Vec::new();
    for j in first..=last {
        let x = node(j);
        let hat = |t: f64| (1.0 - (t - x).abs() / step).max(0.0);
        // Both factors are linear between the breakpoints, so Simpson's rule is exact on each piece.
        let mut cuts: Vec<f64> = [x - step, x, x + step, lo, centre, hi]
            .into_iter()
            .filter(|&t| t >= lo.max(x - step) && t <= hi.min(x + step))
            .collect();
        cuts.sort_by(f64::total_cmp);
        let integral: f64 = cuts
            .windows(2)
            .map(|p| {
                let (a, b) = (p[0], p[1]);
                let m = 0.5 * (a + b);
                (b - a) / 6.0 * (triangle(a) * hat(a) + 4.0 * triangle(m) * hat(m) + triangle(b) * hat(b))
            })
            .sum();
        if integral > 0.0 {
            weights.push((x, integral / width));
        }
    }
    weights
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle's average of a linear function is its value at the centre; of (x - centre)^2, the triangle's
    /// variance w^2 / 6 for FWHM w (16.7 for 10 nm) plus h^2 / 6 for the linear interpolation between nodes h = 1
    /// nm apart (the interpolant of x^2 lies above it by (x - a)(b - x), whose mean over a cell is h^2 / 6).
    #[test]
    fn triangle_moments() {
        let s = Sampling::new(&[500.0, 510.0, 520.0], &[10.0, 10.0, 10.0]);
        let linear: Vec<f64> = s.nodes_nm.iter().map(|x| 3.0 + 0.5 * x).collect();
        for (v, c) in s.apply(&linear).iter().zip([500.0, 510.0, 520.0]) {
            assert!((v - (3.0 + 0.5 * c)).abs() < 1e-9, "{v}");
        }
        let parabola: Vec<f64> = s.nodes_nm.iter().map(|x| (x - 510.0) * (x - 510.0)).collect();
        let variance = s.apply(&parabola)[1];
        assert!((variance - (100.0 + 1.0) / 6.0).abs() < 1e-9, "{variance}");
    }

    #[test]
    fn neighbours_share_nodes_and_zero_width_is_the_point() {
        let wl: Vec<f64> = (0..31).map(|i| 400.0 + 10.0 * i as f64).collect();
        let s = Sampling::new(&wl, &vec![10.0; 31]);
        // 390 to 710 nm every 1 nm: the triangles' reach.
        assert_eq!(s.nodes_nm.len(), 321, "{:?}", &s.nodes_nm[..12]);
        assert_eq!(Sampling::new(&wl, &vec![15.0; 31]).nodes_nm.len(), 331);
        // A narrow bandpass gets nodes half its width apart.
        let fine: Vec<f64> = (0..11).map(|i| 500.0 + i as f64).collect();
        let narrow = Sampling::new(&fine, &[1.5; 11]);
        assert!((narrow.nodes_nm[1] - narrow.nodes_nm[0] - 0.75).abs() < 1e-12, "{:?}", &narrow.nodes_nm[..3]);
        let p = Sampling::new(&wl, &vec![0.0; 31]);
        assert_eq!(p.nodes_nm, wl);
        let values: Vec<f64> = wl.iter().map(|x| x.sin()).collect();
        assert_eq!(p.apply(&values), values);
    }

    #[test]
    fn widths_follow_the_spacing_and_are_checked() {
        let wl = [400.0, 410.0, 430.0, 480.0];
        assert_eq!(Bandpass::Spacing.widths_nm(&wl).unwrap(), vec![15.0, 20.0, 20.0, 20.0]);
        assert_eq!(Bandpass::Spacing.widths_nm(&[500.0, 501.0, 502.0]).unwrap(), vec![1.5; 3]);
        let e = Bandpass::FwhmNm(25.0).widths_nm(&wl).unwrap_err().to_string();
        assert!(e.contains("bandpass") && e.contains("25"), "{e}");
        assert!(Bandpass::FwhmNm(f64::NAN).widths_nm(&wl).is_err());
    }
}
