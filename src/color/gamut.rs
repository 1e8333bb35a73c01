//! Colours outside the working space's gamut: the non-negative RGB of a radial profile.
//!
//! A radial profile's RGB is a linear map of its spectrum (through CIE XYZ) into the working space. Far from the
//! point of entry only long-wavelength light is left (blue and green are absorbed within a millimetre or so), and a
//! spectrum concentrated above ~600 nm is more saturated than the space's red primary: its colour lies outside the
//! gamut and one channel (green or blue) is negative. That is the exact colour, not an error, and it is what an
//! integral of the profile needs (the linear map commutes with integration, so the RGB profile integrates to the
//! RGB albedo). A renderer or a plot that cannot use negative light takes [`RgbMapping::NonNegative`].

use serde::{Deserialize, Serialize};

/// How each radius's colour of an RGB radial profile is formed (`Request::rgb_mapping`; Python's `rgb_mapping=`
/// and the CLI's `--rgb-mapping` take the same names, "linear" and "non_negative").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum RgbMapping {
    /// The spectrum's XYZ mapped linearly into the working space: the exact colour, additive and integrating to the
    /// albedo, but with a negative channel at radii whose light lies outside the gamut (the red tail).
    #[default]
    Linear,
    /// The linear colour, moved at each radius where a channel is negative along the straight line towards the grey
    /// of the same luminance Y (R = G = B = Y) just far enough that its most negative channel becomes 0: luminance
    /// and the hue (the direction from grey) are kept, saturation is reduced, and radii whose colour is in the gamut
    /// are unchanged. Not additive across radii: its integral over the plane is not the albedo.
    NonNegative,
}

/// Every mapping, the default first.
pub const ALL_RGB_MAPPINGS: [RgbMapping; 2] = [RgbMapping::Linear, RgbMapping::NonNegative];

impl RgbMapping {
    /// The serde name ("linear", "non_negative"), as Python takes it.
    pub fn name(self) -> &'static str {
        match self {
            RgbMapping::Linear => "linear",
            RgbMapping::NonNegative => "non_negative",
        }
    }

    /// True for the default, [`RgbMapping::Linear`].
    pub fn is_linear(&self) -> bool {
        *self == RgbMapping::Linear
    }

    /// The colour `rgb` (linear, in a working space whose luminance is `luminance` . rgb, with luminance summing to
    /// 1 so that grey (Y, Y, Y) has luminance Y) under this mapping.
    pub fn apply(self, rgb: [f64; 3], luminance: [f64; 3]) -> [f64; 3] {
        match self {
            RgbMapping::Linear => rgb,
            RgbMapping::NonNegative => desaturate_to_non_negative(rgb, luminance),
        }
    }
}

/// The point of the segment from `rgb` to the grey of the same luminance that is nearest to `rgb` with no negative
/// channel: `grey + t (rgb - grey)` with the largest t in [0, 1] that keeps every channel >= 0. A colour with no
/// negative channel is returned unchanged; a colour whose luminance is not positive (no light) becomes black.
pub fn desaturate_to_non_negative(rgb: [f64; 3], luminance: [f64; 3]) -> [f64; 3] {
    if rgb.iter().all(|&c| c >= 0.0) {
        return rgb;
    }
    let y = luminance[0] * rgb[0] + luminance[1] * rgb[1] + luminance[2] * rgb[2];
    if y.is_nan() || y <= 0.0 {
        return [0.0; 3];
    }
    // Channel c reaches 0 at t = y / (y - rgb[c]) (rgb[c] < 0 < y, so 0 < t < 1); the most negative channel does so
    // first and bounds t. It is set to 0 exactly (its formula leaves round-off of either sign).
    let mut bound = 0;
    for c in 1..3 {
        if rgb[c] < rgb[bound] {
            bound = c;
        }
    }
    let t = y / (y - rgb[bound]);
    let mut out = rgb.map(|c| y + t * (c - y));
    out[bound] = 0.0;
    // The other channels are >= min(y, their own value) > 0 up to round-off; max(0) removes only that.
    out.map(|c| c.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rec.709's luminance row (ITU-R BT.709-6 item 3.2: Y = 0.2126 R + 0.7152 G + 0.0722 B).
    const BT709_LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

    fn luma(rgb: [f64; 3]) -> f64 {
        (0..3).map(|c| BT709_LUMA[c] * rgb[c]).sum()
    }

    #[test]
    fn in_gamut_colours_are_unchanged() {
        for rgb in [[0.0, 0.0, 0.0], [0.5, 0.2, 0.1], [3.0, 0.0, 1e-300], [1.0, 1.0, 1.0]] {
            assert_eq!(desaturate_to_non_negative(rgb, BT709_LUMA), rgb, "{rgb:?}");
            assert_eq!(RgbMapping::Linear.apply([-1.0, 2.0, 0.5], BT709_LUMA), [-1.0, 2.0, 0.5], "{rgb:?}");
        }
    }

    /// A hand-worked case: (1, -0.1, 0.2) has Y = 0.2126 - 0.07152 + 0.01444 = 0.15552; green reaches 0 at
    /// t = 0.15552 / 0.25552; then R = Y + t (1 - Y), B = Y + t (0.2 - Y).
    #[test]
    fn out_of_gamut_colour_goes_to_the_boundary_at_the_same_luminance() {
        let rgb = [1.0, -0.1, 0.2];
        let out = desaturate_to_non_negative(rgb, BT709_LUMA);
        let (y, t) = (0.15552, 0.15552 / 0.25552);
        let expected = [y + t * (1.0 - y), 0.0, y + t * (0.2 - y)];
        for c in 0..3 {
            assert!((out[c] - expected[c]).abs() < 1e-12, "{out:?} vs {expected:?}");
        }
        assert!((luma(out) - luma(rgb)).abs() < 1e-12, "{} vs {}", luma(out), luma(rgb));
    }

    /// Random colours with negative channels: every channel >= 0, one of them 0 (on the boundary, not inside), the
    /// same luminance, and on the line through the grey of that luminance (same hue direction).
    #[test]
    fn random_out_of_gamut_colours() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 1.0
        };
        let mut tried = 0;
        while tried < 10_000 {
            let rgb = [next(), next(), next()];
            let y = luma(rgb);
            if rgb.iter().all(|&c| c >= 0.0) || y <= 0.0 {
                continue;
            }
            tried += 1;
            let out = desaturate_to_non_negative(rgb, BT709_LUMA);
            assert!(out.iter().all(|&c| c >= 0.0), "{rgb:?} -> {out:?}");
            assert!(out.contains(&0.0), "{rgb:?} -> {out:?} is inside the gamut");
            assert!((luma(out) - y).abs() <= 1e-12 * (1.0 + y.abs()), "{rgb:?} -> {out:?}");
            // out - grey = t (rgb - grey): the cross product of the two differences vanishes.
            let (a, b) = ([0, 1, 2].map(|c| out[c] - y), [0, 1, 2].map(|c| rgb[c] - y));
            let cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            assert!(cross.iter().all(|v| v.abs() < 1e-9), "{rgb:?} -> {out:?}");
        }
    }

    #[test]
    fn no_light_is_black() {
        assert_eq!(desaturate_to_non_negative([-1.0, 0.1, 0.1], BT709_LUMA), [0.0; 3]);
    }

    #[test]
    fn names_are_serde_names() {
        for m in ALL_RGB_MAPPINGS {
            assert_eq!(serde_json::to_string(&m).unwrap(), format!("\"{}\"", m.name()), "{m:?}");
        }
    }
}
