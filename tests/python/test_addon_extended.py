"""The add-on's extended physiology without bpy (blender_addon/core): the three values come from the core's table,
go from the settings into every core call of the plan (evaluate, maps, shader_table) and into the plan, only when
changed for the map and live paths; the panel's albedo swatch is evaluate's albedo; presets carry their values."""

from __future__ import annotations

import dataclasses
import importlib
import inspect

import numpy as np
import pytest
import spectral_skin
from addon_helpers import load_core

core = load_core()
plan_module = importlib.import_module("addon_core.plan")
live = importlib.import_module("addon_core.live")
scene = importlib.import_module("addon_core.scene")

SPECS = {p["name"]: p for p in spectral_skin.parameters()}
THIN = {"epidermis_thickness_mm": 0.1, "baseline_absorption_scale": 2.0, "blood_oxygenation": 0.5}


def _settings(**kw):
    return core.SkinSettings.from_preset("caucasian", **{"blender": "5.0", "engine": "cycles", **kw})


def test_extended_parameters_and_defaults_are_the_cores():
    assert set(core.EXTENDED_PARAMETERS) == {n for n, p in SPECS.items() if p["default"] is not None}
    assert set(THIN) == set(core.EXTENDED_PARAMETERS)
    assert core.EXTENDED_DEFAULTS == {n: SPECS[n]["default"] for n in core.EXTENDED_PARAMETERS}
    # SkinSettings has a field per extended parameter, whose default is the table's.
    fields = {f.name: f.default for f in dataclasses.fields(core.SkinSettings)}
    assert {n: fields[n] for n in core.EXTENDED_PARAMETERS} == core.EXTENDED_DEFAULTS
    for name in core.EXTENDED_PARAMETERS:
        info = core.PARAMETER_INFO[name]
        assert (info.low, info.high) == (SPECS[name]["min"], SPECS[name]["max"])
        assert info.label.startswith(SPECS[name]["label"])
    assert core.PARAMETER_INFO["epidermis_thickness_mm"].label.endswith(", mm)")


def test_presets_carry_their_extended_values():
    for name, preset in spectral_skin.presets().items():
        settings = core.SkinSettings.from_preset(name)
        assert settings.extended() == {n: preset.get(n, SPECS[n]["default"]) for n in core.EXTENDED_PARAMETERS}
        assert settings.constants() == {n: preset[n] for n in core.PARAMETERS}
    assert core.SkinSettings.from_preset("asian", epidermis_thickness_mm=0.1).epidermis_thickness_mm == 0.1
    # A new material's values are the core's first preset's: no copy of them in the add-on.
    first, values = next(iter(spectral_skin.presets().items()))
    assert core.DEFAULT_PRESET == first
    assert core.SkinSettings().constants() == {n: values[n] for n in core.PARAMETERS}, core.SkinSettings().constants()


def test_constant_plan_uses_the_extended_values():
    settings = _settings(**THIN)
    plan = scene.scene_plan(settings, None)
    assert plan.extended == THIN
    ev = spectral_skin.evaluate(preset="caucasian", blender="5.0", engine="cycles", **THIN)
    np.testing.assert_allclose(plan.base_color, ev["methods"]["burley"]["base_color"], rtol=1e-12)
    np.testing.assert_allclose(plan.radius, ev["methods"]["burley"]["subsurface_radius_mm"], rtol=1e-12)
    # Not the paper's: a thinner epidermis with more baseline absorption and less oxygen changes the colour.
    paper = spectral_skin.evaluate(preset="caucasian", blender="5.0", engine="cycles")
    assert np.max(np.abs(np.subtract(plan.base_color, paper["methods"]["burley"]["base_color"]))) > 0.01
    assert scene.scene_plan(_settings(), None).extended == core.EXTENDED_DEFAULTS


def test_swatch_is_evaluates_albedo():
    values = {"melanin": 0.2, "melanin_blend": 0.3, "hemoglobin": 0.04, "oiliness": 0.5, **THIN}
    for space in core.WORKING_SPACES:
        swatch = plan_module.swatch_albedo(values, space)
        ev = spectral_skin.evaluate(0.2, 0.3, 0.04, 0.5, outputs=["albedo"], working_space=space, **THIN)
        np.testing.assert_allclose(swatch, ev["diffuse_reflectance_rgb"], rtol=1e-12)
    # An extended value left out is the default.
    four = {n: values[n] for n in core.PARAMETERS}
    np.testing.assert_allclose(plan_module.swatch_albedo(four, "Linear Rec.709"),
                               spectral_skin.evaluate(0.2, 0.3, 0.04, 0.5, outputs=["albedo"])
                               ["diffuse_reflectance_rgb"], rtol=1e-12)


