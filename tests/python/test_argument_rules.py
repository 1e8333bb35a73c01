"""One rule for every argument of the bindings: a bool, a str, a wrong dtype, shape or a NaN is an error whose message
names the argument (TypeError for a wrong type, SpectralSkinError, a ValueError, for a wrong value); non-contiguous
and read-only numpy arrays are read as they are."""

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

SEMI = (float("inf"), 0.02, 2.0, 1.4)
# The numeric keywords of evaluate/profile, with a valid value each (so only the wrong type can fail).
REAL_KEYWORDS = {"wavelength_step_nm": 10.0, "profile_r_min_mm": 0.01, "profile_r_max_mm": 10.0}
INTEGER_KEYWORDS = {"multipole_pairs": 3, "profile_count": 16}
PARAMETERS = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
NOT_NUMBERS = (True, False, np.bool_(True), "0.1", b"0.1")


def params_array(h=3, w=3, seed=0):
    rng = np.random.default_rng(seed)
    ranges = spectral_skin.parameter_ranges()
    lo = np.array([ranges[p][0] for p in PARAMETERS])
    hi = np.array([ranges[p][1] for p in PARAMETERS])
    return (lo + (hi - lo) * rng.random((h, w, 4))).astype(np.float32)


def raises_naming(exception, name, call):
    with pytest.raises(exception) as info:
        call()
    assert name in str(info.value), (name, str(info.value))


@pytest.mark.parametrize("function", [spectral_skin.evaluate, spectral_skin.profile])
@pytest.mark.parametrize("bad", NOT_NUMBERS, ids=repr)
def test_every_numeric_keyword_rejects_bool_and_str(function, bad):
    for name in (*REAL_KEYWORDS, *INTEGER_KEYWORDS):
        raises_naming(TypeError, name, lambda name=name: function(preset="asian", **{name: bad}))
    for name in PARAMETERS:
        raises_naming(TypeError, name, lambda name=name: function(preset="asian", **{name: bad}))


def test_positional_string_parameter_names_the_argument():
    raises_naming(TypeError, "melanin", lambda: spectral_skin.evaluate("0.1", 0.5, 0.05, 0.5))
    raises_naming(TypeError, "hemoglobin", lambda: spectral_skin.evaluate(0.1, 0.5, True, 0.5))


def test_integer_keywords_reject_floats():
    for name in INTEGER_KEYWORDS:
        raises_naming(TypeError, name, lambda name=name: spectral_skin.evaluate(preset="asian", **{name: 16.0}))


def test_numpy_number_scalars_are_accepted():
    a = spectral_skin.evaluate(preset="asian", wavelength_step_nm=np.float32(10.0), multipole_pairs=np.int64(3))
    b = spectral_skin.evaluate(preset="asian", wavelength_step_nm=10, multipole_pairs=3)
    np.testing.assert_array_equal(a["methods"]["burley"]["base_color"], b["methods"]["burley"]["base_color"])


@pytest.mark.parametrize("bad", NOT_NUMBERS[:3], ids=repr)
def test_maps_keywords_reject_bool(bad):
    params = params_array()
    raises_naming(TypeError, "wavelength_step_nm", lambda: spectral_skin.maps(params, wavelength_step_nm=bad))
    raises_naming(TypeError, "table_resolution[1]", lambda: spectral_skin.maps(params, table_resolution=(3, bad, 3)))
    raises_naming(TypeError, "oiliness", lambda: spectral_skin.maps(params, oiliness=bad))


def test_blender_version_rejects_bool_parts():
    raises_naming(TypeError, "blender", lambda: spectral_skin.evaluate(preset="asian", blender=(True, 3)))


@pytest.mark.parametrize("bad", NOT_NUMBERS, ids=repr)
def test_layer_fields_and_radii_reject_bool_and_str(bad):
    raises_naming(TypeError, "layers[0][2]", lambda: spectral_skin.layered_reflectance([(1.0, 0.1, bad, 1.4)], [1.0]))
    raises_naming(TypeError, "radii_mm[1]", lambda: spectral_skin.layered_reflectance([SEMI], [1.0, bad]))


