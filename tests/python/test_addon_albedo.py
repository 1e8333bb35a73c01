"""From Albedo Texture's portable part (blender_addon/core/albedo.py): the image's pixels as linear RGB, the call
of the core's per-texel fit and its summary, the parameter EXR the core's reader takes. The fit itself is the core's
(``spectral_skin.fit_albedo_map``); where this spectral_skin lacks it a stand-in records the call."""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
import spectral_skin
from addon_helpers import load_core

core = load_core()
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


class _StandIn:
    """What the core's AlbedoMapFit gives the add-on (attributes; ``write`` records its path)."""

    def __init__(self, h: int, w: int, thickness: dict | None) -> None:
        self.shape = (h, w)
        self.residual_delta_e00 = np.arange(h * w, dtype=np.float32).reshape(h, w)
        self.extended = {**core.EXTENDED_DEFAULTS, "epidermis_thickness_mm": 0.12}
        self.thickness = thickness
        self.stats = {"outside_skin_texels": 2}
        self.written: list[str] = []

    def write(self, path: str) -> None:
        self.written.append(path)


def test_fit_passes_the_albedo_and_summarises(monkeypatch):
    calls = []

    def fit_albedo_map(rgb, *, working_space, epidermis_thickness_mm=None):
        calls.append((rgb, working_space, epidermis_thickness_mm))
        h, w, _ = rgb.shape
        return _StandIn(h, w, None if epidermis_thickness_mm is not None else {"chosen_mm": 0.12})

    monkeypatch.setattr(spectral_skin, "fit_albedo_map", fit_albedo_map, raising=False)
    rgb = np.random.default_rng(1).uniform(0.1, 0.6, (3, 5, 3)).astype(np.float32)
    result = albedo.fit(rgb, "ACEScg", None)
    assert calls[0][0] is rgb and calls[0][1:] == ("ACEScg", None)
    assert result["median_delta_e00"] == 7.0 and result["max_delta_e00"] == 14.0
    assert result["outside_skin_texels"] == 2 and result["thickness"] == {"chosen_mm": 0.12}
    # The extended physiology is the fit's (what the parameters hold for), by name.
    assert result["extended"] == {**core.EXTENDED_DEFAULTS, "epidermis_thickness_mm": 0.12}
    assert albedo.fit(rgb, "ACEScg", 0.08)["thickness"] is None and calls[-1][2] == 0.08
    monkeypatch.setattr(spectral_skin, "fit_albedo_map", lambda rgb, **kw: _StandIn(1, 1, None), raising=False)
    with pytest.raises(RuntimeError, match="returned a fit of"):
        albedo.fit(rgb, "ACEScg", None)


def test_parameter_map_path():
    assert albedo.parameter_map_path("/x/head.blend", "head_Skin") == str(Path("/x/head_Skin_params.exr"))
    with pytest.raises(ValueError, match="not saved yet"):
        albedo.parameter_map_path("", "Skin")


