"""The add-on's Surface choice in Blender (issue 24): the menu is the core's ``surface_models()``; Apply with the
measured surface sets the Principled BSDF's level and Coat as ``evaluate(surface="measured")`` gives them, and the
material as applied reflects 0.024-0.05 along the normal at every oiliness (rendered by Cycles: the Principled
node's own inputs after Apply, over Base Color black, under a uniform white world), dry skin included; the paper's
surface applied to dry skin reflects nothing.

Run: .venv-blender/5.0/bin/python -m pytest tests/blender/test_addon_surface.py
"""

from __future__ import annotations

import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")

import spectral_skin  # noqa: E402
from blender_scenes import PRINCIPLED_SURFACE_INPUTS, render_normal_incidence_reflection  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402

CATALOG = spectral_skin.surface_models()
OILINESS = (0.0, 0.3, 1.0)


def _applied_inputs(surface: str, oiliness: float) -> dict[str, float]:
    """Apply the add-on to a new caucasian material with ``surface`` and ``oiliness``; its Principled BSDF's surface
    inputs as Apply left them."""
    material = bpy.data.materials.new(f"Skin {surface} {oiliness}")
    props = material.spectral_skin
    props.preset = "CAUCASIAN"
    props.oiliness = oiliness
    props.surface = surface.upper()
    assert bpy.ops.spectral_skin.apply(material=material.name) == {"FINISHED"}
    (node,) = addon_nodes.tagged_nodes(material.node_tree, "principled")
    return {name: float(node.inputs[name].default_value) for name in PRINCIPLED_SURFACE_INPUTS}


def test_surface_menu_is_the_cores(addon):
    rna = bpy.types.Material.bl_rna.properties["spectral_skin"].fixed_type.bl_rna.properties["surface"]
    assert [i.identifier for i in rna.enum_items] == [m["name"].upper() for m in CATALOG]
    assert rna.default == next(m["name"] for m in CATALOG if m["default"]).upper()


def test_applied_measured_surface_reflects_like_skin_at_every_oiliness(addon):
    bpy.context.scene.render.engine = "CYCLES"
    applied = [_applied_inputs("measured", o) for o in OILINESS]
    for oiliness, inputs in zip(OILINESS, applied, strict=True):
        expected = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",),
                                          surface="measured", blender=bpy.app.version)["specular"]
        for name, key in PRINCIPLED_SURFACE_INPUTS.items():
            assert inputs[name] == pytest.approx(expected[key], rel=1e-6), (oiliness, name)
    # Oil sharpens the Coat and raises its weight.
    assert applied[0]["Coat Roughness"] > applied[2]["Coat Roughness"]
    assert applied[0]["Coat Weight"] < applied[2]["Coat Weight"]
    paper_dry = _applied_inputs("paper", 0.0)
    assert paper_dry["Specular IOR Level"] == 0.0 and paper_dry["Coat Weight"] == 0.0
    rendered = render_normal_incidence_reflection([*applied, paper_dry], "cycles", 512)
    print(f"[{bpy.app.version_string}] applied measured surface, oiliness {OILINESS}: {rendered[:3]}; "
          f"paper, dry: {rendered[3]}")
    for oiliness, got in zip(OILINESS, rendered, strict=False):
        assert 0.024 <= got <= 0.05, (oiliness, got)
    assert rendered[3] < 1e-6, rendered


def test_live_mode_links_the_groups_surface_outputs(addon):
    """Live mode with the measured surface: the group (named for the surface) feeds the Principled BSDF's Specular IOR
    Level, Coat Weight and Coat Roughness; the group's values are checked by tests/blender/test_live_group.py."""
    bpy.context.scene.render.engine = "CYCLES"
    groups = {}
    for surface in ("PAPER", "MEASURED"):
        material = bpy.data.materials.new(f"Live skin {surface}")
        props = material.spectral_skin
        props.mode = "LIVE"
        props.surface = surface
        assert bpy.ops.spectral_skin.apply(material=material.name) == {"FINISHED"}
        (principled,) = addon_nodes.tagged_nodes(material.node_tree, "principled")
        (group,) = addon_nodes.tagged_nodes(material.node_tree, "live")
        groups[surface] = group.node_tree.name
    # One group per surface (the default's name has no surface in it, the other's does).
    assert groups["PAPER"].endswith("paper") and groups["MEASURED"] != groups["PAPER"], groups
    for name in ("Specular IOR Level", "Coat Weight", "Coat Roughness"):
        links = principled.inputs[name].links
        assert len(links) == 1 and links[0].from_node == group and links[0].from_socket.name == name, name
