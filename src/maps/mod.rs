//! Parameter maps in, texture maps out: input/output, the lookup table and the pipeline.

pub mod example;
pub mod io;
pub mod kinds;
pub mod lut;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod report;
pub mod request;
pub mod shader_table;
pub mod summary;
pub mod thickness_tables;
pub mod udim;

pub use pipeline::{compute_maps, run_maps, MapReport, MapResult, MapSettings, StrategyChoice};
