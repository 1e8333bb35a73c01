//! Parameter maps to Principled textures: the pipeline, its inputs and outputs, cancellation, the shader table and the Blender targets.
//!
//! One test crate of several modules: linked once (see docs/tests.md).

mod blender_targets;
mod image_inputs;
mod maps_cancel;
mod maps_extended;
mod maps_io;
mod maps_lookup_rows;
mod maps_outputs;
mod maps_pipeline;
mod maps_request;
mod maps_streaming;
mod shader_table;
mod truncated_images;
