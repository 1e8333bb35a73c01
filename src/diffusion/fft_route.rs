//! DJ05's numerical route to layered reflectance (Donner & Jensen 2005, "Light diffusion in multi-layered translucent
//! materials"): sample each layer's real-space profiles R+, T+, R-, T- on a 2-D grid, FFT them, combine the layers per
//! frequency bin with the adding equations, inverse FFT. The crate's own route (`layered`, `hankel`) does the same
//! algebra on closed-form transforms; this one exists to price the sampled route against it.
//!
//! Grid: N x N pixels of side h = extent / N, stored row-major in FFT order: pixel index i along an axis is centred at
//! x = k h with k = i for i < N/2 and k = i - N otherwise. The point of entry is the centre of pixel (0, 0), so r = 0
//! is sampled; the grid covers [-extent/2 - h/2, extent/2 - h/2) on each axis. Each pixel holds h^2 times the profile
//! at its centre or its mean over the pixel ([`PixelSampling`]): the energy in the pixel. The DFT of those energies
//! is the sampled R~, its DC bin the total.
//!
//! Known limits of the route:
//! - Wrap-around: the DFT treats the square as one tile of a periodic plane, so every product is a circular
//!   convolution (light leaving one side re-enters at the other) and the tail beyond extent/2 is lost from the total.
//!   The extent must cover the profile's tail: many 1 / sigma_tr of the least absorbing layer.
//! - Pixel sampling of the peak: by Poisson summation the centre-sampled transform is sum_m R~(k + 2 pi m / h), and
//!   the multipole's R~, T~ decay like e^(-z s) with z the shallowest image depth (l for R+, d - l for T+). With
//!   centre sampling the pixel must be well below the top layer's l and d - l, or the peak near r = 0 aliases. Fair
//!   skin's epidermis nears the thin-slab cap in the red (caucasian: d - l = 0.047 mm at 650 nm, 0.005 mm at 780 nm),
//!   where no affordable grid resolves T+: use `PixelSampling::Area` there.
//! - Radii are read by cubic interpolation along the row through the point of entry; a radius beyond extent/2 is an
//!   error (it lies outside the tile). Where the profile falls below ~1e-16 of its peak (450 nm beyond 5 mm) the
//!   FFT's rounding dominates.
//! - `Slab::transmittance` has no point mass at the thin-slab cap (l = d); it is not sampled here. Skin layers stay
//!   short of the cap over 380-780 nm (d - l >= 0.005 mm for the presets), so this is ignored.
//!
//! Measured (release build, one core per stack on a 2-core machine, caucasian preset, default `SkinModel`,
//! directional combination, whole multipole series; `cargo test --release --lib fft_route::tests::timing_table --
//! --ignored --nocapture`). Time: one call for one stack at 550 nm, best of 3-10; "fills" is the three pixel fills
//! alone (image sums at the N^2/8 distinct pixels), "FFTs" four 2-D transforms alone. The closed-form route
//! (`reflectance_profiles`, same 41 radii) takes 2.5 ms for the same stack. Errors are against the closed form at
//! 450 / 550 / 650 / 780 nm; total: DC vs `reflectance_hat(0.0, ..)`; profile: largest |FFT / closed - 1| over 41
//! log-spaced radii in 0.01-10 mm.
//!
//! | sampling | N    | extent | h mm  | time   | fills  | FFTs   | total error 450/550/650/780   | profile error 450/550/650/780 |
//! |----------|------|--------|-------|--------|--------|--------|-------------------------------|-------------------------------|
//! | centre   | 128  | 40 mm  | 0.31  | 11 ms  | 11 ms  | 0.2 ms | +1.5 / +2.0 / +28 / +1.5e5    | 13 / 6.2 / 50 / 2.2e5         |
//! | centre   | 256  | 40 mm  | 0.16  | 43 ms  | 42 ms  | 1.6 ms | +0.11 / +0.11 / +2.0 / +9.1e3 | 0.35 / 0.29 / 3.3 / 1.4e4     |
//! | centre   | 512  | 40 mm  | 0.078 | 0.17 s | 0.16 s | 7 ms   | 1.5e-3 / 2.0e-3 / 0.14 / 580  | 0.088 / 0.035 / 0.23 / 870    |
//! | centre   | 1024 | 40 mm  | 0.039 | 0.70 s | 0.62 s | 43 ms  | 3.9e-7 / 1.1e-6 / 2.5e-3 / 38 | 1.3e-2 / 3.2e-3 / 4.2e-3 / 58 |
//! | centre   | 1024 | 20 mm  | 0.020 | 0.58 s | 0.52 s | 42 ms  | 2e-12 / 6e-8 / -4.1e-4 / 2.9  | 0.75 / 0.67 / 0.52 / 6.8 (*)  |
//! | centre   | 2048 | 40 mm  | 0.020 | 2.8 s  | 2.5 s  | 0.17 s | 3e-14 / 3e-13 / -2e-8 / 2.9   | 1.3e-3 / 3e-4 / 1.3e-4 / 4.4  |
//! | area     | 128  | 40 mm  | 0.31  | 24 ms  | 27 ms  | 0.2 ms | -3e-8 / -1e-8 / -1e-6 / -9e-6 | 1.0 / 0.62 / 0.40 / 0.33      |
//! | area     | 256  | 40 mm  | 0.16  | 54 ms  | 53 ms  | 1.6 ms | 8e-9 / 9e-8 / -1e-6 / -9e-6   | 0.57 / 0.22 / 0.12 / 0.081    |
//! | area     | 512  | 40 mm  | 0.078 | 0.18 s | 0.18 s | 7 ms   | 8e-8 / 2e-7 / -9e-7 / -9e-6   | 0.12 / 0.035 / 0.017 / 0.010  |
//! | area     | 1024 | 40 mm  | 0.039 | 0.71 s | 0.67 s | 43 ms  | 3e-7 / 5e-7 / -8e-7 / -9e-6   | 1.6e-2 / 4.5e-3 / 2e-3 / 1e-3 |
//! | area     | 1024 | 20 mm  | 0.020 | 0.62 s | 0.55 s | 48 ms  | 4e-7 / 4e-7 / -4.1e-4 / -1e-3 | 0.75 / 0.68 / 0.52 / 0.50 (*) |
//! | area     | 2048 | 40 mm  | 0.020 | 2.8 s  | 2.8 s  | 0.17 s | 4e-7 / 5e-7 / -9e-7 / -9e-6   | 1.8e-3 / 4e-4 / 2e-4 / 1.1e-4 |
//!
//! Timings are +-15 % (the machine was shared; fills timed apart can exceed the whole call). The fills dominate
//! (~1.6 us per distinct pixel and fill at N = 1024); the FFTs are ~6 %. A spectrum of 31 wavelengths at N = 1024
//! costs ~22 s of one core (11 s on two), against ~0.08 s for the closed form.
//! (*) at r = 10 mm = extent / 2 the tile's periodic copy adds its own tail (wrap-around); below 1 mm the same grid
//! is within 3e-4 (centre) or 4e-4 (area) at 550 nm. Centre sampling fails in the red first (see the limits above):
//! the sampled T+ and R- overshoot so far that the adding denominator 1 - R2 R1- nearly vanishes. Area sampling
//! fixes the totals at any N (their remaining error, -9e-6 at 780 nm, is the 40 mm tile's lost tail) but blurs the
//! profile on the scale h near r = 0 and keeps an O(h^2) blur of the bounce term (550 nm, 1-10 mm, N = 1024: 6.5e-4
//! against 2.2e-5 centred). At fine grids both are limited at small radii by the cubic readout of the peak (the top
//! layer's l is 0.10 mm at 450 nm).

