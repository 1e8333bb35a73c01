"""Tests of the Python bindings: shapes, dtypes, presets, errors, the GIL, and the diffusion solver against Jensen et
al. 2001's dipole written out here in numpy (independent of the Rust code)."""

import math
import threading

import numpy as np
import pytest
import spectral_skin
from spectral_skin import SpectralSkinError

PRESET_NAMES = ("caucasian", "asian", "african")
# Median fits of the thirds of the Xiao et al. 2016 spectra by L* (docs/measured-skin.md, section Presets).
MEASURED_PRESET_NAMES = ("measured-light", "measured-medium", "measured-dark")
# The palette: one preset per ITA class of the same spectra, lightest first (docs/measured-skin.md, section Palette).
PALETTE_PRESET_NAMES = ("ita-very-light", "ita-light", "ita-intermediate", "ita-tan", "ita-brown", "ita-dark")
ALL_OUTPUTS = ("albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular")
# Rec.709 luminance weights (ITU-R BT.709-6), for ordering the presets by lightness.
REC709_LUMA = np.array([0.2126, 0.7152, 0.0722])


def assert_float_array(a, shape):
    assert isinstance(a, np.ndarray), type(a)
    assert a.dtype == np.float64, a.dtype
    assert a.shape == shape, (a.shape, shape)
    assert np.all(np.isfinite(a)), a


# --- Jensen et al. 2001, computed here --------------------------------------------------------------------------------


def fdr(eta):
    """Diffuse Fresnel reflectance, Jensen et al. 2001 (Egan & Hilgeman fit), eta >= 1."""
    return -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta


def jensen_total(sigma_a, sigma_s_reduced, eta):
    """R_d = (a'/2)(1 + exp(-(4/3) A sqrt(3(1-a')))) exp(-sqrt(3(1-a'))), Jensen et al. 2001 eq. 5 integrated."""
    a = sigma_s_reduced / (sigma_a + sigma_s_reduced)
    big_a = (1 + fdr(eta)) / (1 - fdr(eta))
    root = math.sqrt(3 * (1 - a))
    return a / 2 * (1 + math.exp(-4 / 3 * big_a * root)) * math.exp(-root)


def jensen_dipole(r_mm, sigma_a, sigma_s_reduced, eta):
    """R(r) in mm^-2 of a semi-infinite medium, Jensen et al. 2001 eq. 4."""
    r = np.asarray(r_mm, dtype=float)
    sigma_t = sigma_a + sigma_s_reduced
    alpha = sigma_s_reduced / sigma_t
    sigma_tr = math.sqrt(3 * sigma_a * sigma_t)
    big_a = (1 + fdr(eta)) / (1 - fdr(eta))
    diffusion = 1 / (3 * sigma_t)
    z_r = 1 / sigma_t
    z_v = z_r + 4 * big_a * diffusion
    d_r = np.sqrt(r**2 + z_r**2)
    d_v = np.sqrt(r**2 + z_v**2)
    pole = lambda z, d: z * (sigma_tr * d + 1) * np.exp(-sigma_tr * d) / d**3  # noqa: E731
    return alpha / (4 * math.pi) * (pole(z_r, d_r) + pole(z_v, d_v))


# --- layered_reflectance ------------------------------------------------------------------------------------------


def test_readme_line_matches_jensen_closed_form():
    # Jensen's dipole is diffusion: the multipole alone (the default transport's total is exact radiative transfer).
    total, profile = spectral_skin.layered_reflectance([(float("inf"), 0.01, 1.0, 1.4)], [0.5, 1.0],
                                                       transport="diffusion")
    assert isinstance(total, float)
    assert_float_array(profile, (2,))
    expected = jensen_total(0.01, 1.0, 1.4)
    assert total == pytest.approx(expected, rel=1e-12), (total, expected)


@pytest.mark.parametrize("sigma_a, sigma_s_reduced", [(0.01, 1.0), (0.2, 3.0), (1.0, 0.5)])
def test_semi_infinite_profile_is_jensen_dipole(sigma_a, sigma_s_reduced):
    radii = np.concatenate([[0.0], np.geomspace(1e-3, 20.0, 30)])
    total, profile = spectral_skin.layered_reflectance([(math.inf, sigma_a, sigma_s_reduced, 1.4)], radii,
                                                       transport="diffusion")
    expected = jensen_dipole(radii, sigma_a, sigma_s_reduced, 1.4)
    np.testing.assert_allclose(profile, expected, rtol=1e-9, atol=0)
    assert total == pytest.approx(jensen_total(sigma_a, sigma_s_reduced, 1.4), rel=1e-12)


