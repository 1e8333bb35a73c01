"""The EEVEE half-lit subsurface edge of a Live material (the "Spectral Skin" node group, EEVEE's table with its
radius compensation inside) against its Baked twin (the core's EEVEE Base Color and compensated radius as values),
both applied by the add-on (apply.apply_skins) in test_eevee_edge.py's scene: a hard-edged spot lighting the half-plane
x < 0 of a thick slab, seen by an orthographic top camera, in a world unit of U mm (the scene's unit scale, so the
add-on's Subsurface Scale converts its millimetres into it).

They agree within the shader table's errors (docs/shader-table.md, Burley 33 x 9 x 17: Base Color 0.450 %, radius
0.740 %) plus one step of EEVEE's surface colour (1/1024: 0.28 % of the bluest albedo here, 0.353). The group built
for EEVEE computes its bilinear weights itself (live.build_group, ``exact``): with the GPU's Linear filtering the
Live edge came out 0.25-0.5 % brighter and 0.4-0.9 % wider than Baked (Mesa llvmpipe misses by up to 0.03 texel).
Measured (docs/blender-render-tests.md, "Live mode"): identical in R and G, one colour step apart in B.
The frame is a smaller version of test_eevee_edge.py's (llvmpipe is slow): half its columns, 8 samples.

Run: <venv>/bin/python -m pytest tests/blender/test_live_eevee_edge.py -q -s
"""

from __future__ import annotations

import math

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

from blender_scenes import assign, eevee_engine_id, fit_burley_edge  # noqa: E402
from eevee_scene import (  # noqa: E402
    BLENDER,
    EEVEE_BAND_ROWS,
    EEVEE_PIXEL_ASPECT,
    EEVEE_ROWS,
    HALF_WIDTH_D,
    REPEATABLE_EEVEE_ONLY,
    Layout,
    Material,
    build_scene,
    render_eevee,
)
from live_scene import apply_materials, skin_material  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402

pytestmark = REPEATABLE_EEVEE_ONLY  # eevee_scene.py: bpy 4.2's EEVEE edge is not repeatable here

PRESET = "caucasian"  # the widest radii: the edge spans the most pixels
WIDTH_PX = 156  # 0.36 d_disk per pixel: caucasian 0.12 mm (its bluest Burley d is 0.6 px)
SAMPLES = 8
# Bounds (see the module's docstring): the table's Base Color (radius) error plus one EEVEE colour step.
EEVEE_STEP = 1.0 / 1024 / 0.35
RMS_BOUND = 0.00450 + EEVEE_STEP
LEVEL_RTOL = 0.00450 + EEVEE_STEP
WIDTH_RTOL = 0.00740 + EEVEE_STEP


def _edge_profiles() -> tuple[Layout, np.ndarray, dict[str, np.ndarray]]:
    ev = spectral_skin.evaluate(preset=PRESET, oiliness=0.0, outputs=("albedo", "radius"), blender=BLENDER,
                                engine="eevee")
    base = np.asarray(ev["methods"]["burley"]["base_color"], dtype=np.float64)
    layout = Layout(np.asarray(ev["methods"]["burley"]["subsurface_radius_mm"], dtype=np.float64), WIDTH_PX)
    # The scene with a placeholder material; then the two skins applied by the add-on for EEVEE in it.
    scene = build_scene(layout, Material([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], subsurface=False), EEVEE_ROWS,
                         EEVEE_PIXEL_ASPECT)
    scene.render.engine = eevee_engine_id()
    scene.unit_settings.scale_length = layout.unit_mm / 1000.0  # metres per world unit
    preset = spectral_skin.presets()[PRESET]
    values = {p: float(preset[p]) for p in ("melanin", "melanin_blend", "hemoglobin")}
    materials = {mode: skin_material(mode.title(), mode, **values) for mode in ("LIVE", "BAKED")}
    slab = bpy.data.objects["Slab"]
    assign(slab, materials["LIVE"])
    plans = apply_materials(scene, *materials.values())
    assert plans[0].live is not None and " eevee" in plans[0].live["group"]
    assert addon_nodes.tagged_nodes(materials["LIVE"].node_tree, "live")
    profiles = {}
    lo = (EEVEE_ROWS - EEVEE_BAND_ROWS) // 2
    for mode, material in materials.items():
        assign(slab, material)
        img = render_eevee(scene, SAMPLES)
        profiles[mode] = math.pi * img[lo : lo + EEVEE_BAND_ROWS].mean(axis=0) / layout.irradiance()[:, None]
    return layout, base, profiles


def test_live_eevee_edge_matches_its_baked_twin(addon):
    layout, base, profiles = _edge_profiles()
    live, baked = profiles["LIVE"], profiles["BAKED"]
    x = layout.x_mm
    flat = x < -0.5 * HALF_WIDTH_D * layout.d_disk_mm
    assert (baked[flat].mean(axis=0) > 0.5 * base).all(), "the lit side is lit"
    rms = np.sqrt(np.mean((live - baked) ** 2, axis=0)) / base
    level = live[flat].mean(axis=0) / baked[flat].mean(axis=0)
    # Burley length of each edge (level-matched to the baked one), fitted as test_eevee_edge.py does.
    d_guess = layout.d_disk_mm
    widths = {}
    for mode, prof in (("live", live / level), ("baked", baked)):
        widths[mode] = np.array([fit_burley_edge(x, prof[:, c], 0.02 * d_guess, 20 * d_guess)[0] for c in range(3)])
    ratio = widths["live"] / widths["baked"]
    pct = lambda v: np.array2string(np.asarray(v) * 100, precision=3)  # noqa: E731
    print(f"\n[live-eevee-edge] Blender {bpy.app.version_string} {PRESET}: {WIDTH_PX} px over {layout.width_mm:.2f} mm, "
          f"{SAMPLES} samples; rms (live - baked) / A {pct(rms)} %; flat level live / baked "
          f"{np.array2string(level, precision=5)}; fitted d live / baked {np.array2string(ratio, precision=4)}")
    assert np.all(rms < RMS_BOUND), rms
    np.testing.assert_allclose(level, 1.0, rtol=LEVEL_RTOL)
    np.testing.assert_allclose(ratio, 1.0, rtol=WIDTH_RTOL)
