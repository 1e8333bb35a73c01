"""The add-on's transport in Blender (issue 20): the Advanced sub-panel's Transport menu from the core's
``transports()``, Apply and the albedo swatch with either transport against evaluate(), the batch flag and sidecar.

Headless, no rendering. Run: .venv-blender/5.0/bin/python -m pytest tests/blender/test_addon_transport.py
"""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

bpy = pytest.importorskip("bpy")

import numpy as np  # noqa: E402
import spectral_skin  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]


from blender_addon import nodes as addon_nodes  # noqa: E402

CATALOG = spectral_skin.transports()
DEFAULT = next(t["name"] for t in CATALOG if t["default"])


def _principled(material):
    found = addon_nodes.tagged_nodes(material.node_tree, "principled")
    assert len(found) == 1, [n.name for n in material.node_tree.nodes]
    return found[0]


def test_transport_menu_is_the_cores(addon, draw_panel):
    rna = bpy.types.Material.bl_rna.properties["spectral_skin"].fixed_type.bl_rna.properties["transport"]
    items = [(i.identifier, i.description) for i in rna.enum_items]
    assert items == [(t["name"].upper(), t["description"]) for t in CATALOG]
    assert rna.default == DEFAULT.upper()
    assert bpy.data.materials.new("Skin").spectral_skin.transport == DEFAULT.upper()
    material = bpy.data.materials.new("Skin")
    context = type("Context", (), {"material": material})()
    assert "transport" in draw_panel(bpy.types.SPECTRAL_SKIN_PT_advanced, context)


@pytest.mark.parametrize("transport", [t["name"] for t in CATALOG])
def test_apply_and_swatch_follow_the_transport(addon, transport):
    bpy.context.scene.render.engine = "CYCLES"
    material = bpy.data.materials.new("Skin")
    props = material.spectral_skin
    props.preset = "AFRICAN"
    props.method = "RANDOM_WALK"
    props.transport = transport.upper()
    expected = spectral_skin.evaluate(preset="african", blender=bpy.app.version, transport=transport)
    space = addon_nodes.scene_working_space()
    swatch = spectral_skin.evaluate(preset="african", outputs=["albedo"], working_space=space, transport=transport)
    np.testing.assert_allclose(props.swatch, swatch["diffuse_reflectance_rgb"], rtol=1e-5)
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    method = expected["methods"]["random_walk"]
    np.testing.assert_allclose(_principled(material).inputs["Base Color"].default_value[:3], method["base_color"],
                               rtol=1e-6)
    np.testing.assert_allclose(props.result_radius_mm, method["subsurface_radius_mm"], rtol=1e-6)


def test_batch_flag_and_sidecar_carry_the_transport(tmp_path):
    blend = tmp_path / "in.blend"
    script = ("import bpy; bpy.ops.wm.read_factory_settings(use_empty=True); "
              "bpy.data.materials.new('Skin').use_fake_user = True; bpy.context.scene.render.engine = 'CYCLES'; "
              f"bpy.ops.wm.save_as_mainfile(filepath={str(blend)!r})")
    subprocess.run([sys.executable, "-c", script], check=True, capture_output=True)
    help_text = subprocess.run([sys.executable, str(REPO / "blender_addon" / "batch.py"), "apply", "--help"],
                               capture_output=True, text=True).stdout
    assert all(t["name"].upper() in help_text for t in CATALOG), help_text
    out = tmp_path / "out.blend"
    run = subprocess.run([sys.executable, str(REPO / "blender_addon" / "batch.py"), "apply", str(blend), str(out),
                          "--material", "Skin", "--preset", "african", "--transport", "DIFFUSION"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    sidecar = json.loads((tmp_path / "out.spectral_skin.json").read_text())
    assert sidecar["Skin"]["transport"] == "diffusion"
    check = (f"import bpy, json; bpy.ops.wm.open_mainfile(filepath={str(out)!r}); m = bpy.data.materials['Skin']; "
             "n = [n for n in m.node_tree.nodes if n.get('spectral_skin') == 'principled'][0]; "
             "print(json.dumps(list(n.inputs['Base Color'].default_value[:3])))")
    base_color = json.loads(subprocess.run([sys.executable, "-c", check], check=True, capture_output=True,
                                           text=True).stdout.strip().splitlines()[-1])
    expected = spectral_skin.evaluate(preset="african", blender=bpy.app.version, transport="diffusion")
    np.testing.assert_allclose(base_color, expected["methods"]["burley"]["base_color"], rtol=1e-6)
    bad = subprocess.run([sys.executable, str(REPO / "blender_addon" / "batch.py"), "apply", str(blend), str(out),
                          "--material", "Skin", "--transport", "MONTE_CARLO"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--transport" in bad.stderr and "DIFFUSION" in bad.stderr, bad.stderr
