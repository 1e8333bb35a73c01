//! The measuring instrument's aperture (docs/measured-skin.md, Instrument aperture).
//!
//! A contact spectrophotometer lights a disc of skin evenly and measures the light that leaves a smaller, concentric
//! disc; it is calibrated on a white tile that returns its light where it fell. Light that enters skin travels
//! sideways before it leaves, so some of what entered near the edge of the lit disc leaves outside the measured one,
//! and nothing from outside the lit disc makes up for it: the instrument reads less than the skin's total diffuse
//! reflectance, most where light travels furthest (the red), the "edge loss" of translucent samples (Atkins &
//! Billmeyer 1966, Materials Research and Standards 6:564). For uniform light over a disc of radius a and a measured
//! disc of radius b <= a, the measured fraction of the total is the radial profile weighted by the overlap of the two
//! discs when their centres are the profile's distance d apart, over the measured disc's area:
//! F = integral of w(d) dE(d), w(d) = A(d; a, b) / (pi b^2), E the profile's encircled energy
//! ([`Shape::encircled_energy`]), w 1 for d <= a - b, the lens area between, 0 beyond a + b.
//!
//! The Konica Minolta CM-2600d of the Xiao et al. 2016 spectra has two masks (CM-2600d/CM-2500d specifications):
//! MAV, a measured disc of 8 mm diameter lit over 11 mm ([`CM2600D_MAV`]), and SAV, 3 mm lit over 6 mm
//! ([`CM2600D_SAV`]); the data do not say which was used.

use std::f64::consts::PI;

use serde::Serialize;

use crate::error::{check_range, SkinError};
use crate::transport::profile_table::Shape;

/// The largest radius accepted, mm: a 20 cm disc, beyond any contact instrument.
pub const MAX_APERTURE_RADIUS_MM: f64 = 100.0;
/// The smallest, mm: a 2 µm disc, below any instrument's (and the profile table's first radii for thin skin).
pub const MIN_APERTURE_RADIUS_MM: f64 = 1e-3;

/// Gauss-Chebyshev nodes over the rim a - b .. a + b ([`Aperture::kernel`]): 12 put the fraction within 4e-6 of
/// 4096 midpoint panels on the presets' stacks (8: 8e-6, 24: 7e-7; tests/physics/aperture.rs); midpoint panels
/// need about 128 for 1e-5.
const RIM_NODES: usize = 12;

/// The spacing, nm, of the wavelengths where a spectrum's measured fraction is computed
/// ([`ApertureKernel::fractions`]); between them it is interpolated by cubic Hermite pieces. A fraction costs about 5 us (the exact shape and its
/// encircled energy), some twenty times a node's diffuse reflectance, and changes slowly with wavelength, except on
/// the Q bands' steep red edge: on the presets, with both masks, a 15 nm bandpass's average of the reflectance times
/// the fraction taken every 10 nm is within 1.4e-4 of the average with the fraction at every nanometre (every 5 nm:
/// 6e-5; linear pieces every 5 nm: 1.2e-4, every 10 nm 2e-4; the fraction only at the measured wavelength: 1.8e-3;
/// tests/physics/aperture.rs). With 10 nm cubic pieces 549 measured spectra fit through the SAV mask in 30 s, where
/// 5 nm linear ones took 43 s (10 s without the aperture; docs/measured-skin.md, Instrument aperture).
pub const FRACTION_STEP_NM: f64 = 10.0;

/// A lit disc and the measured disc inside it, radii in mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Aperture {
    pub illuminated_radius_mm: f64,
    pub measured_radius_mm: f64,
}

/// The CM-2600d's MAV mask: measured over 8 mm, lit over 11 mm (diameters).
pub const CM2600D_MAV: Aperture = Aperture { illuminated_radius_mm: 5.5, measured_radius_mm: 4.0 };
/// The CM-2600d's SAV mask: measured over 3 mm, lit over 6 mm (diameters).
pub const CM2600D_SAV: Aperture = Aperture { illuminated_radius_mm: 3.0, measured_radius_mm: 1.5 };

/// The apertures known by name, for the fronts' `aperture` argument ([`Aperture::parse`]).
pub const NAMED_APERTURES: [(&str, Aperture); 2] = [("cm2600d-mav", CM2600D_MAV), ("cm2600d-sav", CM2600D_SAV)];

