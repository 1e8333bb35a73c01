"""Live mode's masks (blender_addon/masks.py) rendered by Cycles: a blush/flush mask painted in one half of a thick flat
slab (Burley, white world, oiliness 0: test_live_mode.py's setup) renders the core's albedo for haemoglobin +
strength, clamped to the parameter's range, in that half and the base albedo in the other; the mask's Strength keyed
at two frames follows with no Apply; a tan/vitiligo mask with a negative strength removes melanin down to the range's
end; a colour-attribute mask works as an image does. The expected parameter values are clamped here from
``spectral_skin.parameters()`` (not from the add-on's code).

Bound: the shader table's Base Color error plus 0.2 % for the render (test_live_mode.BOUND).
Run: python -m pytest tests/blender/test_live_masks.py -s
"""

from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from blender_scenes import add_slab, add_top_camera, assign, render, set_world  # noqa: E402
from live_scene import BURLEY_SPP, apply_materials, check, core_albedo, skin_material  # noqa: E402

from blender_addon import masks  # noqa: E402
from blender_addon import nodes as addon_nodes  # noqa: E402

SPAN_M = 0.2  # the camera's width; the UV map puts u = 0..1 across it, the mask's seam at x = 0
WIDTH_PX, HEIGHT_PX = 64, 64
# Measured columns: 25-75 mm from the seam (the largest Burley radius here is under 5 mm: its profile is gone by
# then), so each half is the flat slab of its own parameters.
PAINTED_COLUMNS, PLAIN_COLUMNS = slice(4, 24), slice(40, 60)
ROWS = slice(8, 56)


def _clamped(parameter: str, value: float) -> float:
    spec = next(p for p in spectral_skin.parameters() if p["name"] == parameter)
    return min(max(value, spec["min"]), spec["max"])


def _scene(**values: float):
    """A fresh scene: the UV-mapped slab with a new Live material of these parameters, under a white world."""
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", values.pop("mode", "LIVE"), **values)
    set_world(scene, strength=1.0)
    slab = add_slab()
    mesh = slab.data
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        x, y, _ = mesh.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (x / SPAN_M + 0.5, y / SPAN_M + 0.5)
    assign(slab, material)
    add_top_camera(scene, ortho_scale=SPAN_M, width=WIDTH_PX, height=HEIGHT_PX)
    return scene, material, slab