def test_layered_reflectance_accepts_array_likes():
    layers = np.array([[0.25, 0.3, 6.0, 1.4], [np.inf, 0.2, 3.0, 1.4]])
    total, profile = spectral_skin.layered_reflectance(layers, np.array([0, 1, 2]))  # int radii are converted
    assert 0 < total < 1
    assert_float_array(profile, (3,))
    assert spectral_skin.layered_reflectance(layers, [])[1].shape == (0,)


# --- evaluate, profile, presets -----------------------------------------------------------------------------------


def test_presets():
    presets = spectral_skin.presets()
    assert list(presets) == [*PRESET_NAMES, *MEASURED_PRESET_NAMES, *PALETTE_PRESET_NAMES]
    for name, p in presets.items():
        specs = spectral_skin.parameters()
        assert set(p) == {s["name"] for s in specs} | {"description"}
        assert 0 <= p["melanin"] <= 0.5 and 0 <= p["melanin_blend"] <= 1
        assert 0 <= p["hemoglobin"] <= 0.1 and 0 <= p["oiliness"] <= 1
        # The paper's presets keep the extended physiology at its defaults (the paper's fixed values); the measured
        # ones have their fitted epidermis thickness and baseline scale.
        at_defaults = all(p[s["name"]] == s["default"] for s in specs if s["default"] is not None)
        assert at_defaults == (name in PRESET_NAMES), name
        assert isinstance(p["description"], str) and p["description"]
        params = spectral_skin.evaluate(preset=name, outputs=())["params"]
        assert params == {s["name"]: p[s["name"]] for s in specs}


def test_explicit_parameters_override_preset():
    asian = spectral_skin.presets()["asian"]
    params = spectral_skin.evaluate(preset="Asian", melanin=0.2, outputs=())["params"]
    assert params["melanin"] == 0.2
    assert params["hemoglobin"] == asian["hemoglobin"]
    assert params["melanin_blend"] == asian["melanin_blend"]


def test_default_outputs_shapes_and_dtypes():
    ev = spectral_skin.evaluate(0.1, 0.5, 0.02, 0.2)
    assert_float_array(ev["diffuse_reflectance_rgb"], (3,))
    for method in ("burley", "random_walk"):
        for key in ("base_color", "subsurface_radius_mm", "expected_albedo"):
            assert_float_array(ev["methods"][method][key], (3,))
        assert np.all(ev["methods"][method]["subsurface_radius_mm"] > 0)
    assert len(ev["radius_fit"]) == 3
    assert set(ev["specular"]) >= {"specular_ior_level", "roughness", "ior"}
    assert ev["default_method"] == "burley"
    assert ev["color_space"] == "Linear Rec.709"
    assert ev["combination"] == "directional"
    assert ev["model"]["dermis_thickness_mm"] == math.inf
    assert "profile" not in ev and "spectral_reflectance" not in ev
    assert ev["work"]["radial_profiles"] == 0


def test_all_outputs_shapes_and_dtypes():
    step = 10.0
    k = int(round(400 / step)) + 1  # 380..780 nm
    ev = spectral_skin.evaluate(preset="african", outputs=ALL_OUTPUTS, wavelength_step_nm=step, profile_count=16)
    assert_float_array(ev["wavelengths_nm"], (k,))
    assert ev["wavelengths_nm"][0] == 380 and ev["wavelengths_nm"][-1] == 780
    assert_float_array(ev["spectral_reflectance"], (k,))
    assert_float_array(ev["profile"]["radii_mm"], (16,))
    assert_float_array(ev["profile"]["rgb_per_mm2"], (16, 3))
    assert_float_array(ev["profile"]["spectral_per_mm2"], (k, 16))
    assert ev["work"]["radial_profiles"] == k
    assert ev["accuracy"]["wavelength_step_nm"] == step


