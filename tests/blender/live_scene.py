"""The Live-mode slab scene, shared by the Live, farm and job tests: a skin material as the panel makes it (Live or
Baked), the add-on's one Apply path, the flat slab under a white world framed so every radius covers a pixel, and
the check against the core (test_live_mode.py's module doc: the bound and why)."""

from __future__ import annotations

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
spectral_skin = pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from blender_scenes import add_slab, add_top_camera, assign, set_world  # noqa: E402

from blender_addon.apply import apply_skins  # noqa: E402
from blender_addon.props import settings_from_material  # noqa: E402

TABLE_ERROR = 0.00450  # docs/shader-table.md, burley, 33x9x17, Base Color
BOUND = TABLE_ERROR + 0.002
BURLEY_SPP = 512  # test_renders.py: the 64 x 64 flat slab



def core_albedo(melanin: float, melanin_blend: float, hemoglobin: float) -> np.ndarray:
    ev = spectral_skin.evaluate(melanin, melanin_blend, hemoglobin, 0.0, outputs=("albedo",),
                                blender=tuple(bpy.app.version), engine="cycles")
    return np.asarray(ev["diffuse_reflectance_rgb"], dtype=np.float64)


def skin_material(name: str, mode: str, **values: float):
    material = bpy.data.materials.new(name)
    props = material.spectral_skin
    props.mode = mode
    props.surface = "PAPER"  # oiliness 0: no surface reflection, the slab shows its albedo alone
    props.override_subsurface = "ON"  # Baked and Live alike: the slab's albedo with subsurface
    for key, value in {"melanin": 0.01, "melanin_blend": 0.7, "hemoglobin": 0.005, "oiliness": 0.0, **values}.items():
        setattr(props, key, value)
    return material


def apply_materials(scene, *materials) -> list[dict]:
    return apply_skins([(m, settings_from_material(m, scene)) for m in materials], scene)


def slab_scene(material):
    """The flat slab under a white world, seen at most 0.1 m wide, narrower where one of the material's Burley radii
    would cover less than a pixel (blender_scenes.span_resolving)."""
    scene = bpy.context.scene
    set_world(scene, strength=1.0)
    slab = add_slab()
    assign(slab, material)
    props = material.spectral_skin
    radius_mm = spectral_skin.evaluate(props.melanin, props.melanin_blend, props.hemoglobin, 0.0,
                                       outputs=("albedo", "radius"), blender=tuple(bpy.app.version),
                                       engine="cycles")["methods"]["burley"]["subsurface_radius_mm"]
    add_top_camera(scene, ortho_scale=blender_scenes.span_resolving(radius_mm, 64, 0.1), width=64, height=64)
    return scene


def centre(img: np.ndarray) -> np.ndarray:
    return img[16:48, 16:48].reshape(-1, 3).mean(axis=0)


def check(what: str, got: np.ndarray, expected: np.ndarray, rtol: float = BOUND, atol: float = 0.0) -> float:
    rel = got / expected - 1.0
    print(f"\n[live] {what}: rendered {np.array2string(got, precision=6)} core "
          f"{np.array2string(expected, precision=6)} rel.err {np.array2string(rel * 100, precision=4)} %")
    np.testing.assert_allclose(got, expected, rtol=rtol, atol=atol, err_msg=what)
    return float(np.abs(rel).max())