use std::sync::Arc;

use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use serde::{Deserialize, Serialize};

use super::layered::{bounce_term, Combination, LayerStack};
use super::multipole::{MultipoleTerms, Slab};
use super::validate_radii;
use crate::error::SkinError;
use crate::numeric::{clamp_zero, gauss_legendre};

/// Smallest grid side accepted, pixels.
pub const MIN_GRID_SIZE: usize = 8;
/// Largest grid side accepted, pixels (a stack in flight holds 40 bytes per pixel: 670 MB at 4096^2).
pub const MAX_GRID_SIZE: usize = 4096;

/// An N x N pixel grid covering a square of side `extent_mm` centred on the point of entry (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FftGrid {
    /// N: pixels per side, a power of two in [`MIN_GRID_SIZE`, `MAX_GRID_SIZE`].
    pub size: usize,
    /// Side of the sampled square, mm: finite and > 0.
    pub extent_mm: f64,
}

impl FftGrid {
    /// A validated grid.
    pub fn new(size: usize, extent_mm: f64) -> Result<FftGrid, SkinError> {
        let grid = FftGrid { size, extent_mm };
        grid.validate()?;
        Ok(grid)
    }

    /// Check N and the extent; the error names the field and the allowed range.
    pub fn validate(&self) -> Result<(), SkinError> {
        let n = self.size;
        if !(n.is_power_of_two() && (MIN_GRID_SIZE..=MAX_GRID_SIZE).contains(&n)) {
            return Err(SkinError::invalid(
                "grid.size",
                format!("must be a power of two in [{MIN_GRID_SIZE}, {MAX_GRID_SIZE}]; got {n}"),
            ));
        }
        if !(self.extent_mm.is_finite() && self.extent_mm > 0.0) {
            return Err(SkinError::invalid(
                "grid.extent_mm",
                format!("must be finite and > 0 mm; got {}", self.extent_mm),
            ));
        }
        Ok(())
    }

