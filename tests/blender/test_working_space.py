"""The scene's colour working space (Blender 5.0: Linear Rec.709, Linear Rec.2020, ACEScg) is honoured by the add-on.

For each working space Blender lets a file have (``bpy.data.colorspace.working_space``, read-only in RNA, set with
``bpy.ops.wm.set_working_color_space``):

- the plan carries the scene's space and the Principled Base Color the add-on sets equals
  ``spectral_skin.evaluate(preset=..., working_space=<space>)``'s Burley base_color;
- a Burley flat slab under a uniform white world renders (in the scene's working space, which is what the EXR holds)
  the core's total diffuse reflectance in that space, within 0.3 %;
- with parameter maps, the albedo texture is tagged with the working space's colour space (radius and specular stay
  Non-Color) and the slab renders the same albedo through the texture.

Run: .venv/bin/python -m pytest tests/blender/test_working_space.py -q -s
"""

from __future__ import annotations

import types

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")


from blender_scenes import add_slab, add_top_camera, assign, render, reset_scene, set_world  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.apply import apply_skin  # noqa: E402
from blender_addon.core import WORKING_SPACES, ParameterMap, SkinSettings, compute  # noqa: E402
from blender_addon.core.scene import scene_plan  # noqa: E402
from blender_addon.nodes import scene_working_space  # noqa: E402

PRESET = "caucasian"
# 256 spp: Cycles' Burley flat-slab estimate with unequal RGB radii has a correlated error of about 0.12 % at 64-256
# spp (test_renders.py), well inside the 0.3 % tolerance; a 64 x 64 render takes well under a second.
SPP = 256
RTOL = 3e-3


def _spaces() -> list[str]:
    colorspace = getattr(bpy.data, "colorspace", None)
    if colorspace is None:  # Blender < 5.0: only Rec.709
        return ["Linear Rec.709"]
    return [e.identifier for e in colorspace.bl_rna.properties["working_space"].enum_items]


SPACES = _spaces()


def _scene_in(space: str):
    """A fresh render scene (blender_scenes.reset_scene) whose file working space is ``space``."""
    scene = reset_scene()
    if space != scene_working_space():
        assert bpy.ops.wm.set_working_color_space(working_space=space, convert_colors=False) == {"FINISHED"}
    assert scene_working_space() == space
    return scene


def _slab_mean(scene, material, size_px: int = 64, region_px: int = 32) -> np.ndarray:
    """The mean rendered RGB over the centre of a flat slab with ``material`` under a uniform white world."""
    set_world(scene, strength=1.0)
    slab = add_slab()
    assign(slab, material)
    add_top_camera(scene, ortho_scale=0.1, width=size_px, height=size_px)
    img = render(scene, samples=SPP)
    lo = (size_px - region_px) // 2
    return img[lo : lo + region_px, lo : lo + region_px].reshape(-1, 3).mean(axis=0)


def _no_specular(material) -> None:
    """Specular IOR Level 0 and Coat Weight 0 (their textures unlinked): no surface reflection, so the slab renders
    exactly its subsurface albedo."""
    principled = addon_nodes.tagged_nodes(material.node_tree, "principled")[0]
    for name in ("Specular IOR Level", "Coat Weight"):
        for link in list(principled.inputs[name].links):
            material.node_tree.links.remove(link)
        principled.inputs[name].default_value = 0.0


def test_blender_lists_the_known_spaces():
    assert set(SPACES) <= set(WORKING_SPACES)
    if hasattr(bpy.data, "colorspace"):
        assert set(SPACES) == set(WORKING_SPACES)
    image = bpy.data.images.new("spectral_skin_ws_probe", 1, 1, float_buffer=True)
    try:
        names = {e.identifier for e in image.colorspace_settings.bl_rna.properties["name"].enum_items}
    finally:
        bpy.data.images.remove(image)
    # The albedo texture is tagged with the working space's own name: it must be an image colour space too.
    assert set(SPACES) <= names


