//! The forward model against independent references: published numbers, converged quadrature, Monte Carlo, exact transport, and its robustness on the whole accepted range.
//!
//! One test crate of several modules: linked once (see docs/tests.md).

#[path = "../support/mod.rs"]
mod support;

mod reference_numbers;
mod diffusion_references;
mod monte_carlo;
mod exact_transport;
mod transport_properties;
mod transport_fronts;
mod fft_route;
mod accuracy;
mod physiology;
mod robustness;
mod robustness_properties;
mod profile_rgb_mapping;
