"""model= of evaluate, profile and fit_spectrum: the model's options beyond the parameters (docs/model.md), one dict
by name that every front reads the same way; what fit_spectrum fits (blood in the epidermis) renders through it."""

from __future__ import annotations

import numpy as np
import pytest
import spectral_skin

SKIN = {"melanin": 0.04, "melanin_blend": 0.4, "hemoglobin": 0.02, "oiliness": 0.3}
WAVELENGTHS = {"wavelength_step_nm": 10.0, "wavelength_placement": "uniform"}


def _spectrum(**model: float) -> tuple[np.ndarray, np.ndarray]:
    ev = spectral_skin.evaluate(**SKIN, outputs=["spectrum"], model=model or None, **WAVELENGTHS)
    keep = (ev["wavelengths_nm"] >= 400) & (ev["wavelengths_nm"] <= 700)
    return ev["wavelengths_nm"][keep], ev["spectral_reflectance"][keep]


def test_epidermal_blood_absorbs_in_the_blood_bands() -> None:
    """docs/model.md, Epidermal blood: blood above the dermis darkens the skin most where haemoglobin absorbs most
    (the Soret band near 415 nm, the Q bands at 542 and 577 nm), least in the red."""
    wavelengths, without = _spectrum()
    _, with_blood = _spectrum(epidermal_hemoglobin=0.02)
    loss = 1.0 - with_blood / without
    at = {int(w): value for w, value in zip(wavelengths, loss, strict=True)}
    assert np.all(loss > 0.0)
    assert at[420] > at[540] > at[650] and at[580] > at[650] and at[650] < 0.05, at


def test_a_fitted_epidermal_blood_renders_as_fitted() -> None:
    """The fit's epidermal_hemoglobin with its params gives back the spectrum it fitted (docs/measured-skin.md, Blood in
    the epidermis)."""
    wavelengths, measured = _spectrum(epidermal_hemoglobin=0.02)
    free = ["melanin", "melanin_blend", "hemoglobin", "epidermal_hemoglobin"]
    fit = spectral_skin.fit_spectrum(wavelengths, measured, free=free, fixed={"epidermis_thickness_mm": 0.25,
                                     "baseline_absorption_scale": 1.0}, specular=0.0, bandpass=0)
    assert fit["epidermal_hemoglobin"] == pytest.approx(0.02, rel=0.02), fit
    assert fit["model"]["epidermal_hemoglobin"] == fit["epidermal_hemoglobin"]
    assert fit["model"]["dermis_thickness_mm"] == float("inf")
    by_value = spectral_skin.evaluate(**fit["params"], outputs=["spectrum"], model={"epidermal_hemoglobin":
                                      fit["epidermal_hemoglobin"]}, **WAVELENGTHS)
    by_model = spectral_skin.evaluate(**fit["params"], outputs=["spectrum"], model=fit["model"], **WAVELENGTHS)
    keep = (by_value["wavelengths_nm"] >= 400) & (by_value["wavelengths_nm"] <= 700)
    assert np.max(np.abs(by_value["spectral_reflectance"][keep] - measured)) < 1e-4
    assert np.array_equal(by_model["spectral_reflectance"], by_value["spectral_reflectance"])


def test_a_held_option_is_fitted_under() -> None:
    """fit_spectrum(model=...) fits the model with that option held; freeing an option the model holds is an error
    naming it."""
    wavelengths, measured = _spectrum(epidermal_hemoglobin=0.02)
    fixed = {"epidermis_thickness_mm": 0.25, "baseline_absorption_scale": 1.0}
    free = ["melanin", "melanin_blend", "hemoglobin"]
    held = spectral_skin.fit_spectrum(wavelengths, measured, free=free, fixed=fixed, specular=0.0, bandpass=0,
                                      model={"epidermal_hemoglobin": 0.02})
    without = spectral_skin.fit_spectrum(wavelengths, measured, free=free, fixed=fixed, specular=0.0, bandpass=0)
    assert held["epidermal_hemoglobin"] == 0.02 and held["rms"] < 1e-4 < without["rms"]
    assert held["model"]["epidermal_hemoglobin"] == 0.02 and "epidermal_hemoglobin" not in without["model"]
    assert held["params"]["hemoglobin"] == pytest.approx(SKIN["hemoglobin"], rel=0.01)
    with pytest.raises(spectral_skin.SpectralSkinError, match="epidermal_hemoglobin"):
        spectral_skin.fit_spectrum(wavelengths, measured, free=[*free, "epidermal_hemoglobin"], fixed=fixed,
                                   model={"epidermal_hemoglobin": 0.02})


