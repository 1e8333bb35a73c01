"""The live node group (blender_addon/live.py) rendered by Cycles: its Base Color and Subsurface Radius outputs,
shown through an Emission shader (radiance = the output, Raw view, float EXR), against the core's direct evaluation
(within the shader table's error, docs/shader-table.md) and against a numpy emulation of the documented lookup at float
precision (the layout, the coordinate maths and Cycles' Linear/Extend image lookup agree)."""

from __future__ import annotations

import numpy as np
import pytest
from blender_scenes import _bpy, add_plane, add_top_camera, assign, render, set_world


def _bilinear(image: np.ndarray, x: float, y: float) -> np.ndarray:
    """Image Texture, Linear, Extend, at (x, y) in [0, 1]^2 with y = 0 the bottom row; image row 0 is the top."""
    h, w, _ = image.shape
    px, py = x * w - 0.5, y * h - 0.5
    x0, y0 = int(np.floor(px)), int(np.floor(py))
    tx, ty = px - x0, py - y0
    up = image[::-1].astype(np.float64)

    def at(xi: int, yi: int) -> np.ndarray:
        return up[min(max(yi, 0), h - 1), min(max(xi, 0), w - 1)]

    return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) + ty * (
        (1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1)
    )


def _emulated(table: dict, key: str, c_m: float, beta: float, c_h: float) -> np.ndarray:
    meta = table["metadata"]
    n_m, n_b, n_h = (meta[a]["nodes"] for a in ("melanin", "melanin_blend", "hemoglobin"))
    u_m, u_h = min(c_m / 0.5, 1.0) ** (1 / 3), min(c_h / 0.1, 1.0) ** (1 / 3)
    b = min(max(beta, 0.0), 1.0) * (n_b - 1)
    j = min(np.floor(b), n_b - 2)
    t = b - j
    xs = [(s * meta["slice_width"] + meta["gutter"] + u_m * (n_m - 1) + 0.5) / meta["width"] for s in (j, j + 1)]
    y = (u_h * (n_h - 1) + 0.5) / n_h
    return np.exp((1 - t) * _bilinear(table[key], xs[0], y) + t * _bilinear(table[key], xs[1], y))


def _emission_probe(scene, group, width: int):
    """A plane filling a ``width`` x ``width`` top view in a black world, whose material shows one output of a node of
    ``group`` through an Emission shader of strength 1 (radiance = the output): (node tree, emission, group node)."""
    bpy = _bpy()
    set_world(scene, 0.0)
    add_top_camera(scene, ortho_scale=0.5, width=width, height=width)
    plane = add_plane("Plane", -1.0, 1.0, -1.0, 1.0, 0.0)
    mat = bpy.data.materials.new("Live")
    if mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emission = nt.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    nt.links.new(emission.outputs["Emission"], out.inputs["Surface"])
    node = nt.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    assign(plane, mat)
    return nt, emission, node


def test_live_group_in_cycles_matches_the_core(scene) -> None:
    spectral_skin = pytest.importorskip("spectral_skin")
    if not hasattr(spectral_skin, "shader_table"):
        pytest.skip("the installed spectral_skin predates shader_table")
    from blender_addon import live

    table = spectral_skin.shader_table(method="random_walk", blender="5.0")
    nt, emission, node = _emission_probe(scene, live.build_group(table), width=4)
    points = [
        (0.1, 0.5, 0.02),
        (0.0, 0.0, 0.0),
        (0.5, 1.0, 0.1),
        (0.013, 0.31, 0.004),
        (0.37, 0.83, 0.071),
        (0.25, 1.0 / 6.0, 0.05),
    ]
    rng = np.random.default_rng(3)
    points += [
        tuple(v) for v in np.column_stack([rng.uniform(0, 0.5, 4), rng.uniform(0, 1, 4), rng.uniform(0, 0.1, 4)])
    ]
    for c_m, beta, c_h in points:
        for socket, value in zip(live.INPUTS, (c_m, beta, c_h, 0.3), strict=True):
            node.inputs[socket].default_value = value
        exact = spectral_skin.evaluate(melanin=c_m, melanin_blend=beta, hemoglobin=c_h, oiliness=0.3, blender="5.0",
                                       surface="paper")  # build_group's surface when none is given
        rw = exact["methods"]["random_walk"]
        for output, key, reference in (
            ("Base Color", "base_color_log", rw["base_color"]),
            ("Subsurface Radius", "radius_log", rw["subsurface_radius_mm"]),
        ):
            nt.links.new(node.outputs[output], emission.inputs["Color"])
            pixels = render(scene, samples=1, filter_width=0.01)
            got = pixels.reshape(-1, 3)
            assert np.ptp(got, axis=0).max() <= 1e-6 * got.max(), "uniform emission"
            where = f"{output} at {(c_m, beta, c_h)}"
            np.testing.assert_allclose(got[0], _emulated(table, key, c_m, beta, c_h), rtol=1e-4, err_msg=where)
            np.testing.assert_allclose(got[0], reference, rtol=0.01, err_msg=where)
    # Specular IOR Level: 0.5 * clamp(oiliness, 0, 1), the core's mapping, at the last point's oiliness 0.3.
    nt.links.new(node.outputs["Specular IOR Level"], emission.inputs["Color"])
    level = render(scene, samples=1, filter_width=0.01).reshape(-1, 3)
    np.testing.assert_allclose(level, exact["specular"]["specular_ior_level"], rtol=1e-6)


