"""The add-on's transport without bpy (blender_addon/core): the choices come from the core's ``transports()``, the
settings' transport goes into every core call the plan makes (evaluate, maps, shader_table, the radius bound, the
albedo fit) and into the plan, the Live table's name and the swatch; a bad value is refused naming the choices."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import spectral_skin
from addon_helpers import load_core

core = load_core()
plan_module = importlib.import_module("addon_core.plan")
live = importlib.import_module("addon_core.live")
scene = importlib.import_module("addon_core.scene")
albedo = importlib.import_module("addon_core.albedo")


def _settings(**kw):
    return core.SkinSettings.from_preset("african", **{"blender": "5.0", "engine": "cycles", **kw})


def test_choices_are_the_cores():
    catalog = spectral_skin.transports()
    assert core.TRANSPORTS == {t["name"].upper(): t["name"] for t in catalog}
    assert core.TRANSPORT_DESCRIPTIONS == {t["name"].upper(): t["description"] for t in catalog}
    assert core.TRANSPORTS[core.DEFAULT_TRANSPORT] == next(t["name"] for t in catalog if t["default"])
    assert core.SkinSettings().transport == core.DEFAULT_TRANSPORT


def test_a_bad_transport_is_refused():
    with pytest.raises(spectral_skin.SpectralSkinError, match="transport must be one of ADDING_DOUBLING, ADDING_DOUBLING_DIFFUSION_SHAPE, DIFFUSION"):
        core.compute(_settings(transport="MONTE_CARLO"))


@pytest.mark.parametrize("key", list(core.TRANSPORTS))
def test_constant_plan_and_swatch_follow_the_transport(key):
    name = core.TRANSPORTS[key]
    plan = scene.scene_plan(_settings(transport=key), None)
    assert plan.transport == name
    ev = spectral_skin.evaluate(preset="african", blender="5.0", engine="cycles", transport=name)
    np.testing.assert_allclose(plan.base_color, ev["methods"]["burley"]["base_color"], rtol=1e-12)
    np.testing.assert_allclose(plan.radius, ev["methods"]["burley"]["subsurface_radius_mm"], rtol=1e-12)
    values = {n: getattr(_settings(), n) for n in (*core.PARAMETERS, *core.EXTENDED_PARAMETERS)}
    swatch = plan_module.swatch_albedo(values, "Linear Rec.709", key)
    np.testing.assert_allclose(swatch, spectral_skin.evaluate(preset="african", outputs=["albedo"], transport=name)[
        "diffuse_reflectance_rgb"], rtol=1e-12)


def test_every_core_call_gets_the_transport(monkeypatch, tmp_path):
    """maps, shader_table, the radius bound's evaluate and the albedo fit: ``transport=`` whenever it is not the core's
    default (the default calls the core as before)."""
    seen: list[tuple[str, object]] = []
    # A skin colour (a grey one would be diagnosed as not an albedo, a warning), before evaluate is spied on.
    skin = np.array([[spectral_skin.evaluate(preset="caucasian", outputs=["albedo"])["diffuse_reflectance_rgb"]]],
                    np.float32)

    def spy(name, real):
        def call(*args, **kw):
            seen.append((name, kw.get("transport")))
            return real(*args, **kw)
        return call

    for name in ("maps", "shader_table", "evaluate", "fit_albedo_map"):
        monkeypatch.setattr(spectral_skin, name, spy(name, getattr(spectral_skin, name)))
    other = next(k for k in core.TRANSPORTS if k != core.DEFAULT_TRANSPORT)
    melanin = core.ParameterMap(np.full((2, 2), 0.3, np.float32), False, "m")
    for key in (core.DEFAULT_TRANSPORT, other):
        seen.clear()
        expected = None if key == core.DEFAULT_TRANSPORT else core.TRANSPORTS[key]
        settings = _settings(transport=key)
        core.compute(settings.replace(maps={"melanin": melanin}, output_dir=str(tmp_path)))
        live.shader_table(settings, {})
        scene.radius_bound_mm(settings)
        albedo.fit(skin, "Linear Rec.709", None, key)
        called = {name for name, _ in seen}
        assert {"maps", "shader_table", "fit_albedo_map"} <= called, seen
        assert all(transport == expected for _, transport in seen), (key, seen)


def test_live_table_name_names_a_transport_other_than_the_default():
    default = live.table_name(_settings(), {})
    assert default == "Spectral Skin 5.0 cycles burley"
    names = {live.table_name(_settings(transport=key), {}) for key in core.TRANSPORTS}
    assert len(names) == len(core.TRANSPORTS) and default in names
    assert live.table_name(_settings(transport="DIFFUSION"), {}) == "Spectral Skin 5.0 cycles burley diffusion"
    longest = live.table_name(_settings(method="RANDOM_WALK_SKIN", accuracy="REFERENCE", transport="DIFFUSION",
                                        working_space="Linear Rec.2020", epidermis_thickness_mm=0.1,
                                        baseline_absorption_scale=2.0, blood_oxygenation=0.5), {})
    assert len(longest + " Base Color") <= 63