impl Aperture {
    /// An aperture from its name in [`NAMED_APERTURES`] or from its two radii in mm, "LIT,MEASURED", validated.
    pub fn parse(spec: &str) -> Result<Aperture, SkinError> {
        if let Some((_, known)) = NAMED_APERTURES.iter().find(|(name, _)| *name == spec.trim()) {
            return Ok(*known);
        }
        let radii: Option<Vec<f64>> = spec.split(',').map(|v| v.trim().parse().ok()).collect();
        let Some([lit, measured]) = radii.as_deref().map(<[f64]>::to_vec).and_then(|v| <[f64; 2]>::try_from(v).ok())
        else {
            let names: Vec<&str> = NAMED_APERTURES.iter().map(|(n, _)| *n).collect();
            let expected =
                format!("{} or the lit and the measured disc's radii in mm, \"LIT,MEASURED\"", names.join(", "));
            return Err(SkinError::invalid("aperture", format!("unknown {spec:?}; expected {expected}")));
        };
        let aperture = Aperture { illuminated_radius_mm: lit, measured_radius_mm: measured };
        aperture.validate().map(|_| aperture)
    }

    /// Both radii in [[`MIN_APERTURE_RADIUS_MM`], [`MAX_APERTURE_RADIUS_MM`]], the measured disc no larger than the
    /// lit one.
    pub fn validate(&self) -> Result<(), SkinError> {
        let max = MAX_APERTURE_RADIUS_MM;
        check_range(
            "aperture.measured_radius_mm",
            "radius of the measured disc, mm",
            self.measured_radius_mm,
            MIN_APERTURE_RADIUS_MM,
            max,
        )?;
        let lit = check_range(
            "aperture.illuminated_radius_mm",
            "radius of the lit disc, mm (at least the measured disc's)",
            self.illuminated_radius_mm,
            self.measured_radius_mm,
            max,
        );
        lit.map(|_| ())
    }

    /// The overlap of the lit and the measured disc with centres `d_mm` apart, over the measured disc's area.
    pub fn overlap_weight(&self, d_mm: f64) -> f64 {
        let (a, b, d) = (self.illuminated_radius_mm, self.measured_radius_mm, d_mm.abs());
        if d <= a - b {
            return 1.0;
        }
        if d >= a + b {
            return 0.0;
        }
        let cos_a = ((d * d + a * a - b * b) / (2.0 * d * a)).clamp(-1.0, 1.0);
        let cos_b = ((d * d + b * b - a * a) / (2.0 * d * b)).clamp(-1.0, 1.0);
        let kite = ((-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b)).max(0.0).sqrt();
        let lens = a * a * cos_a.acos() + b * b * cos_b.acos() - 0.5 * kite;
        (lens / (PI * b * b)).clamp(0.0, 1.0)
    }

    /// The quadrature of the measured fraction, built once per aperture. Integrated by parts, the fraction is
    /// F = integral over the rim of E(d) (-dw/dd) dd, and -dw/dd is the two circles' common chord over pi b^2
    /// (the lens area falls at the chord's length per unit of d). With d = a + b x the chord is
    /// 2 b sqrt(1 - x^2) sqrt((a + X) / (2 d)), X = (d^2 + a^2 - b^2) / (2 d) the chord's distance from the lit
    /// disc's centre: a square root at both ends times a smooth factor, which Gauss-Chebyshev quadrature of the
    /// second kind integrates with nodes x_i = cos(i pi / (n + 1)). The weights are scaled to sum to 1 (what an
    /// encircled energy of 1 over the whole rim must give).
    pub fn kernel(&self) -> ApertureKernel {
        let (a, b) = (self.illuminated_radius_mm, self.measured_radius_mm);
        let n = RIM_NODES;
        let (mut radii_mm, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 1..=n {
            let theta = i as f64 * PI / (n + 1) as f64;
            let d = a + b * theta.cos();
            let chord_from_centre = (d * d + a * a - b * b) / (2.0 * d);
            let smooth = 2.0 / PI * ((a + chord_from_centre) / (2.0 * d)).max(0.0).sqrt();
            radii_mm.push(d);
            weights.push(PI / (n + 1) as f64 * theta.sin().powi(2) * smooth);
        }
        let sum: f64 = weights.iter().sum();
        weights.iter_mut().for_each(|w| *w /= sum);
        ApertureKernel { radii_mm, weights }
    }
}

/// The measured fraction's quadrature: radii over the rim and their weights (summing to 1).
#[derive(Debug, Clone, PartialEq)]
pub struct ApertureKernel {
    radii_mm: Vec<f64>,
    weights: Vec<f64>,
}

impl ApertureKernel {
    /// The fraction of a profile's total the instrument measures: the encircled energy weighted over the rim.
    pub fn measured_fraction(&self, shape: &Shape) -> f64 {
        let energy = shape.encircled_energy(&self.radii_mm);
        energy.iter().zip(&self.weights).map(|(e, w)| e * w).sum::<f64>().clamp(0.0, 1.0)
    }