def test_profile_function_matches_evaluate():
    knobs = dict(preset="caucasian", wavelength_step_nm=10.0, profile_r_min_mm=0.01, profile_r_max_mm=10.0,
                 profile_count=12)
    rgb = spectral_skin.profile(**knobs)
    assert set(rgb) == {"radii_mm", "rgb_per_mm2"}
    assert_float_array(rgb["rgb_per_mm2"], (12, 3))
    np.testing.assert_allclose(rgb["radii_mm"][[0, -1]], [0.01, 10.0], rtol=1e-12)
    spectral = spectral_skin.profile(**knobs, spectral=True)
    assert set(spectral) == {"radii_mm", "spectral_per_mm2", "wavelengths_nm"}
    assert_float_array(spectral["spectral_per_mm2"], (41, 12))
    ev = spectral_skin.evaluate(**knobs, outputs=("profile_rgb",))
    np.testing.assert_array_equal(ev["profile"]["rgb_per_mm2"], rgb["rgb_per_mm2"])
    # R(r) >= 0 per wavelength and falls off with radius. (RGB tails may dip below 0: at large r only red light is left,
    # which is out of the Rec.709 gamut.)
    assert np.all(spectral["spectral_per_mm2"] >= 0)
    assert np.all(rgb["rgb_per_mm2"][0] > 10 * np.abs(rgb["rgb_per_mm2"][-1]))


def test_preset_albedos_ordered_by_lightness():
    luma = {}
    for name in PRESET_NAMES:
        ev = spectral_skin.evaluate(preset=name, outputs=("albedo",))
        rgb = ev["diffuse_reflectance_rgb"]
        assert_float_array(rgb, (3,))
        assert np.all((rgb > 0) & (rgb < 1)), (name, rgb)
        assert ev["work"]["radial_profiles"] == 0
        assert "methods" not in ev and "specular" not in ev
        luma[name] = float(REC709_LUMA @ rgb)
    assert luma["african"] < luma["asian"] < luma["caucasian"], luma


def test_palette_runs_from_light_to_dark():
    luma = [float(REC709_LUMA @ spectral_skin.evaluate(preset=name, outputs=("albedo",))["diffuse_reflectance_rgb"])
            for name in PALETTE_PRESET_NAMES]
    assert luma == sorted(luma, reverse=True), luma


def test_model_choices_are_passed_through():
    base = dict(preset="asian", outputs=("albedo",), wavelength_step_nm=10.0)
    rec709 = spectral_skin.evaluate(**base)["diffuse_reflectance_rgb"]
    rec2020 = spectral_skin.evaluate(**base, working_space="Linear Rec.2020")
    assert rec2020["color_space"] == "Linear Rec.2020"
    assert not np.allclose(rec709, rec2020["diffuse_reflectance_rgb"])
    symmetric = spectral_skin.evaluate(**base, combination="symmetric")
    assert symmetric["combination"] == "symmetric"
    pairs = spectral_skin.evaluate(**base, multipole_pairs=10)
    assert pairs["accuracy"]["multipole_terms"] == {"pairs": 10}


# --- errors -------------------------------------------------------------------------------------------------------

EVALUATE_ERRORS = [
    (dict(melanin=0.7, melanin_blend=0.5, hemoglobin=0.01, oiliness=0.3), ["melanin", "[0, 0.5]", "0.7"]),
    (dict(preset="asian", hemoglobin=float("nan")), ["hemoglobin", "[0, 0.1]", "NaN"]),
    (dict(preset="martian"), ["preset", "martian", "caucasian", "asian", "african"]),
    (dict(preset="asian", outputs=("albedo", "colour")), ["colour", "albedo", "profile_rgb", "spectrum"]),
    (dict(melanin=0.1), ["preset", "missing", "melanin_blend", "hemoglobin", "oiliness"]),
    (dict(), ["preset", "melanin"]),
    (dict(preset="asian", wavelength_step_nm=0.0), ["wavelength_step_nm", "[0.5, 100]"]),
    (dict(preset="asian", multipole_pairs=-1), ["multipole_pairs", "-1"]),
    (dict(preset="asian", accuracy="fast"), ["accuracy", "fast", "draft", "default", "reference"]),
    (dict(preset="asian", combination="sideways"), ["combination", "sideways", "directional", "symmetric"]),
    (dict(preset="asian", working_space="sRGB"), ["working_space", "sRGB", "Linear Rec.709", "Linear Rec.2020"]),
]


@pytest.mark.parametrize("kwargs, fragments", EVALUATE_ERRORS)
def test_evaluate_errors(kwargs, fragments):
    with pytest.raises(SpectralSkinError) as info:
        spectral_skin.evaluate(**kwargs)
    assert isinstance(info.value, ValueError)
    message = str(info.value)
    assert all(f in message for f in fragments), (message, fragments)


def test_profile_errors():
    with pytest.raises(SpectralSkinError, match="profile_count"):
        spectral_skin.profile(preset="asian", profile_count=0)
    with pytest.raises(SpectralSkinError, match="r_max_mm"):
        spectral_skin.profile(preset="asian", profile_r_min_mm=1.0, profile_r_max_mm=0.5)