@pytest.mark.parametrize(
    "radii, exception",
    [
        (np.array([True, False]), TypeError),
        (np.array(["1.0", "2.0"]), TypeError),
        (np.array([1 + 1j]), TypeError),
        (np.array([[1.0, 2.0]]), SpectralSkinError),
        (np.array([1.0, np.nan]), SpectralSkinError),
    ],
)
def test_radii_arrays_wrong_dtype_shape_or_nan(radii, exception):
    raises_naming(exception, "radii_mm", lambda: spectral_skin.layered_reflectance([SEMI], radii))


def test_radii_non_contiguous_read_only_and_integer_arrays_work():
    radii = np.linspace(0.1, 4.0, 20)
    total, expected = spectral_skin.layered_reflectance([SEMI], radii[::3].copy())
    strided = radii[::3]
    strided.setflags(write=False)
    assert not strided.flags.c_contiguous
    total_strided, profile = spectral_skin.layered_reflectance([SEMI], strided)
    assert total_strided == total
    np.testing.assert_array_equal(profile, expected)
    _, from_ints = spectral_skin.layered_reflectance([SEMI], np.array([1, 2], dtype=np.int32))
    _, from_floats = spectral_skin.layered_reflectance([SEMI], [1.0, 2.0])
    np.testing.assert_array_equal(from_ints, from_floats)


@pytest.mark.parametrize(
    "kwargs, exception, name",
    [
        ({"params": np.zeros((3, 3, 4), dtype=np.int64)}, TypeError, "params"),
        ({"params": params_array().astype(">f4")}, TypeError, "params"),
        ({"params": params_array()[..., 0]}, SpectralSkinError, "params"),
        ({"params": params_array()[..., :3]}, SpectralSkinError, "params"),
        ({"params": params_array(), "melanin": np.zeros((3, 3), dtype=np.bool_)}, TypeError, "melanin"),
        ({"params": params_array(), "hemoglobin": np.zeros((3, 3, 1), dtype=np.float32)}, SpectralSkinError,
         "hemoglobin"),
        ({"params": params_array(), "oiliness": float("nan")}, SpectralSkinError, "oiliness"),
        ({"params": params_array(), "melanin_blend": np.full((3, 3), np.nan)}, SpectralSkinError, "melanin_blend"),
    ],
)
def test_maps_arrays_wrong_dtype_shape_or_nan(kwargs, exception, name):
    raises_naming(exception, name, lambda: spectral_skin.maps(**kwargs))


def test_maps_nan_texel_names_the_parameter():
    params = params_array()
    params[1, 2, 2] = np.nan
    with pytest.raises(SpectralSkinError) as info:
        spectral_skin.maps(params)
    assert "hemoglobin" in str(info.value)
    assert info.value.bad_texels["parameter"] == "hemoglobin"
    assert info.value.bad_texels["nan"] == 1


def test_maps_non_contiguous_and_read_only_arrays_work():
    params = params_array(4, 6, seed=3)
    expected = spectral_skin.maps(params.copy(), exact=True)
    wide = np.zeros((4, 12, 4), dtype=np.float32)
    wide[:, ::2] = params
    strided = wide[:, ::2]
    strided.setflags(write=False)
    assert not strided.flags.c_contiguous and not strided.flags.writeable
    got = spectral_skin.maps(strided, exact=True)
    np.testing.assert_array_equal(got["albedo"], expected["albedo"])
    # A per-parameter map given as a transposed (Fortran-ordered) read-only view.
    melanin = np.ascontiguousarray(params[..., 0].T).T
    melanin.setflags(write=False)
    assert not melanin.flags.c_contiguous
    got = spectral_skin.maps(params, melanin=melanin, exact=True)
    np.testing.assert_array_equal(got["albedo"], expected["albedo"])


@pytest.mark.parametrize("bad", NOT_NUMBERS, ids=repr)
def test_maps_extended_keywords_reject_bool_and_str(bad):
    params = params_array()
    for name in ("epidermis_thickness_mm", "baseline_absorption_scale", "blood_oxygenation"):
        raises_naming(TypeError, name, lambda name=name: spectral_skin.maps(params, **{name: bad}))