@pytest.mark.parametrize("space", SPACES)
def test_constant_base_color_and_render_in_working_space(addon, space):
    scene = _scene_in(space)
    material = bpy.data.materials.new("Skin")
    plan = apply_skin(material, SkinSettings.from_preset(PRESET))
    assert plan.working_space == space

    expected = spectral_skin.evaluate(preset=PRESET, working_space=space)
    assert expected["color_space"] == space
    principled = addon_nodes.tagged_nodes(material.node_tree, "principled")[0]
    base_color = np.asarray(principled.inputs["Base Color"].default_value[:3], dtype=np.float64)
    np.testing.assert_allclose(base_color, expected["methods"]["burley"]["base_color"], rtol=1e-6)

    _no_specular(material)
    mean = _slab_mean(scene, material)
    albedo = np.asarray(expected["diffuse_reflectance_rgb"])
    print(f"\n[{space}] rendered {np.array2string(mean, precision=6)} core {np.array2string(albedo, precision=6)} "
          f"rel.err {np.array2string((mean / albedo - 1) * 100, precision=4)} %")
    np.testing.assert_allclose(mean, albedo, rtol=RTOL)


@pytest.mark.parametrize("space", SPACES)
def test_albedo_texture_tagged_with_working_space(addon, space, tmp_path):
    scene = _scene_in(space)
    material = bpy.data.materials.new("SkinMaps")
    preset = spectral_skin.presets()[PRESET]
    # Uniform 2 x 2 maps (oiliness varying so that a specular texture is written too): every texel is the preset.
    oiliness = np.full((2, 2), preset["oiliness"], dtype=np.float32)
    oiliness[0, 0] = 0.5
    settings = SkinSettings.from_preset(PRESET).replace(
        maps={"melanin": ParameterMap(np.full((2, 2), preset["melanin"], dtype=np.float32), normalized=False),
              "oiliness": ParameterMap(oiliness, normalized=False)},
        output_dir=str(tmp_path))
    material.spectral_skin.override_constant_maps = "OFF"  # the textures of one value, not values: their path
    plan = apply_skin(material, settings)
    assert plan.working_space == space
    colorspaces = {role: addon_nodes.tagged_nodes(material.node_tree, role)[0].image.colorspace_settings.name
                   for role in ("albedo", "radius", "specular")}
    assert colorspaces == {"albedo": space, "radius": "Non-Color", "specular": "Non-Color"}

    # The texture path renders the core's albedo in the scene's space too (a Rec.709 tag in a Rec.2020 or ACEScg
    # scene would be converted by Blender and miss by several per cent).
    _no_specular(material)
    mean = _slab_mean(scene, material)
    albedo = np.asarray(spectral_skin.evaluate(preset=PRESET, working_space=space)["diffuse_reflectance_rgb"])
    print(f"\n[{space}, texture] rendered {np.array2string(mean, precision=6)} "
          f"rel.err {np.array2string((mean / albedo - 1) * 100, precision=4)} %")
    np.testing.assert_allclose(mean, albedo, rtol=RTOL)


def test_plan_in_another_space_is_refused():
    """A constant Base Color computed for Rec.709 must not land in a scene with another working space."""
    other = [s for s in SPACES if s != "Linear Rec.709"]
    if not other:
        pytest.skip("this Blender has only Linear Rec.709")
    _scene_in(other[0])
    material = bpy.data.materials.new("Mismatch")
    plan = scene_plan(SkinSettings.from_preset(PRESET), None)  # working_space defaults to Linear Rec.709
    with pytest.raises(ValueError, match="working space"):
        addon_nodes.apply_plan(material, plan)


def test_settings_reject_unknown_space():
    with pytest.raises(spectral_skin.SpectralSkinError, match="working space"):
        compute(SkinSettings.from_preset(PRESET, working_space="sRGB"))


def test_fallback_without_colorspace(monkeypatch):
    """Blender before 5.0 has no bpy.data.colorspace: the scene is Linear Rec.709."""
    monkeypatch.setattr(addon_nodes, "bpy", types.SimpleNamespace(data=types.SimpleNamespace()))
    assert addon_nodes.scene_working_space() == "Linear Rec.709"
