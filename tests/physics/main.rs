//! The forward model against independent references: published numbers, converged quadrature, Monte Carlo, exact transport, and its robustness on the whole accepted range.
//!
//! One test crate of several modules: linked once (see docs/tests.md).

#[path = "../support/mod.rs"]
mod support;

mod accuracy;
mod aperture;
mod cancel_latency;
mod diffusion_references;
mod doc_stamps;
mod exact_profile;
mod exact_transport;
mod fft_route;
mod model_version;
mod monte_carlo;
mod physiology;
mod profile_rgb_mapping;
mod reference_numbers;
mod robustness;
mod robustness_properties;
mod total_table;
mod transport_fronts;
mod transport_limits;
mod transport_properties;
