//! The core's CIELAB and CIEDE2000 (`color::difference`) for Python: the one colour difference the fits, the reports
//! and scripts use.

use numpy::ndarray::{ArrayD, Axis};
use numpy::{AllowTypeChange, IxDyn, PyArrayDyn, PyArrayLikeDyn, PyUntypedArrayMethods, ToPyArray};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::color::difference::{ciede2000, LabConverter};
use crate::color::rgb::{WorkingSpace, ALL_WORKING_SPACES};
use crate::maps::io::{check_texel_count, MAX_TEXELS};

use super::convert::{by_name, check_array_size, shape_text};
use super::detach::detached;
use super::errors::invalid;

const RGB_EXPECTED: &str = "an array of linear RGB colours, shape (..., 3)";

/// `obj` as float64 colours of shape (..., 3), with every value finite; at most as many colours as a texture has
/// texels.
fn colours(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<[f64; 3]>)> {
    // An array's size from its shape, before it is converted to float64 (a copy for any other dtype).
    check_array_size(name, obj, RGB_EXPECTED, 3 * MAX_TEXELS)?;
    let array = obj
        .extract::<PyArrayLikeDyn<'_, f64, AllowTypeChange>>()
        .map_err(|e| PyTypeError::new_err(format!("{name} must be {RGB_EXPECTED}: {e}")))?;
    let shape = array.shape().to_vec();
    if shape.last() != Some(&3) {
        return Err(invalid(name, format!("must be {RGB_EXPECTED}; got shape {}", shape_text(&shape))));
    }
    let count: usize = shape[..shape.len() - 1].iter().product();
    check_texel_count(name, count.max(1), 1)?;
    let view = array.as_array();
    let rows = view.to_shape((count, 3)).map_err(|e| invalid(name, format!("cannot be read as (N, 3): {e}")))?;
    let mut out = Vec::with_capacity(count);
    for (i, row) in rows.axis_iter(Axis(0)).enumerate() {
        let rgb = [row[0], row[1], row[2]];
        if !rgb.iter().all(|v| v.is_finite()) {
            return Err(invalid(name, format!("must hold finite values; colour {i} is {rgb:?}")));
        }
        out.push(rgb);
    }
    Ok((shape, out))
}

fn converter(working_space: &str, white_luminance: f64) -> PyResult<(LabConverter, f64)> {
    let space: WorkingSpace = by_name("working_space", working_space, &ALL_WORKING_SPACES)?;
    if !(white_luminance.is_finite() && white_luminance > 0.0) {
        return Err(invalid("white_luminance", format!("must be finite and > 0; got {white_luminance}")));
    }
    Ok((LabConverter::new(space), white_luminance))
}

/// CIELAB (CIE 15:2004) of linear RGB colours in a working space, relative to the white RGB = (w, w, w).
///
/// Arguments:
///     rgb: linear RGB, any shape (..., 3) (lists are accepted).
///     working_space: "Linear Rec.709" (default), "Linear Rec.2020" or "ACEScg".
///     white_luminance: w, the luminance of the white (RGB = w each), > 0; default 1.
///
/// Returns:
///     float64 array of the same shape: L*, a*, b* on the last axis.
///
/// Raises:
///     SpectralSkinError: a last axis other than 3, more colours than a 16384 x 16384 texture, a value that is not
///         finite, an unknown working space, a white luminance that is not finite and positive.
#[pyfunction]
#[pyo3(name = "cielab", signature = (rgb, *, working_space = "Linear Rec.709", white_luminance = 1.0))]
pub(super) fn cielab_py<'py>(
    py: Python<'py>,
    rgb: &Bound<'py, PyAny>,
    working_space: &str,
    white_luminance: f64,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (convert, white) = converter(working_space, white_luminance)?;
    let (shape, rgb) = colours("rgb", rgb)?;
    let lab: Vec<f64> = detached(py, || Ok(rgb.iter().flat_map(|c| convert.lab(c.map(|v| v / white))).collect()))?;
    let array = ArrayD::from_shape_vec(IxDyn(&shape), lab).map_err(super::errors::internal)?;
    Ok(array.to_pyarray(py))
}

/// CIEDE2000 colour difference ΔE00 (Sharma, Wu & Dalal 2005, k_L = k_C = k_H = 1) between linear RGB colours,
/// through :func:`cielab`. About 1 is a just-noticeable difference side by side.
///
/// Arguments:
///     reference: linear RGB, any shape (..., 3).
///     test: linear RGB of the same shape.
///     working_space: as for :func:`cielab`.
///     white_luminance: as for :func:`cielab`.
///
/// Returns:
///     float64 array of shape (...): ΔE00 per colour (a 0-d array for one colour each).
///
/// Raises:
///     SpectralSkinError: as for :func:`cielab`, for either input; shapes that differ.
#[pyfunction]
#[pyo3(name = "delta_e00", signature = (reference, test, *, working_space = "Linear Rec.709", white_luminance = 1.0))]
pub(super) fn delta_e00_py<'py>(
    py: Python<'py>,
    reference: &Bound<'py, PyAny>,
    test: &Bound<'py, PyAny>,
    working_space: &str,
    white_luminance: f64,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let (convert, white) = converter(working_space, white_luminance)?;
    let (shape, reference) = colours("reference", reference)?;
    let (test_shape, test) = colours("test", test)?;
    if test_shape != shape {
        return Err(invalid(
            "test",
            format!("must have the shape of reference {}; got {}", shape_text(&shape), shape_text(&test_shape)),
        ));
    }
    let lab = |c: &[f64; 3]| convert.lab(c.map(|v| v / white));
    let differences: Vec<f64> =
        detached(py, || Ok(reference.iter().zip(&test).map(|(r, t)| ciede2000(lab(r), lab(t))).collect()))?;
    let array =
        ArrayD::from_shape_vec(IxDyn(&shape[..shape.len() - 1]), differences).map_err(super::errors::internal)?;
    Ok(array.to_pyarray(py))
}