    /// h: side of one pixel, mm.
    pub fn pixel_mm(&self) -> f64 {
        self.extent_mm / self.size as f64
    }
}

/// What a pixel holds: the profile at its centre, or its mean over the pixel; either way times h^2 (its energy).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PixelSampling {
    /// The profile at the pixel centre (midpoint rule): exact values at the nodes, but a peak narrower than the
    /// pixel aliases (its energy is over-counted by up to h^2 R(0)).
    #[default]
    Centre,
    /// The mean over the pixel, so the grid holds every pixel's energy whatever the peak's width: the centre pixel by
    /// polar quadrature (graded in r, down to peaks of width 1e-7 h), pixels up to [`NEAR_PIXELS`] away by
    /// Gauss-Legendre (8 x 8 up to 2 away, 4 x 4 beyond), the rest by the centre value plus 1/24 of its 5-point
    /// Laplacian (the mean to O(h^4); the multipole's z / r^3 shoulder makes that term ~ 1/k^4 at k pixels, hence
    /// quadrature out to 16). The readout turns the output's pixel means back into point values the same way
    /// (value - Laplacian / 24); the bounce term, a product of three box-filtered spectra, keeps a blur of O(h^2).
    /// (Dividing each spectrum by the box's transform instead amplifies the aliased high frequencies into ringing
    /// that swamps the far tail: tried and dropped.)
    Area,
}

/// Pixels (Chebyshev distance from the centre pixel) whose mean `PixelSampling::Area` integrates by quadrature.
pub const NEAR_PIXELS: usize = 16;

/// Output of [`fft_reflectance_profiles`], one entry per stack.
#[derive(Debug, Clone, PartialEq)]
pub struct FftProfiles {
    /// R(r) at the requested radii, mm^-2.
    pub profiles: Vec<Vec<f64>>,
    /// Total diffuse reflectance: the DC bin of the combined spectrum.
    pub totals: Vec<f64>,
}

/// Reflectance profiles (mm^-2, at `radii_mm`) and totals of several stacks (typically one per wavelength) by DJ05's
/// sampled route: pixel-centre samples, 2-D FFT, adding equations per bin (as `LayerStack::reflectance_hat`),
/// inverse FFT. Stacks run in parallel; the FFT plans are made once. Radii must be in [0, extent/2].
pub fn fft_reflectance_profiles(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    grid: FftGrid,
) -> Result<FftProfiles, SkinError> {
    fft_reflectance_profiles_with(stacks, radii_mm, combination, terms, grid, PixelSampling::Centre)
}

