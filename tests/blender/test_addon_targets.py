"""The add-on computes for the Blender it runs in and the scene's render engine (the core's target table): EEVEE
scenes get the radius compensated for EEVEE's Burley, the method menu is this Blender's, other engines are refused.

Headless, no rendering. The EEVEE reference is Christensen & Burley 2015's s(A) written out here, applied to the
Cycles radius. Run: .venv/bin/python -m pytest tests/blender/test_addon_targets.py
"""

from __future__ import annotations

import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402
from blender_scenes import eevee_engine_id, read_exr  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402


def _s(albedo: np.ndarray) -> np.ndarray:
    """EEVEE divides Radius x Scale by s(A_n), A_n = A / max(A) per channel (Christensen & Burley 2015, eq. 6)."""
    a = albedo / albedo.max(axis=-1, keepdims=True)
    return 1.9 - a + 3.5 * (a - 0.8) ** 2


def _radius_mm(node) -> np.ndarray:
    scale_mm = node.inputs["Subsurface Scale"].default_value * bpy.context.scene.unit_settings.scale_length / 1e-3
    return np.array(node.inputs["Subsurface Radius"].default_value) * scale_mm


@pytest.mark.parametrize("preset", ["caucasian", "african"])
def test_eevee_scene_gets_the_compensated_radius(addon, preset):
    material = bpy.data.materials.new("Skin")
    material.spectral_skin.preset = preset.upper()
    bpy.context.scene.render.engine = "CYCLES"
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    node = addon_nodes.tagged_nodes(material.node_tree, "principled")[0]
    cycles_albedo = np.array(node.inputs["Base Color"].default_value[:3])
    cycles_radius = _radius_mm(node)
    assert "CYCLES" in material.spectral_skin.result_target

    bpy.context.scene.render.engine = eevee_engine_id()
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    assert "EEVEE" in material.spectral_skin.result_target
    np.testing.assert_allclose(node.inputs["Base Color"].default_value[:3], cycles_albedo, rtol=1e-6)
    np.testing.assert_allclose(_radius_mm(node), cycles_radius * _s(cycles_albedo), rtol=1e-5)
    assert np.max(np.abs(_s(cycles_albedo) - 1.0)) > 0.05  # the compensation is not a no-op for this skin


def test_eevee_radius_map_is_compensated_per_texel(addon, tmp_path):
    melanin = np.array([[0.01, 0.1], [0.25, 0.45]], dtype=np.float32)
    path = tmp_path / "melanin.exr"
    import OpenImageIO as oiio

    spec = oiio.ImageSpec(2, 2, 1, "float")
    spec.channelnames = ("melanin",)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(np.ascontiguousarray(melanin[:, :, None]))
    out.close()
    material = bpy.data.materials.new("Skin")
    material.spectral_skin.melanin_map = bpy.data.images.load(str(path))
    material.spectral_skin.output_dir = str(tmp_path / "maps")
    radius = {}
    for engine in ("CYCLES", eevee_engine_id()):
        bpy.context.scene.render.engine = engine
        assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
        radius[engine] = read_exr(str(tmp_path / "maps" / "Skin_radius.exr"))[:, :, :3]
        albedo = read_exr(str(tmp_path / "maps" / "Skin_albedo.exr"))[:, :, :3]
    # Both radius maps and the albedo are written as half floats (within 2^-11 each): rtol 2e-3, against
    # compensation factors s(A_n) of 1.0 to 2.1 here.
    np.testing.assert_allclose(radius[eevee_engine_id()], radius["CYCLES"] * _s(albedo.astype(np.float64)), rtol=2e-3)


def test_method_menu_is_this_blenders(addon):
    """The menu offers exactly the subsurface methods this Blender's Principled BSDF has."""
    props = bpy.data.materials.new("Skin").spectral_skin
    ours = {i.identifier for i in props.bl_rna.properties["method"].enum_items}
    blenders = {i.identifier for i in bpy.types.ShaderNodeBsdfPrincipled.bl_rna.properties["subsurface_method"].enum_items}
    assert ours == blenders


def test_random_walk_is_this_blenders(addon):
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new("Skin")
    material.spectral_skin.method = "RANDOM_WALK"
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    node = addon_nodes.tagged_nodes(material.node_tree, "principled")[0]
    assert node.subsurface_method == "RANDOM_WALK"
    version = f"{bpy.app.version[0]}.{bpy.app.version[1]}"
    expected = spectral_skin.evaluate(preset="caucasian", blender=version)
    assert f"Blender {expected['target']['blender']}" in material.spectral_skin.result_target
    np.testing.assert_allclose(_radius_mm(node), expected["methods"]["random_walk"]["subsurface_radius_mm"], rtol=1e-5)


def test_engine_without_subsurface_is_refused(addon):
    material = bpy.data.materials.new("Skin")
    bpy.context.scene.render.engine = "BLENDER_WORKBENCH"
    with pytest.raises(RuntimeError, match="BLENDER_WORKBENCH.*Cycles or EEVEE"):
        bpy.ops.spectral_skin.apply(material="Skin")
    # Nothing changed: no node tree at all (Blender 4.2 creates materials without one) or none of the add-on's nodes.
    assert material.node_tree is None or not addon_nodes.tagged_nodes(material.node_tree)
