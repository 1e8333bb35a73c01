"""Live mode's decisions without bpy (blender_addon/core/live.py): the shader table a material needs, one per target,
method, accuracy and working space; Burley when subsurface is off; subsurface and specular kept unless Off; the plan
of the constants with the table; the mode validated."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import spectral_skin
from addon_helpers import load_core

core = load_core()
live = importlib.import_module("addon_core.live")


def _settings(**kw):
    return core.SkinSettings.from_preset("caucasian", **{"blender": "5.0", "engine": "cycles", **kw})


def test_table_name_follows_the_table_key():
    names = {live.table_name(_settings(method=m, engine=e, accuracy=a), {}) for m in ("BURLEY", "RANDOM_WALK")
             for e in ("cycles", "eevee") for a in ("DEFAULT", "DRAFT")}
    assert len(names) == 8
    assert live.table_name(_settings(method="RANDOM_WALK"), {"subsurface": "OFF"}) == live.table_name(_settings(), {})
    assert live.table_method(_settings(method="RANDOM_WALK"), {"subsurface": "AUTO"}) == "random_walk"
    assert live.table_name(_settings(), {}) == "Spectral Skin 5.0 cycles burley"
    # Blender 4.x cuts ID names at 63 bytes: the longest key still gives distinct names that fit with " Base Color".
    longest = [live.table_name(_settings(method=m, accuracy="REFERENCE", working_space="Linear Rec.2020"), {})
               for m in ("RANDOM_WALK", "RANDOM_WALK_SKIN")]
    assert len(set(longest)) == 2 and all(len(n + " Base Color") <= 63 for n in longest)


def test_effects_kept_unless_off():
    assert live.kept({}, "subsurface") and live.kept({"subsurface": "AUTO"}, "subsurface")
    assert not live.kept({"specular": "OFF"}, "specular")


def test_live_plan_is_the_constants_plan_with_the_cores_table():
    settings = _settings(oiliness=0.0)
    plan = live.live_plan(settings, None, {}, table_needed=True)
    info = plan.live
    assert info["subsurface"] and info["specular"] and plan.radius is not None
    table = spectral_skin.shader_table(method="burley", blender="5.0", engine="cycles")
    np.testing.assert_array_equal(info["table"]["base_color_log"], table["base_color_log"])
    ev = spectral_skin.evaluate(preset="caucasian", oiliness=0.0, blender="5.0", engine="cycles")
    np.testing.assert_allclose(plan.base_color, ev["methods"]["burley"]["base_color"], rtol=1e-6)
    assert live.live_plan(settings, None, {"subsurface": "OFF"}, table_needed=False).live["table"] is None


def test_mode_is_checked():
    with pytest.raises(spectral_skin.SpectralSkinError, match="mode must be one of BAKED, LIVE"):
        core.check(_settings(mode="live"))