/// [`fft_reflectance_profiles`] with a choice of what each pixel holds.
pub fn fft_reflectance_profiles_with(
    stacks: &[LayerStack],
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    grid: FftGrid,
    sampling: PixelSampling,
) -> Result<FftProfiles, SkinError> {
    grid.validate()?;
    validate_radii(radii_mm)?;
    let half_extent = 0.5 * grid.extent_mm;
    if let Some((i, r)) = radii_mm.iter().enumerate().find(|(_, r)| **r > half_extent) {
        return Err(SkinError::invalid(
            "radii_mm",
            format!("radii must be <= grid.extent_mm / 2 = {half_extent} mm (the sampled tile); radii_mm[{i}] = {r}"),
        ));
    }
    let plans = Plans::new(grid.size);
    let (profiles, totals) = stacks
        .par_iter()
        .map(|stack| stack_profile(stack, radii_mm, combination, terms, grid, sampling, &plans))
        .unzip();
    Ok(FftProfiles { profiles, totals })
}

/// Forward and inverse plans for one grid side, shared by all stacks.
struct Plans {
    forward: Arc<dyn Fft<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    scratch_len: usize,
}

impl Plans {
    fn new(n: usize) -> Plans {
        let mut planner = FftPlanner::new();
        let forward = planner.plan_fft_forward(n);
        let inverse = planner.plan_fft_inverse(n);
        let scratch_len = forward.get_inplace_scratch_len().max(inverse.get_inplace_scratch_len());
        Plans { forward, inverse, scratch_len }
    }
}

/// One stack: the bottom layer's R+, then each layer above bottom-up: `below = R+ + bounce(R+, T+, R-, T-, below)`.
/// Every sampled profile is real and even in x and y, so its DFT is real: two profiles share one complex FFT
/// (f + i g transforms to F + i G), which halves the forward FFTs.
fn stack_profile(
    stack: &LayerStack,
    radii_mm: &[f64],
    combination: Combination,
    terms: MultipoleTerms,
    grid: FftGrid,
    sampling: PixelSampling,
    plans: &Plans,
) -> (Vec<f64>, f64) {
    let n = grid.size;
    let mut scratch = vec![Complex::default(); plans.scratch_len];
    let mut work = vec![Complex::default(); n * n];
    let Some((last, above)) = stack.slabs().split_last() else {
        return (vec![0.0; radii_mm.len()], 0.0); // unreachable: a LayerStack has at least one layer
    };
    sample_pair(&mut work, grid, sampling, |r| (last.reflectance(r, terms), 0.0));
    fft2_transposed(&mut work, plans.forward.as_ref(), &mut scratch, n);
    let mut below: Vec<f64> = work.iter().map(|c| c.re).collect();

    let directional = combination == Combination::Directional;
    let mut up = if directional && !above.is_empty() { vec![Complex::default(); n * n] } else { Vec::new() };
    for slab in above.iter().rev() {
        sample_pair(&mut work, grid, sampling, |r| (slab.reflectance(r, terms), slab.transmittance(r, terms)));
        fft2_transposed(&mut work, plans.forward.as_ref(), &mut scratch, n);
        if directional {
            let flipped: Slab = slab.flipped();
            sample_pair(&mut up, grid, sampling, |r| (flipped.reflectance(r, terms), flipped.transmittance(r, terms)));
            fft2_transposed(&mut up, plans.forward.as_ref(), &mut scratch, n);
        }
        for (k, b) in below.iter_mut().enumerate() {
            let down = work[k];
            // The symmetric combination reads only the "+" pair.
            let upward = if directional { up[k] } else { down };
            *b = down.re + bounce_term([down.re, down.im, upward.re, upward.im], *b, combination);
        }
    }

    let total = below[0];
    for (w, &b) in work.iter_mut().zip(&below) {
        *w = Complex::new(b, 0.0);
    }
    fft2_transposed(&mut work, plans.inverse.as_ref(), &mut scratch, n);
    // rustfft leaves the inverse unnormalised (factor N^2); h^2 turns energy per pixel into mm^-2.
    let h = grid.pixel_mm();
    let scale = 1.0 / ((n * n) as f64 * h * h);
    // Rows 0 and 1 hold the points (0, y_j) and (h, y_j); the result is even, and index j wraps to y = (j - N) h.
    let at = |row: usize, j: i64| work[row * n + j.rem_euclid(n as i64) as usize].re * scale;
    let node = |j: i64| match sampling {
        PixelSampling::Centre => at(0, j),
        PixelSampling::Area => {
            // Pixel means back to point values to O(h^4) where the profile is smooth on the pixel scale.
            let laplacian = at(0, j - 1) + at(0, j + 1) + 2.0 * at(1, j) - 4.0 * at(0, j);
            at(0, j) - laplacian / 24.0
        }
    };
    let profile = radii_mm
        .iter()
        .map(|&r| {
            let t = r / h;
            let j = t.floor() as i64;
            clamp_zero(catmull_rom([node(j - 1), node(j), node(j + 1), node(j + 2)], t - j as f64))
        })
        .collect();
    (profile, total)
}

