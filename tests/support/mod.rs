//! Shared helpers for the integration tests (`mod support;`).
#![allow(dead_code)]

pub mod mc;
pub mod measured;
pub mod profile_figures;