SEMI = (math.inf, 0.1, 1.0, 1.4)
LAYER_ERRORS = [
    ([(1.0, -0.1, 1.0, 1.4)], [1.0], ["layer 0", "sigma_a_per_mm", ">= 0", "-0.1"]),
    ([SEMI, (1.0, 0.1, 1.0, 1.4)], [1.0], ["layer 0", "thickness_mm", "infinity only for the last layer", "inf"]),
    ([], [1.0], ["layers", "at least one layer"]),
    ([SEMI], [0.5, -1.0], ["radii_mm", ">= 0", "radii_mm[1]", "-1"]),
    ([SEMI], [float("nan")], ["radii_mm", "NaN"]),
    ([(1.0, 0.1, 1.0, 1.4), (math.inf, 0.1, 1.0)], [1.0], ["layer 1", "4 values", "got 3"]),
    ([(1.0, 0.1, 1.0, 0.5)], [1.0], ["layer 0", "ior", "0.5"]),
]


@pytest.mark.parametrize("layers, radii, fragments", LAYER_ERRORS)
def test_layered_reflectance_errors(layers, radii, fragments):
    with pytest.raises(SpectralSkinError) as info:
        spectral_skin.layered_reflectance(layers, radii)
    assert isinstance(info.value, ValueError)
    message = str(info.value)
    assert all(f in message for f in fragments), (message, fragments)


@pytest.mark.parametrize(
    "call",
    [
        lambda: spectral_skin.evaluate(preset="asian", outputs="albedo"),
        lambda: spectral_skin.layered_reflectance("layers", [1.0]),
        lambda: spectral_skin.layered_reflectance([(1.0, 0.1, "x", 1.4)], [1.0]),
        lambda: spectral_skin.layered_reflectance([SEMI], [[1.0, 2.0]]),
        lambda: spectral_skin.layered_reflectance([SEMI], "1.0"),
    ],
)
def test_wrong_types_are_type_errors(call):
    with pytest.raises(TypeError):
        call()


def test_error_and_warning_classes_are_exported():
    assert issubclass(SpectralSkinError, ValueError)
    assert spectral_skin.SpectralSkinError is spectral_skin._core.SpectralSkinError
    assert issubclass(spectral_skin.SpectralSkinWarning, UserWarning)
    assert issubclass(spectral_skin.SpectralSkinIOError, OSError)
    assert set(spectral_skin.__all__) == {
        "MODEL_VERSION", "AlbedoMapFit", "Maps", "SpectralSkinError", "SpectralSkinIOError", "SpectralSkinWarning", "__version__", "blender_targets", "cielab", "delta_e00", "evaluate",
        "fit_albedo", "fit_albedo_map", "fit_spectra", "fit_spectrum", "layered_reflectance", "map_kinds", "maps",
        "parameter_ranges", "parameters", "accuracy_levels", "presets", "profile", "read_parameter_map", "shader_table",
        "surface_albedo", "surface_brdf", "surface_input_nodes", "surface_models", "transports", "write_maps",
        "write_shader_table"
    }


# --- the GIL ------------------------------------------------------------------------------------------------------


def test_gil_is_released_during_a_core_call(assert_releases_gil):
    """While the core computes, this thread keeps running Python: it could not if the call held the GIL."""
    assert_releases_gil(lambda: spectral_skin.profile(preset="caucasian"))


def test_concurrent_calls_finish_and_agree():
    results = [None, None]

    def work(i):
        results[i] = spectral_skin.profile(preset="african", wavelength_step_nm=10.0, profile_count=16)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not any(t.is_alive() for t in threads)
    np.testing.assert_array_equal(results[0]["rgb_per_mm2"], results[1]["rgb_per_mm2"])


def test_parameter_ranges_bound_what_evaluate_accepts():
    ranges = spectral_skin.parameter_ranges()
    assert ranges == {"melanin": (0.0, 0.5), "melanin_blend": (0.0, 1.0), "hemoglobin": (0.0, 0.1), "oiliness": (0.0, 1.0),
                      "epidermis_thickness_mm": (0.01, 0.5), "baseline_absorption_scale": (0.0, 10.0),
                      "blood_oxygenation": (0.0, 1.0)}
    for name, (_low, high) in ranges.items():
        values = {"melanin": 0.1, "melanin_blend": 0.5, "hemoglobin": 0.01, "oiliness": 0.2}
        spectral_skin.evaluate(**{**values, name: high}, outputs=("albedo",))
        with pytest.raises(spectral_skin.SpectralSkinError, match=name):
            spectral_skin.evaluate(**{**values, name: high * 1.01 + 0.001}, outputs=("albedo",))