def _constant_maps(settings, tmp_path):
    melanin = np.full((2, 3), settings.melanin, dtype=np.float32)
    return settings.replace(maps={"melanin": core.ParameterMap(melanin, False, "m")}, output_dir=str(tmp_path))


def test_maps_get_only_changed_extended_values(tmp_path, monkeypatch):
    """The map path passes the changed extended values to maps() (not the defaults, so that the paper's model calls
    the core as before)."""
    calls = []
    real = spectral_skin.maps

    def maps(params=None, *, epidermis_thickness_mm=None, baseline_absorption_scale=None, blood_oxygenation=None,
             **kw):
        calls.append({"epidermis_thickness_mm": epidermis_thickness_mm,
                      "baseline_absorption_scale": baseline_absorption_scale, "blood_oxygenation": blood_oxygenation})
        return real(params, **kw)

    monkeypatch.setattr(spectral_skin, "maps", maps)
    core.compute(_constant_maps(_settings(), tmp_path))
    core.compute(_constant_maps(_settings(epidermis_thickness_mm=0.1), tmp_path))
    assert calls == [{"epidermis_thickness_mm": None, "baseline_absorption_scale": None, "blood_oxygenation": None},
                     {"epidermis_thickness_mm": 0.1, "baseline_absorption_scale": None, "blood_oxygenation": None}]


def test_maps_with_extended_values(tmp_path):
    """With this spectral_skin's maps(): a constant map with a non-default thickness gives evaluate's Base Color; a
    maps() without the extended keywords gives the clear error instead of the paper's colours."""
    settings = _constant_maps(_settings(method="RANDOM_WALK", epidermis_thickness_mm=0.1), tmp_path)
    if "epidermis_thickness_mm" not in inspect.signature(spectral_skin.maps).parameters:
        with pytest.raises(spectral_skin.SpectralSkinError,
                           match="extended physiology with parameter maps needs a spectral_skin whose maps"):
            core.compute(settings)
        return
    plan = core.compute(settings)
    ev = spectral_skin.evaluate(preset="caucasian", blender="5.0", engine="cycles", epidermis_thickness_mm=0.1)
    base_color = np.asarray(plan.maps.albedo, dtype=np.float64).reshape(-1, 3)
    np.testing.assert_allclose(base_color, np.broadcast_to(ev["methods"]["random_walk"]["base_color"], (6, 3)),
                               rtol=2e-3)  # the table strategy's interpolation (docs/maps-performance.md)


def test_live_table_key_and_arguments_follow_the_extended_values(monkeypatch):
    names = {live.table_name(_settings(**{name: value}), {}) for name, value in THIN.items()}
    names.add(live.table_name(_settings(), {}))
    assert len(names) == 4
    assert live.table_name(_settings(), {}) == "Spectral Skin 5.0 cycles burley"
    assert live.table_name(_settings(epidermis_thickness_mm=0.1), {}) == "Spectral Skin 5.0 cycles burley epidermis=0.1"
    # Two values a Blender slider tells apart (float32) get two names; the longest key still fits Blender's IDs.
    assert (live.table_name(_settings(blood_oxygenation=float(np.float32(0.5))), {})
            != live.table_name(_settings(blood_oxygenation=float(np.nextafter(np.float32(0.5), np.float32(1)))), {}))
    longest = live.table_name(_settings(method="RANDOM_WALK_SKIN", accuracy="REFERENCE",
                                        working_space="Linear Rec.2020", **THIN), {})
    assert len(longest + " Base Color") <= 63

    calls = []

    def shader_table(*, epidermis_thickness_mm=None, baseline_absorption_scale=None, blood_oxygenation=None, **kw):
        calls.append((epidermis_thickness_mm, baseline_absorption_scale, blood_oxygenation, kw["method"]))
        return {}

    monkeypatch.setattr(spectral_skin, "shader_table", shader_table)
    live.shader_table(_settings(), {})
    live.shader_table(_settings(**THIN), {"subsurface": "OFF"})
    assert calls == [(None, None, None, "burley"), (0.1, 2.0, 0.5, "burley")]


def test_live_plan_without_extended_shader_table_says_so(monkeypatch):
    def shader_table(*, method="burley", blender=None, engine="cycles", accuracy="default",
                     working_space="Linear Rec.709"):
        return {}

    monkeypatch.setattr(spectral_skin, "shader_table", shader_table)
    assert live.shader_table(_settings(), {}) == {}
    with pytest.raises(spectral_skin.SpectralSkinError,
                       match="extended physiology in Live mode needs a spectral_skin whose shader_table"):
        live.shader_table(_settings(blood_oxygenation=0.5), {})
