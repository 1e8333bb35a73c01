//! The skin surface's reflection (`surface::lobes`) for Python: its BRDF over arrays of angles and its directional
//! albedo.

use std::sync::atomic::AtomicBool;

use numpy::ndarray::{ArrayD, ArrayViewD};
use numpy::{
    AllowTypeChange, IxDyn, PyArrayDescrMethods, PyArrayDyn, PyArrayLikeDyn, PyUntypedArray, PyUntypedArrayMethods,
    ToPyArray,
};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::maps::io::check_texel_count;
use crate::surface::lobes::{SurfaceModel, SurfaceReflection};
use crate::surface::principled::surface_input_nodes;

use super::args::{named, Choice};
use super::convert::{real_arg, shape_text, target_from};
use super::detach::{detached, detached_interruptible};
use super::errors::{internal, invalid};

const ANGLES: &str = "a number or an array of numbers (degrees)";
/// The oiliness when none is given: the presets' 0.3 (`skin::params::PRESETS`).
const DEFAULT_OILINESS: f64 = 0.3;
/// The relative azimuth when none is given: the plane of mirror reflection.
const DEFAULT_PHI_DEG: f64 = 180.0;

/// `obj` as a float64 array of any shape (a number: shape ()), read through `numpy.asarray`: ints and floats only (a
/// bool, str or other dtype is a TypeError naming `name`); at most as many values as a 16384 x 16384 texture has
/// texels.
fn angles<'py>(
    py: Python<'py>,
    name: &str,
    obj: &Bound<'py, PyAny>,
) -> PyResult<PyArrayLikeDyn<'py, f64, AllowTypeChange>> {
    let array = py.import("numpy")?.call_method1("asarray", (obj,))?;
    let untyped = array.cast::<PyUntypedArray>().map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?;
    if !matches!(untyped.dtype().kind(), b'f' | b'i' | b'u') {
        return Err(PyTypeError::new_err(format!(
            "{name} must be {ANGLES}; got an array of dtype {}",
            untyped.dtype()
        )));
    }
    check_texel_count(name, untyped.len().max(1), 1)?;
    array
        .extract::<PyArrayLikeDyn<'py, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("{name} must be {ANGLES}: {e}")))
}

/// The shape numpy broadcasts `shapes` to (trailing axes aligned; each of length 1 or the common length), else an
/// error naming the arguments.
fn broadcast_shape(named: &[(&str, &[usize])]) -> PyResult<Vec<usize>> {
    let ndim = named.iter().map(|(_, s)| s.len()).max().unwrap_or(0);
    let mut shape = vec![1usize; ndim];
    for (_, s) in named {
        for (k, &n) in s.iter().enumerate() {
            let axis = ndim - s.len() + k;
            if shape[axis] == 1 {
                shape[axis] = n;
            } else if n != 1 && n != shape[axis] {
                let names: Vec<&str> = named.iter().map(|(n, _)| *n).collect();
                let shapes: Vec<String> = named.iter().map(|(_, s)| shape_text(s)).collect();
                return Err(invalid(
                    names.join(", "),
                    format!("shapes {} do not broadcast together", shapes.join(", ")),
                ));
            }
        }
    }
    Ok(shape)
}

/// `view` broadcast to `shape`, its values in row-major order.
fn broadcast_values(view: ArrayViewD<'_, f64>, shape: &[usize]) -> PyResult<Vec<f64>> {
    Ok(view
        .broadcast(IxDyn(shape))
        .ok_or_else(|| internal("an angle array does not broadcast"))?
        .iter()
        .copied()
        .collect())
}

/// The model named `surface` at `oiliness` (None: 0.3).
fn reflection(surface: &str, oiliness: Option<&Bound<'_, PyAny>>) -> PyResult<SurfaceReflection> {
    let model: SurfaceModel = named(surface)?;
    let oiliness = real_arg("oiliness", oiliness)?.map_or(DEFAULT_OILINESS, |r| r.0);
    Ok(SurfaceReflection::new(model, oiliness)?)
}