def _paint_left_half(image) -> None:
    """White where u < 0.5 (x < 0), black elsewhere, as a brush would leave it; packed again as after painting."""
    w, h = image.size
    rgba = np.zeros((h, w, 4), dtype=np.float32)
    rgba[..., 3] = 1.0
    rgba[:, : w // 2, :3] = 1.0
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    image.pack()


def _halves(scene) -> tuple[np.ndarray, np.ndarray]:
    img = render(scene, samples=BURLEY_SPP)
    return (img[ROWS, PAINTED_COLUMNS].reshape(-1, 3).mean(axis=0),
            img[ROWS, PLAIN_COLUMNS].reshape(-1, 3).mean(axis=0))


def _mask_image(mask_node):
    tree = mask_node.id_data
    link = mask_node.inputs["Mask"].links[0]
    source = link.from_node.inputs["Color"].links[0].from_node
    assert source in addon_nodes.tagged_nodes(tree, f"live {mask_node[addon_nodes.TAG].split()[1]} mask source")
    return source


def test_blush_mask_renders_the_cores_albedo_where_painted_keyed_at_two_frames(addon):
    scene, material, _ = _scene(melanin=0.05, hemoglobin=0.02)
    apply_materials(scene, material)
    assert bpy.ops.spectral_skin.add_blush_mask(material="Skin") == {"FINISHED"}
    (mask,) = masks.mask_nodes(material.node_tree, "hemoglobin")
    image = _mask_image(mask).image
    assert tuple(image.size) == (1024, 1024) and image.packed_file is not None
    assert image.colorspace_settings.name == "Non-Color"
    _paint_left_half(image)
    # Apply again: the panel's constant goes to the head of the mask chain, the mask stays.
    material.spectral_skin.hemoglobin = 0.02
    apply_materials(scene, material)
    assert masks.mask_nodes(material.node_tree, "hemoglobin") == [mask]
    base = core_albedo(0.05, 0.7, 0.02)
    strength = mask.inputs["Strength"]
    # Frame 1: 0.02 + 0.03 inside the range; frame 10: 0.02 + 0.09 clamped to the range's end (0.1).
    keys = ((1, 0.03), (10, 0.09))
    for frame, value in keys:
        strength.default_value = value
        strength.keyframe_insert("default_value", frame=frame)
    for frame, value in keys:
        scene.frame_set(frame)
        painted, plain = _halves(scene)
        hemoglobin = _clamped("hemoglobin", 0.02 + value)
        check(f"blush strength {value} at frame {frame}, painted half (C_h {hemoglobin})", painted,
               core_albedo(0.05, 0.7, hemoglobin))
        check(f"blush strength {value} at frame {frame}, unpainted half", plain, base)
    assert _clamped("hemoglobin", 0.11) < 0.11  # the second key does reach the clamp


def test_vitiligo_mask_removes_melanin_down_to_the_range(addon):
    scene, material, _ = _scene(melanin=0.05, hemoglobin=0.01)
    apply_materials(scene, material)
    assert bpy.ops.spectral_skin.add_tan_mask(material="Skin", strength=-0.08) == {"FINISHED"}
    (mask,) = masks.mask_nodes(material.node_tree, "melanin")
    _paint_left_half(_mask_image(mask).image)
    painted, plain = _halves(scene)
    check("vitiligo strength -0.08, painted half (C_m 0)", painted,
           core_albedo(_clamped("melanin", 0.05 - 0.08), 0.7, 0.01))
    check("vitiligo, unpainted half", plain, core_albedo(0.05, 0.7, 0.01))


def test_colour_attribute_mask(addon):
    scene, material, slab = _scene(melanin=0.05, hemoglobin=0.02)
    apply_materials(scene, material)
    assert bpy.ops.spectral_skin.add_blush_mask(material="Skin", source="ATTRIBUTE", strength=0.03) == {"FINISHED"}
    (mask,) = masks.mask_nodes(material.node_tree, "hemoglobin")
    attribute = slab.data.color_attributes[_mask_image(mask).layer_name]
    assert attribute.data_type == "FLOAT_COLOR" and attribute.domain == "CORNER"
    painted, plain = _halves(scene)
    check("unpainted attribute, left", painted, core_albedo(0.05, 0.7, 0.02))
    for corner in attribute.data:  # painted white everywhere
        corner.color = (1.0, 1.0, 1.0, 1.0)
    slab.data.update()
    painted, plain = _halves(scene)
    for what, got in (("left", painted), ("right", plain)):
        check(f"attribute painted white, strength 0.03, {what}", got, core_albedo(0.05, 0.7, 0.05))


def test_mask_over_a_keyed_input_warns_and_a_failed_mask_changes_nothing(addon):
    scene, material, slab = _scene(melanin=0.05, hemoglobin=0.02)
    apply_materials(scene, material)
    tree = material.node_tree
    (group_node,) = addon_nodes.tagged_nodes(tree, "live")
    group_node.inputs["Hemoglobin"].keyframe_insert("default_value", frame=1)
    mask = masks.add_mask(material, "BLUSH")
    assert masks.keyed_input(mask) == "Hemoglobin"
    assert masks.keyed_input(masks.add_mask(material, "TAN")) is None
    # A colour attribute mask with no mesh using the material: an error, and the tree and meshes as they were.
    before = sorted(n.name for n in tree.nodes)
    slab.data.materials.clear()
    with pytest.raises(ValueError, match="no mesh uses the material"):
        masks.add_mask(material, "BLUSH", source="ATTRIBUTE")
    assert sorted(n.name for n in tree.nodes) == before and not slab.data.color_attributes


def test_mask_needs_live_mode(addon):
    scene, material, _ = _scene(mode="BAKED")
    apply_materials(scene, material)
    with pytest.raises(ValueError, match="apply it in Live mode first"):
        masks.add_mask(material, "BLUSH")
