//! Layers combined in the Hankel domain by the adding equations (DJ05; docs/model.md, section Adding layers):
//! R12 = R1+ + T1+ R2 T1- / (1 - R2 R1-), applied from the bottom layer up.

use serde::{Deserialize, Serialize};

use super::multipole::{ballistic_fraction, MultipoleTerms, Slab};
use crate::error::SkinError;
use crate::layer::{validate_layers, Layer};
use crate::numeric::safe_div;

/// Index of refraction of the medium above the stack (air).
pub const AMBIENT_IOR: f64 = 1.0;
/// Smallest denominator of the adding equation; it is 1 - R2 R1- with both below 1 unless nothing is absorbed.
const MIN_ADDING_DENOMINATOR: f64 = 1e-300;

/// Which transport through the top layer the combination uses (docs/model.md, section Adding layers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Combination {
    /// R-, T- computed with the layer's boundaries swapped: light returning from below sees the layer from below.
    #[default]
    Directional,
    /// DJ05's published form: the same R1, T1 (those seen from above) for both directions.
    Symmetric,
}

/// How a stack sets up its boundaries (docs/robustness.md, "Negative profile lobes and monotonicity"). Python's
/// `boundaries=` and the CLI's `--boundaries` take the serde names ("paper", "capped").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Boundaries {
    /// The default: each face's extrapolation distance is z_b = 2 A D (DJ05), whatever the thickness, and across a
    /// layer thinner than one reduced mean free path its neighbours see the index blend with weight w = b, its
    /// ballistic share (1 - tau)^2 (see [`LayerStack::new`]). Where a slab's z_b,0 exceeds d + z_b,d its own R(r) has
    /// a negative tail (`Slab::capped`); the skin presets' epidermis is such a slab in the red, filled by the dermis,
    /// and there this agrees with Monte Carlo better than `Capped` does.
    #[default]
    Paper,
    /// Every slab capped (`Slab::capped`): every slab's R(r) and T(r), from either side, is >= 0, and so is every
    /// stack's exact profile (the adding series is a sum of convolutions of them); the numerical inverse transform can
    /// still dip below zero, which is reported as a lobe of these boundaries (`NegativeLobe`). And the blend weight is the share that
    /// crosses without scattering, w = (1 - sigma_s' d)^2 below sigma_s' d = 1, which absorption does not change (light
    /// absorbed in a thin layer reveals no index): with both, more absorption never gives more reflectance
    /// (tests/physics/robustness_properties.rs). Where no cap acts and every finite layer has sigma_s' d >= 1 it is the paper's
    /// stack, bit for bit. Not the default: it moves the presets' red and thin epidermis away from Monte Carlo
    /// (docs/robustness.md).
    Capped,
}

/// Every combination, the default first.
pub const ALL_COMBINATIONS: [Combination; 2] = [Combination::Directional, Combination::Symmetric];

/// Every choice of boundaries, the default first.
pub const ALL_BOUNDARIES: [Boundaries; 2] = [Boundaries::Paper, Boundaries::Capped];

impl Boundaries {
    /// Whether this is the default (for `skip_serializing_if`: requests with the paper's boundaries keep the JSON,
    /// and so the table-cache keys, they had before the choice existed).
    pub fn is_paper(&self) -> bool {
        *self == Boundaries::Paper
    }
}

/// A validated stack of layers under air, reduced to slabs seen from above (`Slab::flipped` sees them from below).
#[derive(Debug, Clone)]
pub struct LayerStack {
    down: Vec<Slab>,
    boundaries: Boundaries,
}