/// The skin surface's BRDF f_r, sr^-1, by numpy broadcasting over the angle arrays (docs/model.md, "Surface
/// reflection: measured two-lobe model").
///
/// Angles are in degrees: polar angles from the surface normal, and the outgoing direction's azimuth relative to the
/// incident one (180, the default, is the plane of mirror reflection: in-plane slices). "measured" is two Beckmann
/// lobes (a broad one for the rough stratum corneum, a sharp one that oil strengthens and smooths) sharing the
/// Fresnel term of the skin surface (index 1.4, F0 = 0.028), so dry skin reflects too; "paper" is Donner & Jensen
/// 2006's oil layer, one lobe scaled by the oiliness (none at oiliness 0).
///
/// Arguments:
///     theta_in_deg: incident polar angle(s), degrees in [0, 90); a number or an array.
///     theta_out_deg: outgoing polar angle(s), degrees in [0, 90); a number or an array.
///     phi_deg: outgoing azimuth relative to the incident direction, degrees (any finite value); default 180.
///     oiliness: 0..1; default 0.3 (the presets').
///     surface: "measured" (default) or "paper".
///
/// Returns:
///     float64 array of the three arguments' broadcast shape (a 0-d array for three numbers): f_r in sr^-1.
///
/// Raises:
///     SpectralSkinError: an angle outside its range or not finite, an oiliness outside [0, 1] or not finite, an
///         unknown surface, shapes that do not broadcast, more values than a 16384 x 16384 texture.
///     TypeError: an angle array of bools, strings or another dtype; an oiliness that is not a number.
#[pyfunction]
#[pyo3(
    name = "surface_brdf",
    signature = (theta_in_deg, theta_out_deg, phi_deg = None, *, oiliness = None, surface = "measured"),
    text_signature = "(theta_in_deg, theta_out_deg, phi_deg=180.0, *, oiliness=0.3, surface='measured')"
)]
pub(super) fn surface_brdf_py<'py>(
    py: Python<'py>,
    theta_in_deg: &Bound<'py, PyAny>,
    theta_out_deg: &Bound<'py, PyAny>,
    phi_deg: Option<&Bound<'py, PyAny>>,
    oiliness: Option<&Bound<'py, PyAny>>,
    surface: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let s = reflection(surface, oiliness)?;
    let theta_in = angles(py, "theta_in_deg", theta_in_deg)?;
    let theta_out = angles(py, "theta_out_deg", theta_out_deg)?;
    let default_phi;
    let phi = match phi_deg.filter(|p| !p.is_none()) {
        Some(p) => p,
        None => {
            default_phi = DEFAULT_PHI_DEG.into_pyobject(py)?.into_any();
            &default_phi
        }
    };
    let phi = angles(py, "phi_deg", phi)?;
    let (a, b, c) = (theta_in.as_array(), theta_out.as_array(), phi.as_array());
    let shape = broadcast_shape(&[("theta_in_deg", a.shape()), ("theta_out_deg", b.shape()), ("phi_deg", c.shape())])?;
    let count = shape.iter().try_fold(1usize, |n, &k| n.checked_mul(k)).unwrap_or(usize::MAX);
    check_texel_count("theta_in_deg, theta_out_deg, phi_deg", count.max(1), 1)?;
    let (a, b, c) = (broadcast_values(a, &shape)?, broadcast_values(b, &shape)?, broadcast_values(c, &shape)?);
    let values = detached(py, || s.f_r_per_sr_each(&a, &b, &c))?;
    Ok(ArrayD::from_shape_vec(IxDyn(&shape), values).map_err(internal)?.to_pyarray(py))
}

