"""The Flamenco job type's re-apply task run for real: the job compiled under Node (farm/spectral_skin_render.js
against tests/farm/flamenco_api.js), its ``spectral-skin-apply`` command executed as a worker with the extension
installed runs it (the add-on loaded as Blender loads an extension, ``bl_ext.user_default.spectral_skin``, and
enabled; the .blend opened; the command's ``--python-expr`` run with the arguments after ``--``), then the re-applied
copy rendered by the render task's plain worker. The copy's skin is the overrides' (the core's Base Color for them,
computed here), the source file is untouched. Oldest and newest supported Blender only.

Run: python -m pytest tests/blender/test_flamenco_apply.py -s
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from farm_worker import REPO, only_in_edge_versions, worker_render  # noqa: E402
from live_scene import apply_materials, skin_material, slab_scene  # noqa: E402

from blender_addon import nodes as addon_nodes  # noqa: E402

pytestmark = only_in_edge_versions(bpy.app.version)

# A worker's Blender with the extension installed and enabled: the add-on under its extension module name, registered;
# then Blender's own order: open the .blend, run --python-expr with sys.argv as Blender leaves it.
EXTENSION_WORKER = textwrap.dedent("""
    import importlib.util, json, sys, types
    repo, blendfile, args = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    import bpy
    for name in ("bl_ext", "bl_ext.user_default"):
        sys.modules[name] = types.ModuleType(name)
        sys.modules[name].__path__ = []
    name = "bl_ext.user_default.spectral_skin"
    spec = importlib.util.spec_from_file_location(name, repo + "/blender_addon/__init__.py",
                                                  submodule_search_locations=[repo + "/blender_addon"])
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    module.register()
    bpy.ops.wm.open_mainfile(filepath=blendfile)
    expr = args[args.index("--python-expr") + 1]
    sys.argv = ["blender", "-b", blendfile, *args]
    exec(compile(expr, "<python-expr>", "exec"), {})
""")


def _compile(job: dict) -> list[dict]:
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None:
        pytest.fail("node not found: bash scripts/setup-python.sh --test installs Debian's nodejs")
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as handle:
        json.dump(job, handle)
        path = handle.name
    try:
        proc = subprocess.run([node, str(REPO / "tests" / "farm" / "flamenco_api.js"),
                               str(REPO / "farm" / "spectral_skin_render.js"), path], capture_output=True, text=True,
                              timeout=60)
    finally:
        os.unlink(path)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)["tasks"]


def test_reapply_task_applies_the_overrides_and_the_render_task_renders_them(addon, tmp_path):
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "BAKED", melanin=0.005)
    slab_scene(material)
    scene.render.resolution_x = scene.render.resolution_y = 16
    scene.cycles.samples = 16
    apply_materials(scene, material)
    blend = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    before = blend.read_bytes()
    tasks = _compile({"name": "shot", "settings": {
        "frames": "1", "chunk_size": 1, "reapply": True, "reapply_materials": "Skin",
        "reapply_overrides": "--preset asian --hemoglobin 0.02 --oiliness 0", "render_output_root": str(tmp_path),
        "render_output_path": str(tmp_path / "out" / "######"), "blendfile": str(blend), "format": "OPEN_EXR"}})
    apply, render = tasks
    assert apply["name"] == "spectral-skin-apply" and render["dependencies"] == ["spectral-skin-apply"]
    params = apply["commands"][0]["parameters"]
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONSTARTUP"}}
    proc = subprocess.run([sys.executable, "-c", EXTENSION_WORKER, str(REPO), params["blendfile"],
                           json.dumps(params["args"])], capture_output=True, text=True, timeout=600, env=env,
                          cwd=str(tmp_path))
    assert proc.returncode == 0, proc.stderr[-3000:] + proc.stdout[-2000:]
    applied = tmp_path / "shot.spectral-skin.blend"
    assert render["commands"][0]["parameters"]["blendfile"] == str(applied) and applied.exists()
    assert blend.read_bytes() == before  # the source .blend is not touched
    # The copy's skin: the core's Burley Base Color for the asian preset with haemoglobin 0.02 (computed here).
    bpy.ops.wm.open_mainfile(filepath=str(applied))
    principled = addon_nodes.tagged_nodes(bpy.data.materials["Skin"].node_tree, "principled")[0]
    preset = spectral_skin.presets()["asian"]
    expected = spectral_skin.evaluate(preset["melanin"], preset["melanin_blend"], 0.02, 0.0,
                                      blender=tuple(bpy.app.version))["methods"]["burley"]
    np.testing.assert_allclose(principled.inputs["Base Color"].default_value[:3], expected["base_color"], rtol=1e-5)
    # The render task's command on a plain worker renders the copy.
    frames = worker_render(applied, tmp_path / "out", "1")
    assert list(frames) == [1] and frames[1].shape == (16, 16, 3)
    print(f"\n[flamenco] Blender {bpy.app.version_string}: re-applied Base Color "
          f"{np.array2string(np.asarray(principled.inputs['Base Color'].default_value[:3]), precision=4)}, "
          f"core {np.array2string(np.asarray(expected['base_color']), precision=4)}; rendered mean "
          f"{frames[1].mean():.4f}")