impl LayerStack {
    /// Validate the layers (top to bottom) and set up their boundaries ([`Boundaries::Paper`]). A finite last layer
    /// rests on a medium of its own index; the medium above the first layer is air.
    ///
    /// A layer thinner than one reduced mean free path lets a share b of the light through without interacting (see
    /// `Slab::new`); its neighbours then see, for the index across their shared boundary, the blend w n' + (1 - w) n
    /// of its own index n and of what lies beyond it n', with w = b. As a layer vanishes (w -> 1) its neighbours thus
    /// meet each other's indices, as in the stack without it; at w = 0 (any layer of one mean free path or more)
    /// nothing changes.
    pub fn new(layers: &[Layer]) -> Result<LayerStack, SkinError> {
        LayerStack::with_boundaries(layers, Boundaries::Paper)
    }

    /// [`LayerStack::new`] with the boundaries set up as `boundaries` says.
    pub fn with_boundaries(layers: &[Layer], boundaries: Boundaries) -> Result<LayerStack, SkinError> {
        validate_layers(layers)?;
        let last = layers.len() - 1;
        // The blend weight w of each layer (1 - w of its own index, w of what lies beyond it).
        let ballistic: Vec<f64> = layers
            .iter()
            .map(|l| {
                if !l.thickness_mm.is_finite() {
                    return 0.0;
                }
                match boundaries {
                    Boundaries::Paper => ballistic_fraction(l.sigma_a_per_mm, l.sigma_s_reduced_per_mm, l.thickness_mm),
                    Boundaries::Capped => ballistic_fraction(0.0, l.sigma_s_reduced_per_mm, l.thickness_mm),
                }
            })
            .collect();
        // Index seen above each layer, top down, and below each layer, bottom up.
        let mut above = vec![AMBIENT_IOR; layers.len()];
        for i in 1..layers.len() {
            let b = ballistic[i - 1];
            above[i] = b * above[i - 1] + (1.0 - b) * layers[i - 1].ior;
        }
        // Below the last layer: a medium of its own index, or, as far as the last layer lets light through
        // unscattered, of the index it sees above (so a vanishing last layer leaves the one above on its own index).
        let b_last = ballistic[last];
        let mut below = vec![b_last * above[last] + (1.0 - b_last) * layers[last].ior; layers.len()];
        for i in (0..last).rev() {
            let b = ballistic[i + 1];
            below[i] = b * below[i + 1] + (1.0 - b) * layers[i + 1].ior;
        }
        let down = layers
            .iter()
            .enumerate()
            .map(|(i, layer)| {
                let slab = Slab::new(
                    layer.sigma_a_per_mm,
                    layer.sigma_s_reduced_per_mm,
                    layer.thickness_mm,
                    layer.ior / above[i],
                    layer.ior / below[i],
                );
                match boundaries {
                    Boundaries::Paper => slab,
                    Boundaries::Capped => slab.capped(),
                }
            })
            .collect();
        Ok(LayerStack { down, boundaries })
    }

    /// How the stack's boundaries were set up.
    pub fn boundaries(&self) -> Boundaries {
        self.boundaries
    }

    /// The top layer's slab, seen from above.
    pub fn top(&self) -> &Slab {
        &self.down[0]
    }

    /// The slabs, top to bottom, each seen from above.
    pub fn slabs(&self) -> &[Slab] {
        &self.down
    }

    /// `R~12(s) - R~1+(s)`: light that has crossed the top layer at least twice. Its inverse transform is smooth and
    /// decays fast in s, unlike R~1+ whose real-space form is known (see `hankel`).
    pub fn below_top_hat(&self, s_per_mm: f64, combination: Combination, terms: MultipoleTerms) -> f64 {
        if self.down.len() == 1 {
            return 0.0;
        }
        let below = self.reflectance_hat_from(1, s_per_mm, combination, terms);
        let hats = self.down[0].hats_both_ways(s_per_mm, terms);
        bounce_term(hats, below, combination)
    }

    /// `R~(s)` of the whole stack; `R~(0)` is the total diffuse reflectance.
    pub fn reflectance_hat(&self, s_per_mm: f64, combination: Combination, terms: MultipoleTerms) -> f64 {
        self.reflectance_hat_from(0, s_per_mm, combination, terms)
    }

