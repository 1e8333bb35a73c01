"""From Albedo Texture's portable part (blender_addon/core/albedo.py): the image's pixels as linear RGB, the call
of the core's per-texel fit and its summary, the parameter EXR the core's reader takes. The fit itself is the core's
(``spectral_skin.fit_albedo_map``); where this spectral_skin lacks it a stand-in records the call."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import spectral_skin
from test_addon_scene import _load_core

core = _load_core()
albedo = importlib.import_module("addon_core.albedo")


def test_srgb_decoding_against_the_standard():
    # IEC 61966-2-1: 0.04045 -> 0.0031308 (the two pieces meet); 0.5 -> 0.2140411; 1 -> 1.
    decoded = albedo.srgb_to_linear([0.0, 0.04045, 0.5, 1.0])
    np.testing.assert_allclose(decoded, [0.0, 0.0031308, 0.2140411, 1.0], rtol=1e-5, atol=1e-7)


def test_linear_albedo_by_colour_space():
    pixels = np.full((2, 3, 4), 0.5, dtype=np.float32)
    rgb, space = albedo.linear_albedo(pixels, "sRGB", False, "ACEScg")
    assert space == "Linear Rec.709" and rgb.shape == (2, 3, 3)
    np.testing.assert_allclose(rgb, 0.2140411, rtol=1e-5)
    # Float images are scene-linear already (Blender converts them on loading), whatever their colour space.
    rgb, space = albedo.linear_albedo(pixels, "sRGB", True, "Linear Rec.2020")
    assert space == "Linear Rec.2020" and np.all(rgb == 0.5)
    assert albedo.linear_albedo(pixels, "Linear", False, "ACEScg")[1] == "Linear Rec.709"
    assert albedo.linear_albedo(pixels, "ACEScg", False, "Linear Rec.709")[1] == "ACEScg"
    with pytest.raises(ValueError, match="colour space 'AgX Log'"):
        albedo.linear_albedo(pixels, "AgX Log", False, "Linear Rec.709")


def test_without_the_cores_fit(monkeypatch):
    monkeypatch.delattr(spectral_skin, "fit_albedo_map", raising=False)
    assert not albedo.available()
    with pytest.raises(RuntimeError, match="needs a spectral_skin with fit_albedo_map"):
        albedo.fit(np.zeros((1, 1, 3), np.float32), "Linear Rec.709", None)


def test_fit_passes_the_albedo_and_summarises(monkeypatch):
    calls = []

    def fit_albedo_map(rgb, *, working_space, epidermis_thickness_mm=None):
        calls.append((rgb, working_space, epidermis_thickness_mm))
        h, w, _ = rgb.shape
        params = np.broadcast_to(np.float32([0.1, 0.5, 0.02, 0.3]), (h, w, 4)).copy()
        residual = np.arange(h * w, dtype=np.float32).reshape(h, w)
        return {"params": params, "residual_delta_e00": residual, "epidermis_thickness_mm": 0.12}

    monkeypatch.setattr(spectral_skin, "fit_albedo_map", fit_albedo_map, raising=False)
    rgb = np.random.default_rng(1).uniform(0.1, 0.6, (3, 5, 3)).astype(np.float32)
    result = albedo.fit(rgb, "ACEScg", None)
    assert calls[0][0] is rgb and calls[0][1:] == ("ACEScg", None)
    assert result["median_delta_e00"] == 7.0 and result["max_delta_e00"] == 14.0
    # The fit's thickness; the others, which the fit does not report, the defaults.
    assert result["extended"] == {**core.EXTENDED_DEFAULTS, "epidermis_thickness_mm": 0.12}

    def fixed(rgb, *, working_space, epidermis_thickness_mm=None):
        out = fit_albedo_map(rgb, working_space=working_space, epidermis_thickness_mm=epidermis_thickness_mm)
        del out["epidermis_thickness_mm"]
        return out

    monkeypatch.setattr(spectral_skin, "fit_albedo_map", fixed, raising=False)
    assert albedo.fit(rgb, "ACEScg", 0.08)["extended"]["epidermis_thickness_mm"] == 0.08
    monkeypatch.setattr(spectral_skin, "fit_albedo_map", lambda rgb, **kw: {"params": np.zeros((1, 1, 4)),
                                                                            "residual_delta_e00": np.zeros((1, 1))},
                        raising=False)
    with pytest.raises(RuntimeError, match="returned params"):
        albedo.fit(rgb, "ACEScg", None)


def test_parameter_map_written_is_read_by_the_core(tmp_path):
    pytest.importorskip("OpenImageIO")
    rng = np.random.default_rng(2)
    params = np.stack([rng.uniform(0, 0.5, (7, 11)), rng.uniform(0, 1, (7, 11)), rng.uniform(0, 0.1, (7, 11)),
                       rng.uniform(0, 1, (7, 11))], axis=-1).astype(np.float32)
    path = albedo.parameter_map_path(str(tmp_path / "head.blend"), "head_Skin")
    assert path == str(tmp_path / "head_Skin_params.exr")
    albedo.write_parameter_map(path, params)
    planes = spectral_skin.read_parameter_map(path)
    assert set(planes) == set(core.PARAMETERS)
    for i, name in enumerate(core.PARAMETERS):
        np.testing.assert_array_equal(planes[name], params[:, :, i])  # float32 EXR: exact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["head_Skin_params.exr"]  # no staging file left
    with pytest.raises(ValueError, match="not saved yet"):
        albedo.parameter_map_path("", "Skin")


@pytest.mark.skipif(not albedo.available(), reason="this spectral_skin has no fit_albedo_map yet")
def test_round_trip_with_the_cores_fit():
    """Parameters -> the core's albedo -> the fit -> the core's albedo of the fitted parameters: within ΔE00 0.5 of
    the start where the fit says so (in-gamut colours: the model's own)."""
    colours = np.array([[spectral_skin.evaluate(preset=name, outputs=["albedo"])["diffuse_reflectance_rgb"]
                         for name in ("caucasian", "asian", "african")]], dtype=np.float32)
    result = albedo.fit(colours, "Linear Rec.709", 0.25)
    assert result["max_delta_e00"] < 0.5
    for i in range(3):
        fitted = result["params"][0, i]
        again = spectral_skin.evaluate(*map(float, fitted), outputs=["albedo"], epidermis_thickness_mm=0.25)
        np.testing.assert_allclose(again["diffuse_reflectance_rgb"], colours[0, i], atol=0.01)