    /// The measured fraction at each of `wavelengths_nm` (increasing), computed from `shape_at` at the first, every
    /// [`FRACTION_STEP_NM`] after it and the last, cubic Hermite between; None where `shape_at` has no shape.
    pub fn fractions(&self, wavelengths_nm: &[f64], shape_at: impl Fn(f64) -> Option<Shape>) -> Option<Vec<f64>> {
        let mut computed: Vec<(f64, f64)> = Vec::new();
        for (i, &nm) in wavelengths_nm.iter().enumerate() {
            let last = i + 1 == wavelengths_nm.len();
            if last || computed.last().map_or(true, |&(at, _)| nm >= at + FRACTION_STEP_NM - 1e-9) {
                computed.push((nm, self.measured_fraction(&shape_at(nm)?)));
            }
        }
        let slopes = hermite_slopes(&computed);
        let fractions = wavelengths_nm
            .iter()
            .map(|&nm| {
                let j = computed.partition_point(|&(at, _)| at < nm).min(computed.len() - 1);
                let (hi_nm, hi) = computed[j];
                if j == 0 || hi_nm <= nm {
                    return hi;
                }
                let (lo_nm, lo) = computed[j - 1];
                let h = hi_nm - lo_nm;
                let t = (nm - lo_nm) / h;
                let (t2, t3) = (t * t, t * t * t);
                (2.0 * t3 - 3.0 * t2 + 1.0) * lo
                    + (t3 - 2.0 * t2 + t) * h * slopes[j - 1]
                    + (-2.0 * t3 + 3.0 * t2) * hi
                    + (t3 - t2) * h * slopes[j]
            })
            .collect();
        Some(fractions)
    }
}

/// The slope at each of `points` (x increasing) for a cubic Hermite interpolant: the three-point derivative of the
/// parabola through each point and its neighbours (one-sided at the ends; 0 for a single point).
fn hermite_slopes(points: &[(f64, f64)]) -> Vec<f64> {
    let n = points.len();
    let secant = |k: usize| (points[k + 1].1 - points[k].1) / (points[k + 1].0 - points[k].0);
    (0..n)
        .map(|k| match (k, n) {
            (_, 1) => 0.0,
            (0, _) => secant(0),
            (k, n) if k == n - 1 => secant(n - 2),
            (k, _) => {
                let (h0, h1) = (points[k].0 - points[k - 1].0, points[k + 1].0 - points[k].0);
                (secant(k - 1) * h1 + secant(k) * h0) / (h0 + h1)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The overlap weight is the lens area: checked against counting a fine grid of points of the measured disc
    /// that fall inside the lit one.
    #[test]
    fn overlap_weight_is_the_lens_area() {
        let ap = Aperture { illuminated_radius_mm: 5.5, measured_radius_mm: 4.0 };
        let n = 800;
        for d in [0.5, 1.5, 2.0, 4.0, 7.0, 9.4, 9.6] {
            let (mut inside, mut all) = (0usize, 0usize);
            for i in 0..n {
                for j in 0..n {
                    let x = -4.0 + 8.0 * (i as f64 + 0.5) / n as f64;
                    let y = -4.0 + 8.0 * (j as f64 + 0.5) / n as f64;
                    if x * x + y * y < 16.0 {
                        all += 1;
                        if (x - d).powi(2) + y * y < 5.5 * 5.5 {
                            inside += 1;
                        }
                    }
                }
            }
            let counted = inside as f64 / all as f64;
            let w = ap.overlap_weight(d);
            assert!((w - counted).abs() < 2e-3, "d {d}: lens {w} vs counted {counted}");
        }
    }

    #[test]
    fn apertures_parse_by_name_and_radii() {
        assert_eq!(Aperture::parse("cm2600d-sav").unwrap(), CM2600D_SAV);
        let ap = Aperture::parse("5.5, 4").unwrap();
        assert_eq!(ap, CM2600D_MAV);
        for bad in ["", "mav", "1", "1,2,3", "x,1"] {
            let e = Aperture::parse(bad).unwrap_err().to_string();
            assert!(e.contains("aperture") && e.contains("cm2600d-mav"), "{bad:?}: {e}");
        }
        let e = Aperture::parse("1,2").unwrap_err().to_string();
        assert!(e.contains("aperture.illuminated_radius_mm"), "{e}");
    }

    #[test]
    fn apertures_are_checked() {
        assert!(CM2600D_MAV.validate().is_ok() && CM2600D_SAV.validate().is_ok());
        let bad = Aperture { illuminated_radius_mm: 1.0, measured_radius_mm: 2.0 };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("aperture.illuminated_radius_mm"), "{e}");
        let nan = Aperture { illuminated_radius_mm: f64::NAN, measured_radius_mm: 2.0 };
        assert!(nan.validate().is_err());
    }
}