@pytest.mark.skipif(not albedo.available(), reason="this spectral_skin has no fit_albedo_map yet")
def test_round_trip_with_the_cores_fit(tmp_path):
    """Parameters -> the core's albedo -> the fit (the thickness chosen, the add-on's default) -> the parameter EXR
    the core writes -> the add-on's reading of it (core.read_map_file, SkinSettings.with_maps) -> the core's albedo
    of the fitted parameters at the chosen thickness: within ΔE00 0.5 of the start where the fit says so."""
    colours = np.array([[spectral_skin.evaluate(preset=name, outputs=["albedo"])["diffuse_reflectance_rgb"]
                         for name in ("caucasian", "asian", "african")]], dtype=np.float32)
    result = albedo.fit(colours, "Linear Rec.709", None)
    assert result["max_delta_e00"] < 0.5 and result["thickness"]["chosen_mm"] in [
        m[0] for m in result["thickness"]["screened"]]
    path = albedo.parameter_map_path(str(tmp_path / "head.blend"), "head_Skin")
    result["fit"].write(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["head_Skin_params.exr"]  # no staging file left
    settings = core.SkinSettings().with_maps(core.read_map_file(path))
    assert set(settings.maps) == set(core.PARAMETERS)  # the extended channels are one value: settings
    assert settings.extended() == result["extended"]
    thickness = result["extended"]["epidermis_thickness_mm"]
    if thickness != core.EXTENDED_DEFAULTS["epidermis_thickness_mm"]:
        assert settings.notes and "epidermis_thickness_mm" in settings.notes[0], settings.notes
    for i in range(3):
        fitted = [float(settings.maps[p].pixels[0, i]) for p in core.PARAMETERS]
        again = spectral_skin.evaluate(*fitted, outputs=["albedo"], **settings.extended())
        np.testing.assert_allclose(again["diffuse_reflectance_rgb"], colours[0, i], atol=0.01)


def test_a_varying_extended_map_stays_a_map_and_live_mode_refuses_it():
    plane = np.array([[0.1, 0.2]], dtype=np.float32)
    maps = {"melanin": core.ParameterMap(np.full((1, 2), 0.1, np.float32), False, "m.exr"),
            "epidermis_thickness_mm": core.ParameterMap(plane, False, "t.exr")}
    settings = core.SkinSettings().with_maps(maps)
    assert set(settings.maps) == {"melanin", "epidermis_thickness_mm"} and not settings.notes
    core.check(settings.replace(output_dir="/tmp"))
    with pytest.raises(spectral_skin.SpectralSkinError, match="Live mode takes one value of epidermis_thickness_mm"):
        core.check(settings.replace(mode="LIVE"))


def test_a_tile_set_is_written_by_the_core_and_read_back_stacked(tmp_path):
    """A fit of two stacked tiles written as a tile set (AlbedoMapFit.write(tiles=...)) and read back by the add-on's
    core.read_tile_set: the same parameters, the tiles' rows recorded; one tile missing a map, tiles of different
    widths and mixed tile sets are refused with messages naming them."""
    colours = np.array([spectral_skin.evaluate(preset=name, outputs=["albedo"])["diffuse_reflectance_rgb"]
                        for name in ("caucasian", "asian", "african")], dtype=np.float32)
    texture = np.stack([np.roll(colours, k, axis=0) for k in range(5)])  # (5, 3, 3): tile 1001 rows 0-1, 1002 rows 2-4
    fit = spectral_skin.fit_albedo_map(texture)
    pattern = str(tmp_path / "p.<UDIM>.exr")
    fit.write(pattern, str(tmp_path / "r.<UDIM>.exr"), tiles=[(1001, 2), (1002, 3)])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.1001.exr", "p.1002.exr", "r.1001.exr", "r.1002.exr"]
    maps = core.read_tile_set(pattern, [1002, 1001])
    assert maps["melanin"].tiles == ((1001, 2), (1002, 3))
    for i, name in enumerate(core.PARAMETERS):
        np.testing.assert_array_equal(maps[name].pixels, fit.params[:, :, i])
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"tiles: the rows add up to 4.*the image.s 5"):
        fit.write(pattern, tiles=[(1001, 2), (1002, 2)])
    with pytest.raises(spectral_skin.SpectralSkinError, match="must hold <UDIM>"):
        fit.write(str(tmp_path / "plain.exr"), tiles=[(1001, 5)])
    narrow = spectral_skin.fit_albedo_map(texture[:, :2])
    narrow.write(str(tmp_path / "p.1003.exr"))
    with pytest.raises(ValueError, match="all of one width"):
        core.read_tile_set(pattern, [1001, 1002, 1003])
    mixed = core.SkinSettings(output_dir=str(tmp_path)).with_maps(
        {**maps, "oiliness": core.ParameterMap(np.zeros((5, 3), np.float32), False, "o.exr")})
    with pytest.raises(spectral_skin.SpectralSkinError, match="one UDIM tile set"):
        core.check(mixed)


def test_a_skin_mask_reaches_the_fit_and_its_figures_are_the_skins():
    """core.albedo.fit with a mask: the core fits every texel, counts the unmasked ones as masked out, and the
    figures (median and largest ΔE00) are over the skin texels alone; no diagnosis for a texture whose non-skin half is
    masked out, one without the mask."""
    skin = [spectral_skin.evaluate(preset=p, outputs=["albedo"])["diffuse_reflectance_rgb"]
            for p in ("caucasian", "asian", "african", "caucasian")]
    texture = np.array([skin, [[0.05, 0.6, 0.05]] * 4], dtype=np.float32)
    mask = np.array([[True] * 4, [False] * 4])
    masked = albedo.fit(texture, "Linear Rec.709", None, mask=mask)
    plain = albedo.fit(texture, "Linear Rec.709", None)
    residual = np.asarray(masked["fit"].residual_delta_e00)
    print(f"masked: {masked['masked_out_texels']} out, median {masked['median_delta_e00']:.3f}, "
          f"max {masked['max_delta_e00']:.3f}; plain diagnosis {plain['diagnosis']!r}")
    assert masked["masked_out_texels"] == 4 and plain["masked_out_texels"] == 0
    assert masked["max_delta_e00"] == pytest.approx(float(residual[0].max()))
    assert masked["max_delta_e00"] < 0.5 < plain["max_delta_e00"]
    assert masked["diagnosis"] is None and plain["diagnosis"] is not None
    with pytest.raises(ValueError, match="'m' is 3x2 texels but the Base Color 'a' is 4x2"):
        albedo.skin_mask(np.ones((2, 3, 3)), texture.shape, "m", "a")