/// The skin surface's directional albedo E(θ_in) = ∫ f_r cos θ_out dω_out: the share of light arriving from θ_in
/// that the surface reflects, dimensionless, of the model :func:`surface_brdf` evaluates. Each distinct angle is
/// integrated once (about 2 ms), in parallel; Ctrl-C stops the work.
///
/// Arguments:
///     theta_in_deg: incident polar angle(s), degrees in [0, 90); a number or an array.
///     oiliness: 0..1; default 0.3 (the presets').
///     surface: "measured" (default) or "paper".
///
/// Returns:
///     float64 array of theta_in_deg's shape (a 0-d array for a number): E, dimensionless. E at 0 degrees is the
///     normal-incidence reflectance.
///
/// Raises:
///     SpectralSkinError: an angle outside [0, 90) or not finite, an oiliness outside [0, 1] or not finite, an
///         unknown surface, more values than a 16384 x 16384 texture.
///     TypeError: an angle array of bools, strings or another dtype; an oiliness that is not a number.
///     KeyboardInterrupt: Ctrl-C while it computes.
#[pyfunction]
#[pyo3(
    name = "surface_albedo",
    signature = (theta_in_deg, *, oiliness = None, surface = "measured"),
    text_signature = "(theta_in_deg, *, oiliness=0.3, surface='measured')"
)]
pub(super) fn surface_albedo_py<'py>(
    py: Python<'py>,
    theta_in_deg: &Bound<'py, PyAny>,
    oiliness: Option<&Bound<'py, PyAny>>,
    surface: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let s = reflection(surface, oiliness)?;
    let theta_in = angles(py, "theta_in_deg", theta_in_deg)?;
    let view = theta_in.as_array();
    let shape = view.shape().to_vec();
    let thetas: Vec<f64> = view.iter().copied().collect();
    let cancel = AtomicBool::new(false);
    let values = detached_interruptible(py, &cancel, || s.directional_albedo_each(&thetas, &cancel))?;
    Ok(ArrayD::from_shape_vec(IxDyn(&shape), values).map_err(internal)?.to_pyarray(py))
}

/// The surface's Principled inputs that depend on the oiliness, at nodes between which they are linear (exact for
/// the level and the Coat Weight; the Coat Roughness within 6e-5): what a shader that computes them from an oiliness
/// input interpolates (the add-on's Live node group), and what ``maps`` and ``evaluate`` give at those oiliness values.
///
/// Arguments:
///     surface: "measured" or "paper" (as ``surface=`` of :func:`evaluate`).
///     blender, engine: the target, as for :func:`evaluate` (the measured level is calibrated per engine).
///
/// Returns:
///     {"surface", "oiliness": [o_0 = 0, ..., 1], "specular_ior_level": [...], "coat_weight": [...],
///     "coat_roughness": [...]}: lists of one value per node, the oiliness ascending.
///
/// Raises:
///     SpectralSkinError: an unknown surface, engine or Blender version.
#[pyfunction]
#[pyo3(name = "surface_input_nodes", signature = (surface = None, *, blender = None, engine = "cycles"))]
pub(super) fn surface_input_nodes_py<'py>(
    py: Python<'py>,
    surface: Option<Choice<SurfaceModel>>,
    blender: Option<&Bound<'py, PyAny>>,
    engine: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let model = surface.map(|c| c.0).unwrap_or_default();
    let target = target_from(blender, engine)?;
    let nodes = surface_input_nodes(model, target.engine);
    let dict = PyDict::new(py);
    dict.set_item("surface", model.name())?;
    dict.set_item("oiliness", nodes.iter().map(|n| n.0).collect::<Vec<_>>())?;
    dict.set_item("specular_ior_level", nodes.iter().map(|n| n.1.specular_ior_level).collect::<Vec<_>>())?;
    dict.set_item("coat_weight", nodes.iter().map(|n| n.1.coat_weight).collect::<Vec<_>>())?;
    dict.set_item("coat_roughness", nodes.iter().map(|n| n.1.coat_roughness).collect::<Vec<_>>())?;
    Ok(dict)
}