def test_live_group_computes_the_measured_surface(scene) -> None:
    """The group built with the measured surface's nodes: its Specular IOR Level, Coat Weight and Coat Roughness
    outputs, rendered through an Emission shader at oiliness values on and between the nodes (and outside [0, 1]),
    equal ``evaluate(surface="measured")``: the level and the weight exactly (piecewise linear in the core too), the
    Coat Roughness within 6e-5 (linear between nodes of a square root)."""
    spectral_skin = pytest.importorskip("spectral_skin")
    from blender_addon import live

    table = spectral_skin.shader_table(method="burley", blender="5.0")
    nodes = spectral_skin.surface_input_nodes("measured", engine="cycles")
    group = live.build_group(table, "Measured", surface_nodes=dict(nodes))
    nt, emission, node = _emission_probe(scene, group, width=2)
    for oiliness in (0.0, 0.05, 0.3, 0.77, 1.0, 1.5, -0.2):
        node.inputs["Oiliness"].default_value = oiliness
        expected = spectral_skin.evaluate(preset="caucasian", oiliness=min(max(oiliness, 0.0), 1.0),
                                          outputs=("specular",), surface="measured")["specular"]
        for output, key in live.SURFACE_OUTPUTS.items():
            nt.links.new(node.outputs[output], emission.inputs["Color"])
            got = render(scene, samples=1, filter_width=0.01).reshape(-1, 3)
            tolerance = 6e-5 if key == "coat_roughness" else 1e-6 * expected[key]
            np.testing.assert_allclose(got, expected[key], rtol=0, atol=tolerance, err_msg=f"{output} at {oiliness}")


def test_live_group_in_eevee_matches_the_emulated_lookup(scene) -> None:
    """EEVEE: the group built for an EEVEE table computes its bilinear weights itself (Closest lookups at texel
    centres; GPU filtering missed by up to 0.03 texel under llvmpipe, 4 % at steep points of the table): its outputs
    match the emulated lookup within EEVEE's half-float output (0.2 %), at points away from the texel centres."""
    spectral_skin = pytest.importorskip("spectral_skin")
    bpy = _bpy()
    if tuple(bpy.app.version[:2]) < (4, 5):
        pytest.skip("bpy 4.2's EEVEE is not tested here (docs/blender-render-tests.md, EEVEE edge)")
    from eevee_scene import render_eevee

    from blender_addon import live

    version = "{}.{}".format(*bpy.app.version[:2])
    table = spectral_skin.shader_table(method="burley", blender=version, engine="eevee")
    group = live.build_group(table)
    assert sum(n.type == "TEX_IMAGE" and n.interpolation == "Closest" for n in group.nodes) == 16
    set_world(scene, 0.0)
    add_top_camera(scene, ortho_scale=0.5, width=4, height=4)
    plane = add_plane("Plane", -1.0, 1.0, -1.0, 1.0, 0.0)
    mat = bpy.data.materials.new("Live")
    if mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emission = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(emission.outputs["Emission"], out.inputs["Surface"])
    node = nt.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    assign(plane, mat)
    # Points where the lookup is steep (low concentrations): the random ones that missed most with GPU filtering.
    points = [(0.0572, 0.0539, 0.0192), (0.161, 0.8079, 0.0258), (0.005, 0.7, 0.005), (0.1998, 0.6524, 0.0117)]
    for c_m, beta, c_h in points:
        for socket, value in zip(live.INPUTS, (c_m, beta, c_h, 0.0), strict=True):
            node.inputs[socket].default_value = value
        for output, key in (("Base Color", "base_color_log"), ("Subsurface Radius", "radius_log")):
            nt.links.new(node.outputs[output], emission.inputs["Color"])
            got = render_eevee(scene, 1).reshape(-1, 3)[0]
            expected = _emulated(table, key, c_m, beta, c_h)
            print(f"\n[live-group/eevee] {output} at {(c_m, beta, c_h)}: rel. err "
                  f"{np.array2string((got / expected - 1) * 100, precision=3)} %")
            np.testing.assert_allclose(got, expected, rtol=2e-3, err_msg=f"{output} at {(c_m, beta, c_h)}")