    /// `R~` of the layers from `first` down (adding equation, bottom up).
    fn reflectance_hat_from(&self, first: usize, s: f64, combination: Combination, terms: MultipoleTerms) -> f64 {
        let last = self.down.len() - 1;
        let mut below = self.down[last].reflectance_hat(s, terms);
        for i in (first..last).rev() {
            let hats = self.down[i].hats_both_ways(s, terms);
            below = hats[0] + bounce_term(hats, below, combination);
        }
        below
    }
}

/// `T~i+ R~below T~i- / (1 - R~below R~i-)`: every path that crosses a layer, returns from below and crosses it
/// again. `hats` = [R~+, T~+, R~-, T~-] of the layer; the symmetric form uses the "+" pair both ways.
pub(crate) fn bounce_term(hats: [f64; 4], below: f64, combination: Combination) -> f64 {
    let [r_down, t_down, r_up, t_up] = hats;
    let (r_up, t_up) = match combination {
        Combination::Directional => (r_up, t_up),
        Combination::Symmetric => (r_down, t_down),
    };
    let denominator = (1.0 - below * r_up).max(MIN_ADDING_DENOMINATOR);
    safe_div(t_down * below * t_up, denominator, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer(t: f64, sa: f64, ss: f64, n: f64) -> Layer {
        Layer { thickness_mm: t, sigma_a_per_mm: sa, sigma_s_reduced_per_mm: ss, ior: n }
    }

    #[test]
    fn validation_names_layer_and_field() {
        let e = LayerStack::new(&[layer(f64::INFINITY, 0.1, 1.0, 1.4), layer(1.0, 0.1, 1.0, 1.4)]).unwrap_err();
        assert!(e.to_string().contains("layer 0") && e.to_string().contains("thickness_mm"), "{e}");
        let e = LayerStack::new(&[layer(1.0, -0.1, 1.0, 1.4)]).unwrap_err();
        assert!(e.to_string().contains("sigma_a_per_mm"), "{e}");
        let e = LayerStack::new(&[layer(1.0, 0.1, f64::NAN, 1.4)]).unwrap_err();
        assert!(e.to_string().contains("sigma_s_reduced_per_mm"), "{e}");
        let e = LayerStack::new(&[layer(1.0, 0.1, 1.0, 0.5)]).unwrap_err();
        assert!(e.to_string().contains("ior"), "{e}");
        assert!(LayerStack::new(&[]).is_err(), "{:?}", LayerStack::new(&[]));
        assert!(
            LayerStack::new(&[layer(1.0, 0.0, 0.0, 1.4)]).is_err(),
            "{:?}",
            LayerStack::new(&[layer(1.0, 0.0, 0.0, 1.4)])
        );
    }

    /// A very thick slab is the semi-infinite medium.
    #[test]
    fn thick_slab_is_semi_infinite() {
        let thick = LayerStack::new(&[layer(200.0, 0.05, 2.0, 1.4)]).unwrap();
        let semi = LayerStack::new(&[layer(f64::INFINITY, 0.05, 2.0, 1.4)]).unwrap();
        for s in [0.0, 0.5, 5.0] {
            let a = thick.reflectance_hat(s, Combination::Directional, MultipoleTerms::All);
            let b = semi.reflectance_hat(s, Combination::Directional, MultipoleTerms::All);
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
    }

    /// Two stacked identical index-matched layers are one layer of the summed thickness (the adding equation is exact
    /// for the image series only approximately, so this holds to the accuracy of diffusion's layer splitting).
    #[test]
    fn split_layer_matches_whole() {
        let whole = LayerStack::new(&[layer(f64::INFINITY, 0.05, 2.0, 1.4)]).unwrap();
        let split = LayerStack::new(&[layer(0.3, 0.05, 2.0, 1.4), layer(f64::INFINITY, 0.05, 2.0, 1.4)]).unwrap();
        let a = whole.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
        let b = split.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All);
        assert!(((a - b) / a).abs() < 0.05, "whole {a} split {b}");
    }
}