def test_a_results_model_reads_back() -> None:
    """The "model" of a result, semi-infinite dermis (float("inf")) included, is a valid model= and changes
    nothing; profile takes the same argument."""
    ev = spectral_skin.evaluate(preset="measured-medium", outputs=["albedo"])
    assert ev["model"]["dermis_thickness_mm"] == float("inf")
    again = spectral_skin.evaluate(preset="measured-medium", outputs=["albedo"], model=ev["model"])
    assert np.array_equal(again["diffuse_reflectance_rgb"], ev["diffuse_reflectance_rgb"])
    plain = spectral_skin.profile(preset="measured-medium")
    bloody = spectral_skin.profile(preset="measured-medium", model={"epidermal_hemoglobin": 0.02})
    assert np.array_equal(plain["radii_mm"], bloody["radii_mm"])
    assert np.all(bloody["rgb_per_mm2"][0] < plain["rgb_per_mm2"][0])


@pytest.mark.parametrize(
    ("model", "error", "pattern"),
    [
        ({"epidermal_blood": 0.01}, spectral_skin.SpectralSkinError, r"model.*epidermal_blood.*epidermal_hemoglobin"),
        ({"epidermal_hemoglobin": 0.5}, spectral_skin.SpectralSkinError, r"epidermal_hemoglobin.*0\.1"),
        ({"epidermal_hemoglobin": float("nan")}, spectral_skin.SpectralSkinError, "epidermal_hemoglobin"),
        ({"epidermal_hemoglobin": "a lot"}, spectral_skin.SpectralSkinError, r"model\[.epidermal_hemoglobin.\]"),
        ({"dermis_thickness_mm": -1.0}, spectral_skin.SpectralSkinError, "dermis_thickness_mm"),
        ([("epidermal_hemoglobin", 0.01)], TypeError, "model must be a dict"),
        ({"blood_vessel_radius_mm": False}, TypeError, r"model\['blood_vessel_radius_mm'\].*bool"),
        ({"eumelanin_shape": {"power_law": {"exponent": True}}}, TypeError, r"\['exponent'\].*bool"),
    ],
)
def test_a_bad_model_is_a_clear_error(model: object, error: type[Exception], pattern: str) -> None:
    for call in (
        lambda: spectral_skin.evaluate(preset="measured-medium", model=model),  # type: ignore[arg-type]
        lambda: spectral_skin.profile(preset="measured-medium", model=model),  # type: ignore[arg-type]
    ):
        with pytest.raises(error, match=pattern):
            call()


def test_maps_render_the_model_options() -> None:
    """maps(model=...): every texel as evaluate gives it with the same options, a constant map (one evaluation) and a
    varying one (exact per texel) alike; the options change the maps."""
    model = {"epidermal_hemoglobin": 0.02}
    params = np.array([[[0.04, 0.4, 0.02, 0.3], [0.1, 0.6, 0.03, 0.3]]], dtype=np.float32)
    varying = spectral_skin.maps(params, outputs=["albedo", "radius"], model=model, exact=True)
    constant = spectral_skin.maps(params[:, :1].copy(), outputs=["albedo", "radius"], model=model)
    plain = spectral_skin.maps(params, outputs=["albedo", "radius"], exact=True)
    for x in range(2):
        skin = [float(v) for v in params[0, x]]
        ev = spectral_skin.evaluate(*skin, model=model)["methods"]["burley"]
        for name, key in (("albedo", "base_color"), ("radius", "subsurface_radius_mm")):
            assert np.allclose(varying[name][0, x], ev[key], rtol=1e-5), (name, x)
            assert not np.allclose(plain[name][0, x], ev[key], rtol=1e-3), (name, x)
    assert np.allclose(constant["albedo"][0, 0], varying["albedo"][0, 0], rtol=1e-5)


def test_a_maps_table_is_built_with_the_model_options() -> None:
    """A varying map read through the lookup table (the strategy of large maps) is built with the options too: its
    texels follow evaluate with them to the table's own error, not evaluate without them."""
    rng = np.random.default_rng(1)
    shape = (96, 96)
    params = np.stack([rng.uniform(0.01, 0.3, shape), rng.uniform(0.0, 1.0, shape), rng.uniform(0.002, 0.05, shape),
                       np.full(shape, 0.3)], axis=-1).astype(np.float32)
    model = {"epidermal_hemoglobin": 0.02}
    got = spectral_skin.maps(params, outputs=["albedo"], model=model, table_cache=False)
    assert got["report"]["strategy"]["name"] == "table"
    tolerance = 2 * got["report"]["strategy"]["measured_error"]["max_albedo_relative"]
    for y, x in ((0, 0), (5, 77), (90, 3)):
        skin = [float(v) for v in params[y, x]]
        with_model = spectral_skin.evaluate(*skin, model=model, outputs=["albedo"])["diffuse_reflectance_rgb"]
        without = spectral_skin.evaluate(*skin, outputs=["albedo"])["diffuse_reflectance_rgb"]
        assert np.allclose(got["albedo"][y, x], with_model, rtol=tolerance), (y, x)
        assert not np.allclose(got["albedo"][y, x], without, rtol=tolerance), (y, x)