/// Index of pixel (a, b), 0 <= b <= a <= N/2, in the wedge table (one eighth of the grid, by the 8-fold symmetry).
fn wedge_index(a: usize, b: usize) -> usize {
    a * (a + 1) / 2 + b
}

/// Fill `buf` (N x N, FFT order) with h^2 (f + i g) per pixel as `sampling` says, where `fg(r) = (f(r), g(r))`. Each
/// distinct (|k_x|, |k_y|) with |k_y| <= |k_x| is computed once and written to its up to eight mirror pixels.
fn sample_pair(buf: &mut [Complex<f64>], grid: FftGrid, sampling: PixelSampling, fg: impl Fn(f64) -> (f64, f64)) {
    let n = grid.size;
    let half = n / 2;
    let h = grid.pixel_mm();
    let mut wedge = Vec::with_capacity(wedge_index(half, half) + 1);
    for a in 0..=half {
        for b in 0..=a {
            wedge.push(fg(h * ((a * a + b * b) as f64).sqrt()));
        }
    }
    if sampling == PixelSampling::Area {
        wedge = pixel_means(&wedge, grid, &fg);
    }
    let area = h * h;
    for a in 0..=half {
        for b in 0..=a {
            let (f, g) = wedge[wedge_index(a, b)];
            let value = Complex::new(area * f, area * g);
            for (x, y) in [(a, b), (b, a)] {
                for ix in [x, (n - x) % n] {
                    for iy in [y, (n - y) % n] {
                        buf[ix * n + iy] = value;
                    }
                }
            }
        }
    }
}

/// Pixel means from the centre values `wedge` (see `PixelSampling::Area`).
fn pixel_means(wedge: &[(f64, f64)], grid: FftGrid, fg: &impl Fn(f64) -> (f64, f64)) -> Vec<(f64, f64)> {
    let n = grid.size as i64;
    let half = grid.size / 2;
    let h = grid.pixel_mm();
    // |k| of a lattice index on the periodic grid.
    let fold = |k: i64| {
        let m = k.rem_euclid(n);
        m.min(n - m) as usize
    };
    let centre = |x: i64, y: i64| {
        let (p, q) = (fold(x), fold(y));
        wedge[wedge_index(p.max(q), p.min(q))]
    };
    let rules = [gauss_legendre(8), gauss_legendre(4)];
    let mut means = Vec::with_capacity(wedge.len());
    for a in 0..=half {
        for b in 0..=a {
            let mean = if a == 0 {
                centre_pixel_mean(fg, h)
            } else if a <= NEAR_PIXELS {
                // Gauss-Legendre over [a - 1/2, a + 1/2] x [b - 1/2, b + 1/2] pixels.
                let (gx, gw) = &rules[usize::from(a > 2)];
                let mut sum = (0.0, 0.0);
                for (xi, wi) in gx.iter().zip(gw) {
                    for (yj, wj) in gx.iter().zip(gw) {
                        let (x, y) = ((a as f64 + 0.5 * xi) * h, (b as f64 + 0.5 * yj) * h);
                        let (f, g) = fg(x.hypot(y));
                        sum = (sum.0 + wi * wj * f, sum.1 + wi * wj * g);
                    }
                }
                (0.25 * sum.0, 0.25 * sum.1)
            } else {
                let (ai, bi) = (a as i64, b as i64);
                let c = centre(ai, bi);
                let neighbours = [centre(ai + 1, bi), centre(ai - 1, bi), centre(ai, bi + 1), centre(ai, bi - 1)];
                let sum = neighbours.iter().fold((0.0, 0.0), |s, v| (s.0 + v.0, s.1 + v.1));
                (c.0 + (sum.0 - 4.0 * c.0) / 24.0, c.1 + (sum.1 - 4.0 * c.1) / 24.0)
            };
            means.push(mean);
        }
    }
    means
}