def test_accuracy_levels():
    """A named level sets every knob; explicit knobs override it; the draft stays close to the reference (the draft and
    default read skin's totals from the table of 32-stream solves, the reference solves at 32 streams: the table's own
    error is tests/physics/total_table.rs's, the streams' tests/physics/accuracy.rs's)."""
    draft = spectral_skin.evaluate(preset="asian", accuracy="draft")
    default = spectral_skin.evaluate(preset="asian")
    reference = spectral_skin.evaluate(preset="asian", accuracy="reference")
    assert (draft["accuracy"]["streams"], default["accuracy"]["streams"], reference["accuracy"]["streams"]) == (4, 10, 32)
    assert draft["accuracy"]["wavelength_placement"] == "cmf_adapted"
    assert (draft["work"]["wavelengths"], default["work"]["wavelengths"], reference["work"]["wavelengths"]) == (21, 41, 401)
    assert default["accuracy"] == spectral_skin.evaluate(preset="asian", accuracy="default")["accuracy"]
    for level, bound in ((draft, 0.005), (default, 0.002)):
        ref_albedo = np.asarray(reference["diffuse_reflectance_rgb"])
        assert np.max(np.abs(np.asarray(level["diffuse_reflectance_rgb"]) / ref_albedo - 1)) < bound
    overridden = spectral_skin.evaluate(preset="asian", accuracy="reference", wavelength_step_nm=10.0)
    assert overridden["work"]["wavelengths"] == 41
    uniform = spectral_skin.evaluate(preset="asian", outputs=("spectrum",), wavelength_placement="uniform")
    np.testing.assert_array_equal(uniform["wavelengths_nm"], np.arange(380.0, 781.0, 10.0))
    adapted = spectral_skin.evaluate(preset="asian", outputs=("spectrum",))
    assert adapted["wavelengths_nm"].shape == (41,) and np.all(np.diff(adapted["wavelengths_nm"]) > 0)
    with pytest.raises(SpectralSkinError, match="wavelength_placement"):
        spectral_skin.evaluate(preset="asian", wavelength_placement="random")
    assert overridden["accuracy"]["fit_frequencies_per_decade"] == reference["accuracy"]["fit_frequencies_per_decade"]
    profile = spectral_skin.profile(preset="asian", accuracy="draft", spectral=True, profile_count=4)
    assert profile["wavelengths_nm"].shape == (21,)
    maps = spectral_skin.maps(melanin=np.full((2, 2), 0.1, np.float32), melanin_blend=0.5, hemoglobin=0.01,
                              oiliness=0.2, accuracy="draft")
    assert maps["report"]["request"]["accuracy"]["wavelength_placement"] == "cmf_adapted"


def test_work_counts_only_what_was_asked():
    """The core's work counter: albedo alone needs no profile and no fit; specular only when asked; the radius one
    Burley fit per RGB channel; a constant parameter map one evaluation for all its texels."""
    albedo = spectral_skin.evaluate(preset="caucasian", outputs=["albedo"])["work"]
    assert (albedo["radial_profiles"], albedo["radius_fits"], albedo["specular_evaluations"]) == (0, 0, 0)
    assert albedo["transform_samples"] == albedo["wavelengths"] > 0
    material = spectral_skin.evaluate(preset="caucasian")["work"]
    assert (material["radial_profiles"], material["radius_fits"], material["specular_evaluations"]) == (0, 3, 1)
    specular = spectral_skin.evaluate(preset="caucasian", outputs=["specular"])["work"]
    assert (specular["wavelengths"], specular["radius_fits"], specular["specular_evaluations"]) == (0, 0, 1)
    ev = spectral_skin.evaluate(preset="caucasian", outputs=["albedo"])
    assert "specular" not in ev and ev["surface"]["ior"] == spectral_skin.evaluate(preset="caucasian")["specular"]["ior"]
    constant = spectral_skin.maps(melanin=np.full((8, 8), 0.1, np.float32), melanin_blend=0.5, hemoglobin=0.02,
                                  oiliness=0.3)["report"]["work"]
    assert (constant["texels"], constant["evaluations"], constant["radius_fits"]) == (64, 1, 3), constant
    assert (constant["table_nodes_built"], constant["table_lookups"], constant["specular_evaluations"]) == (0, 0, 1)
    assert constant["outputs"] == {"albedo": 64, "radius": 64, "specular": 0}
