"""The surface model in the add-on's portable part (blender_addon/core, loaded without bpy): the plan carries the
measured surface's Coat (values, or textures when the oiliness varies), the scene analysis keeps the measured
surface's reflection on dry skin (the paper's oil layer is dropped there), forced off drops the Coat too, animated
oiliness gives the Coat per frame, and Live mode's group gets the core's oiliness nodes of the surface. Values are
checked against the core's own ``evaluate`` (the add-on computes nothing itself)."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import spectral_skin
from addon_helpers import animation_facts, core, scene, scene_facts, with_changes

MEASURED = next(key for key, name in core.SURFACES.items() if name == "measured")
PAPER = next(key for key, name in core.SURFACES.items() if name == "paper")


def _specular(oiliness: float, surface: str = "measured", engine: str = "cycles") -> dict:
    return dict(spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",),
                                       surface=surface, engine=engine)["specular"])


def test_surface_choices_come_from_the_core():
    assert set(core.SURFACES.values()) == {m["name"] for m in spectral_skin.surface_models()}
    assert core.SURFACES[core.DEFAULT_SURFACE] == next(m["name"] for m in spectral_skin.surface_models()
                                                        if m["default"])
    with pytest.raises(spectral_skin.SpectralSkinError, match="surface must be one of.*MEASURED"):
        core.compute(core.SkinSettings(surface="GLOSSY"))


@pytest.mark.parametrize("engine", ["cycles", "eevee"])
def test_measured_constants_set_the_coat(engine):
    settings = core.SkinSettings.from_preset("caucasian", surface=MEASURED, engine=engine)
    plan = scene.scene_plan(settings, None)
    expected = _specular(settings.oiliness, engine=engine)
    assert plan.surface == "measured"
    for field in ("specular_ior_level", "roughness", "coat_weight", "coat_roughness", "coat_ior", "ior"):
        assert getattr(plan, field) == pytest.approx(expected[field], rel=1e-12), field
    # The paper's surface has no Coat.
    paper = scene.scene_plan(settings.replace(surface=PAPER), None)
    assert paper.surface == "paper" and paper.coat_weight == 0.0


def test_dry_skin_keeps_the_measured_reflection():
    dry = core.SkinSettings.from_preset("caucasian", oiliness=0.0, surface=MEASURED)
    plan = scene.scene_plan(dry, None)
    entry = next(e for e in plan.effects if e["effect"] == "specular")
    assert entry["enabled"] and "every oiliness" in entry["reason"], entry
    expected = _specular(0.0)
    assert plan.specular_ior_level == pytest.approx(expected["specular_ior_level"]) and plan.specular_ior_level > 0.4
    assert plan.coat_weight == pytest.approx(expected["coat_weight"]) and plan.coat_weight > 0.1
    assert plan.work["specular_evaluations"] == 1
    # The paper's oil layer on the same dry skin: nothing reflects, nothing computed.
    paper = scene.scene_plan(dry.replace(surface=PAPER), None)
    assert not scene.enabled(paper.effects, "specular") and paper.specular_ior_level == 0.0
    # Forced off: no level and no Coat.
    off = scene.scene_plan(dry, None, {"specular": "OFF"})
    assert (off.specular_ior_level, off.coat_weight) == (0.0, 0.0)


def test_varying_oiliness_writes_the_coat_textures(tmp_path):
    oiliness = np.linspace(0.0, 1.0, 16, dtype=np.float32).reshape(4, 4)
    melanin = np.linspace(0.01, 0.4, 16, dtype=np.float32).reshape(4, 4)
    maps = {"melanin": core.ParameterMap(melanin, False), "oiliness": core.ParameterMap(oiliness, False)}
    settings = core.SkinSettings.from_preset("caucasian", maps=maps, output_dir=str(tmp_path), file_prefix="Skin",
                                             surface=MEASURED)
    plan = scene.scene_plan(settings, None)
    assert sorted(plan.textures) == ["albedo", "coat_roughness", "coat_weight", "radius", "specular"]
    assert (plan.specular_ior_level, plan.coat_weight, plan.coat_roughness) == (None, None, None)
    for y, x in [(0, 0), (3, 3), (1, 2)]:
        expected = _specular(float(oiliness[y, x]))
        for texture, field in (("specular", "specular_ior_level"), ("coat_weight", "coat_weight"),
                               ("coat_roughness", "coat_roughness")):
            assert plan.textures[texture][y, x] == pytest.approx(expected[field], rel=1e-6), (texture, y, x)
    core.write_textures(plan)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"Skin_{k}.exr" for k in sorted(plan.textures)]
    # Specular forced off: no surface texture is kept, and the files of the earlier write are removed.
    off = scene.scene_plan(settings, None, {"specular": "OFF"})
    assert sorted(off.textures) == ["albedo", "radius"] and (off.specular_ior_level, off.coat_weight) == (0.0, 0.0)
    core.write_textures(off)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["Skin_albedo.exr", "Skin_radius.exr"]


def test_animated_oiliness_gives_the_coat_per_frame():
    settings = core.SkinSettings.from_preset("caucasian", surface=MEASURED)
    plan = scene.scene_plan(settings, with_changes(scene_facts(0.5), animation=animation_facts({"oiliness": (0.0, 0.5, 1.0)})))
    for index, oiliness in enumerate((0.0, 0.5, 1.0)):
        expected = _specular(oiliness)
        for field in ("specular_ior_level", "coat_weight", "coat_roughness"):
            assert plan.animation[field][index] == pytest.approx(expected[field], rel=1e-12), (field, oiliness)
    assert plan.animation["coat_weight"][0] < plan.animation["coat_weight"][2]


def test_live_plan_carries_the_surfaces_nodes():
    """Live mode: the group is named for the surface (its outputs differ) and built from the core's oiliness nodes,
    whose linear interpolation is what evaluate gives (level and Coat Weight exactly, Coat Roughness within 6e-5)."""
    live = importlib.import_module("addon_core.live")
    settings = core.SkinSettings.from_preset("caucasian", surface=MEASURED, mode="LIVE", blender="5.0")
    plan = live.live_plan(settings, None, {}, table_needed=False)
    nodes = plan.live["surface_nodes"]
    assert nodes["surface"] == "measured" and nodes["oiliness"][0] == 0.0 and nodes["oiliness"][-1] == 1.0
    names = {live.table_name(settings.replace(surface=s), {}) for s in core.SURFACES}
    assert len(names) == len(core.SURFACES) and live.table_name(settings.replace(surface=PAPER), {}).endswith("paper")
    for oiliness in np.linspace(0.0, 1.0, 41):
        expected = _specular(float(oiliness))
        for key, atol in (("specular_ior_level", 1e-12), ("coat_weight", 1e-12), ("coat_roughness", 6e-5)):
            interpolated = np.interp(oiliness, nodes["oiliness"], nodes[key])
            assert interpolated == pytest.approx(expected[key], abs=atol), (key, oiliness)
    # The plan's constants are the panel's oiliness's, as in Baked mode.
    assert plan.coat_weight == pytest.approx(_specular(settings.oiliness)["coat_weight"])