/// Mean of `fg` over the centre pixel: 8 int_0^(pi/4) dtheta int_0^(h / (2 cos theta)) f(r) r dr / h^2, the radial
/// integral on panels halving towards r = 0 so that a peak of width >= 1e-7 h is resolved.
fn centre_pixel_mean(fg: &impl Fn(f64) -> (f64, f64), h: f64) -> (f64, f64) {
    const PANELS: i32 = 24;
    let (x, w) = gauss_legendre(8);
    let quarter = std::f64::consts::FRAC_PI_4;
    let mut sum = (0.0, 0.0);
    for (xt, wt) in x.iter().zip(&w) {
        let theta = 0.5 * quarter * (xt + 1.0);
        let edge = 0.5 * h / theta.cos();
        // Panels [0, edge 2^-PANELS], [edge 2^-k, edge 2^(1-k)] for k = PANELS..=1.
        let mut radial = (0.0, 0.0);
        let mut lo = 0.0;
        for k in (0..=PANELS).rev() {
            let hi = edge * 0.5f64.powi(k);
            let (mid, half_width) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            for (xr, wr) in x.iter().zip(&w) {
                let r = mid + half_width * xr;
                let (f, g) = fg(r);
                radial = (radial.0 + half_width * wr * f * r, radial.1 + half_width * wr * g * r);
            }
            lo = hi;
        }
        let weight = 0.5 * quarter * wt;
        sum = (sum.0 + weight * radial.0, sum.1 + weight * radial.1);
    }
    (8.0 * sum.0 / (h * h), 8.0 * sum.1 / (h * h))
}

/// 2-D DFT of an N x N row-major buffer by rows, transpose, rows: the result is the transform transposed. Per-bin
/// products do not see the orientation, and a second call (the inverse) transposes back.
fn fft2_transposed(buf: &mut [Complex<f64>], fft: &dyn Fft<f64>, scratch: &mut [Complex<f64>], n: usize) {
    fft.process_with_scratch(buf, scratch);
    transpose_in_place(buf, n);
    fft.process_with_scratch(buf, scratch);
}

/// In-place transpose of a square N x N row-major matrix, in cache-sized blocks.
fn transpose_in_place(buf: &mut [Complex<f64>], n: usize) {
    const BLOCK: usize = 32;
    for bi in (0..n).step_by(BLOCK) {
        for bj in (bi..n).step_by(BLOCK) {
            for i in bi..(bi + BLOCK).min(n) {
                let start = if bi == bj { i + 1 } else { bj };
                for j in start..(bj + BLOCK).min(n) {
                    buf.swap(i * n + j, j * n + i);
                }
            }
        }
    }
}

