//! Python bindings (`spectral_skin._core`, built by maturin with the `python` feature). Bindings only: every function
//! reads its arguments under the GIL, makes one core call with the GIL released, and converts the result. No physics
//! lives here; names of outputs, combinations and working spaces come from the core's serde names.

mod args;
mod catalog;
#[cfg(feature = "cli")]
mod cli;
mod color;
mod convert;
mod detach;
mod errors;
mod evaluate;
mod inverse;
mod inverse_albedo;
mod inverse_batch;
mod maps;
mod maps_result;
mod maps_write;
mod progress;
mod shader_table;
mod stamp;
mod surface;

use pyo3::prelude::*;

use catalog::{
    accuracy_levels_py, blender_targets_py, parameter_ranges_py, parameters_py, presets_py, surface_models_py,
    transports_py,
};
use color::{cielab_py, delta_e00_py};
use errors::{SpectralSkinError, SpectralSkinIOError, SpectralSkinWarning};
use evaluate::{evaluate_py, layered_reflectance_py, profile_py};
use inverse::fit_spectrum_py;
use inverse_albedo::{fit_albedo_map_py, fit_albedo_py, AlbedoMapFitPy};
use inverse_batch::fit_spectra_py;
use maps::{map_kinds_py, maps_py, read_parameter_map_py};
use maps_result::{write_maps_py, MapsPy};
use shader_table::{shader_table_py, write_shader_table_py};
use surface::{surface_albedo_py, surface_brdf_py, surface_input_nodes_py};

/// spectral-skin's compiled core: Donner & Jensen 2006's spectral skin BSSRDF.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SpectralSkinError", m.py().get_type::<SpectralSkinError>())?;
    m.add("SpectralSkinWarning", m.py().get_type::<SpectralSkinWarning>())?;
    m.add("SpectralSkinIOError", m.py().get_type::<SpectralSkinIOError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MODEL_VERSION", crate::stamp::MODEL_VERSION)?;
    m.add_function(wrap_pyfunction!(stamp::markdown_stamp_py, m)?)?;
    m.add_function(wrap_pyfunction!(stamp::write_markdown_blocks_py, m)?)?;
    m.add_function(wrap_pyfunction!(stamp::stamp_png_py, m)?)?;
    m.add_function(wrap_pyfunction!(stamp::png_stamp_version_py, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_py, m)?)?;
    m.add_function(wrap_pyfunction!(profile_py, m)?)?;
    m.add_function(wrap_pyfunction!(presets_py, m)?)?;
    m.add_function(wrap_pyfunction!(parameter_ranges_py, m)?)?;
    m.add_function(wrap_pyfunction!(parameters_py, m)?)?;
    m.add_function(wrap_pyfunction!(accuracy_levels_py, m)?)?;
    m.add_function(wrap_pyfunction!(transports_py, m)?)?;
    m.add_function(wrap_pyfunction!(surface_models_py, m)?)?;
    m.add_function(wrap_pyfunction!(layered_reflectance_py, m)?)?;
    m.add_function(wrap_pyfunction!(maps_py, m)?)?;
    m.add_function(wrap_pyfunction!(map_kinds_py, m)?)?;
    m.add_function(wrap_pyfunction!(blender_targets_py, m)?)?;
    m.add_function(wrap_pyfunction!(read_parameter_map_py, m)?)?;
    m.add_function(wrap_pyfunction!(write_maps_py, m)?)?;
    m.add_function(wrap_pyfunction!(shader_table_py, m)?)?;
    m.add_function(wrap_pyfunction!(write_shader_table_py, m)?)?;
    m.add_function(wrap_pyfunction!(fit_albedo_py, m)?)?;
    m.add_function(wrap_pyfunction!(fit_albedo_map_py, m)?)?;
    m.add_class::<AlbedoMapFitPy>()?;
    m.add_class::<MapsPy>()?;
    // A maps() result reads like the dict it replaced: a Mapping for isinstance (its methods are its own).
    m.py().import("collections.abc")?.getattr("Mapping")?.call_method1("register", (m.py().get_type::<MapsPy>(),))?;
    m.add_function(wrap_pyfunction!(fit_spectrum_py, m)?)?;
    m.add_function(wrap_pyfunction!(fit_spectra_py, m)?)?;
    m.add_function(wrap_pyfunction!(cielab_py, m)?)?;
    m.add_function(wrap_pyfunction!(delta_e00_py, m)?)?;
    m.add_function(wrap_pyfunction!(surface_brdf_py, m)?)?;
    m.add_function(wrap_pyfunction!(surface_albedo_py, m)?)?;
    m.add_function(wrap_pyfunction!(surface_input_nodes_py, m)?)?;
    #[cfg(feature = "cli")]
    m.add_function(wrap_pyfunction!(cli::cli_main_py, m)?)?;
    Ok(())
}