/// Catmull-Rom cubic through p[1] (u = 0) and p[2] (u = 1).
fn catmull_rom(p: [f64; 4], u: f64) -> f64 {
    let [p0, p1, p2, p3] = p;
    p1 + 0.5 * u * ((p2 - p0) + u * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) + u * (3.0 * (p1 - p2) + p3 - p0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel is written once by the mirror fill, at the distance of its own centre from the point of entry.
    #[test]
    fn sampling_covers_every_pixel_at_its_radius() {
        for n in [8, 16, 64] {
            let grid = FftGrid::new(n, 3.0).unwrap();
            let mut buf = vec![Complex::new(f64::NAN, f64::NAN); n * n];
            sample_pair(&mut buf, grid, PixelSampling::Centre, |r| (r, 1.0));
            let h = grid.pixel_mm();
            let coordinate = |i: usize| if i < n / 2 { i as f64 } else { i as f64 - n as f64 } * h;
            for ix in 0..n {
                for iy in 0..n {
                    let r = coordinate(ix).hypot(coordinate(iy));
                    let v = buf[ix * n + iy];
                    assert!((v.re - h * h * r).abs() < 1e-12 && v.im == h * h, "n={n} ({ix},{iy}): {v}");
                }
            }
        }
    }

    /// Area sampling holds each pixel's mean: checked on Gaussians, whose pixel means are products of erf
    /// differences, from far narrower than the pixel (all energy in the centre pixel) to several pixels wide.
    #[test]
    fn area_sampling_gives_pixel_means_of_gaussians() {
        let n = 64;
        let grid = FftGrid::new(n, 4.0).unwrap();
        let h = grid.pixel_mm();
        for sigma in [1e-3 * h, 0.1 * h, 0.5 * h, h, 3.0 * h] {
            let gauss =
                |r: f64| (-(r * r) / (2.0 * sigma * sigma)).exp() / (2.0 * std::f64::consts::PI * sigma * sigma);
            let mut buf = vec![Complex::default(); n * n];
            sample_pair(&mut buf, grid, PixelSampling::Area, |r| (gauss(r), 2.0 * gauss(r)));
            let cdf = |x: f64| 0.5 * (1.0 + libm::erf(x / (sigma * std::f64::consts::SQRT_2)));
            let cell = |k: usize| {
                let k = if k < n / 2 { k as f64 } else { k as f64 - n as f64 };
                cdf((k + 0.5) * h) - cdf((k - 0.5) * h)
            };
            let (mut worst, mut total) = (0.0f64, 0.0);
            for ix in 0..n {
                for iy in 0..n {
                    let exact = cell(ix) * cell(iy);
                    let v = buf[ix * n + iy];
                    worst = worst.max((v.re - exact).abs()).max((v.im - 2.0 * exact).abs() / 2.0);
                    total += v.re;
                }
            }
            println!("sigma = {:.3} h: worst pixel energy error {worst:.1e}, total {total:.12}", sigma / h);
            assert!(worst < 1e-7 && (total - 1.0).abs() < 1e-7, "sigma = {sigma}: {worst:e}, total {total}");
        }
    }

    #[test]
    fn transpose_matches_definition() {
        for n in [8, 64, 96] {
            let orig: Vec<Complex<f64>> = (0..n * n).map(|k| Complex::new(k as f64, -(k as f64))).collect();
            let mut buf = orig.clone();
            transpose_in_place(&mut buf, n);
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(buf[i * n + j], orig[j * n + i], "n={n} ({i},{j})");
                }
            }
        }
    }

    /// The 2-D DFT of a plane wave is one bin (forward), and forward then inverse is N^2 times the identity.
    #[test]
    fn fft2_of_a_plane_wave_and_round_trip() {
        let n = 16;
        let plans = Plans::new(n);
        let mut scratch = vec![Complex::default(); plans.scratch_len];
        let (kx, ky) = (3usize, 5usize);
        let wave: Vec<Complex<f64>> = (0..n * n)
            .map(|p| {
                let (x, y) = (p / n, p % n);
                let phase = 2.0 * std::f64::consts::PI * ((kx * x + ky * y) as f64) / n as f64;
                Complex::new(phase.cos(), phase.sin())
            })
            .collect();
        let mut buf = wave.clone();
        fft2_transposed(&mut buf, plans.forward.as_ref(), &mut scratch, n);
        for (p, v) in buf.iter().enumerate() {
            // Transposed output: bin (kx, ky) sits at row ky, column kx.
            let expected = if p == ky * n + kx { (n * n) as f64 } else { 0.0 };
            assert!((v - Complex::new(expected, 0.0)).norm() < 1e-9, "bin {p}: {v}");
        }
        fft2_transposed(&mut buf, plans.inverse.as_ref(), &mut scratch, n);
        for (a, b) in buf.iter().zip(&wave) {
            assert!((a / (n * n) as f64 - b).norm() < 1e-12, "{} vs {b}", a / (n * n) as f64);
        }
    }

    #[test]
    fn catmull_rom_reproduces_quadratics() {
        let f = |x: f64| 2.0 - x + 0.5 * x * x;
        for u in [0.0, 0.25, 0.5, 1.0] {
            let v = catmull_rom([f(-1.0), f(0.0), f(1.0), f(2.0)], u);
            assert!((v - f(u)).abs() < 1e-12, "u={u}: {v} vs {}", f(u));
        }
    }

    /// The timing table of the module docs.
    #[test]
    #[ignore]
    fn timing_table() {
        use crate::diffusion::hankel::{reflectance_profiles, HankelQuadrature};
        use crate::skin::{skin_layers, SkinModel, SkinParams};
        use std::time::Instant;

        let params = SkinParams::preset("caucasian").unwrap();
        let (c, t) = (Combination::Directional, MultipoleTerms::All);
        let radii: Vec<f64> = (0..=40).map(|i| 0.01 * 10f64.powf(i as f64 * 3.0 / 40.0)).collect();
        let wavelengths = [450.0, 550.0, 650.0, 780.0];
        let stacks: Vec<LayerStack> = wavelengths
            .iter()
            .map(|&w| LayerStack::new(&skin_layers(&params, &SkinModel::default(), w)).unwrap())
            .collect();
        let at_550 = std::slice::from_ref(&stacks[1]);
        let exact = reflectance_profiles(&stacks, &radii, c, t, &HankelQuadrature::default());
        let mut best = f64::INFINITY;
        for _ in 0..10 {
            let start = Instant::now();
            let _ = reflectance_profiles(at_550, &radii, c, t, &HankelQuadrature::default());
            best = best.min(start.elapsed().as_secs_f64());
        }
        println!("closed form, 1 stack, 41 radii: {:.2} ms", best * 1e3);
        let totals: Vec<f64> = stacks.iter().map(|s| s.reflectance_hat(0.0, c, t)).collect();
        for sampling in [PixelSampling::Centre, PixelSampling::Area] {
            for (n, extent) in [(128, 40.0), (256, 40.0), (512, 40.0), (1024, 40.0), (1024, 20.0), (2048, 40.0)] {
                let grid = FftGrid::new(n, extent).unwrap();
                let repeats = if n <= 256 { 10 } else { 3 };
                let mut seconds = f64::INFINITY;
                for _ in 0..repeats {
                    let start = Instant::now();
                    let _ = fft_reflectance_profiles_with(at_550, &radii, c, t, grid, sampling).unwrap();
                    seconds = seconds.min(start.elapsed().as_secs_f64());
                }
                // The sampling share: the three fills of the two-layer stack.
                let mut buf = vec![Complex::default(); n * n];
                let start = Instant::now();
                let [epi, derm] = [stacks[1].slabs()[0], stacks[1].slabs()[1]];
                sample_pair(&mut buf, grid, sampling, |r| (derm.reflectance(r, t), 0.0));
                sample_pair(&mut buf, grid, sampling, |r| (epi.reflectance(r, t), epi.transmittance(r, t)));
                let up = epi.flipped();
                sample_pair(&mut buf, grid, sampling, |r| (up.reflectance(r, t), up.transmittance(r, t)));
                let filling = start.elapsed().as_secs_f64();
                let plans = Plans::new(n);
                let mut scratch = vec![Complex::default(); plans.scratch_len];
                let start = Instant::now();
                for _ in 0..4 {
                    fft2_transposed(&mut buf, plans.forward.as_ref(), &mut scratch, n);
                }
                let ffts = start.elapsed().as_secs_f64();
                let out = fft_reflectance_profiles_with(&stacks, &radii, c, t, grid, sampling).unwrap();
                let total_errors: Vec<String> =
                    out.totals.iter().zip(&totals).map(|(a, b)| format!("{:+.1e}", a / b - 1.0)).collect();
                let band = |k: usize, lo: f64, hi: f64| {
                    radii
                        .iter()
                        .zip(out.profiles[k].iter().zip(&exact[k]))
                        .filter(|(r, _)| **r >= lo && **r <= hi)
                        .map(|(_, (a, b))| (a / b - 1.0).abs())
                        .fold(0.0, f64::max)
                };
                let profile_errors: Vec<String> =
                    (0..wavelengths.len()).map(|k| format!("{:.1e}", band(k, 0.01, 10.0))).collect();
                println!(
                    "| {sampling:?} | {n:>4} | {extent:>2} | {:.4} | {:>6.1} ms | fills {:>6.1} ms, 4 FFTs {:>6.1} ms | {} | {} | 550 nm by band: 0.01-0.1 {:.1e}, 0.1-1 {:.1e}, 1-10 {:.1e}",
                    grid.pixel_mm(),
                    seconds * 1e3,
                    filling * 1e3,
                    ffts * 1e3,
                    total_errors.join(" / "),
                    profile_errors.join(" / "),
                    band(1, 0.01, 0.1),
                    band(1, 0.1, 1.0),
                    band(1, 1.0, 10.0),
                );
            }
        }
    }
}
