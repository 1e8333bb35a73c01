"""Farm-ready: a .blend set up by the add-on renders the same on a machine without it (and without spectral_skin).

The add-on's output is plain Blender data (a Principled BSDF, image textures saved next to the .blend or packed into
it), so a render node needs only Blender. These tests save such a .blend, render it in a fresh process that cannot
import spectral_skin nor the add-on, and compare with the render made where the add-on is registered. Also: the
packed .blend after its texture folder is deleted, the headless render script ``scripts/tools/render_blend.py`` (not
part of the extension; run without spectral_skin), and "nothing lost" when a parameter map cannot be read. Small
renders (64x64, 32 spp, fixed seed).

Run: .venv/bin/python -m pytest tests/blender/test_farm.py -s   (-s shows the 2048² apply timing)
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap
import time

import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")

import numpy as np  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]

import render_blend  # noqa: E402  (scripts/tools/render_blend.py)
from blender_scenes import (  # noqa: E402
    add_slab,
    add_sun,
    add_top_camera,
    assign,
    material_snapshot,
    new_material,
    read_exr,
    reset_scene,
    set_world,
)

from blender_addon import batch  # noqa: E402
from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.core import ParameterMap, SkinSettings  # noqa: E402

BATCH = REPO / "blender_addon" / "batch.py"
RENDER = REPO / "scripts" / "tools" / "render_blend.py"
# scripts/tools/render_blend.py as a render node runs it: an isolated Python (-I) where importing spectral_skin fails.
RENDER_NODE = ("import runpy, sys; sys.modules['spectral_skin'] = None; sys.argv = sys.argv[1:]; "
               "runpy.run_path(sys.argv[0], run_name='__main__')")
SIZE = 64
SAMPLES = 32
SEED = 7

# 4x4 melanin map (float: the values are C_m itself), row 0 at the top; strong contrast so the texture shows.
MELANIN = np.array([[0.01, 0.05, 0.10, 0.20],
                    [0.02, 0.08, 0.15, 0.30],
                    [0.03, 0.12, 0.25, 0.40],
                    [0.005, 0.04, 0.18, 0.45]], dtype=np.float32)

# A render node: no add-on, no spectral_skin (importing it fails), just bpy; renders the .blend as saved.
FARM_SCRIPT = textwrap.dedent("""
    import importlib.util, json, sys
    sys.modules["spectral_skin"] = None  # any `import spectral_skin` now raises ImportError
    import bpy
    blend, out = sys.argv[1], sys.argv[2]
    assert importlib.util.find_spec("blender_addon") is None, "the add-on is importable on the render node"
    bpy.ops.wm.open_mainfile(filepath=blend)
    assert not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply"), "the add-on is registered on the render node"
    scene = bpy.context.scene
    scene.render.filepath = out
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    images = {i.name: {"filepath": i.filepath, "packed": i.packed_file is not None, "size": list(i.size)}
              for i in bpy.data.images if i.source == "FILE"}
    print("FARM " + json.dumps({"images": images,
                                "spectral_skin_loaded": sys.modules.get("spectral_skin") is not None,
                                "addon_loaded": any(m.startswith("blender_addon") for m in sys.modules)}))
""")


def _registered() -> bool:
    return hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply")


def _build_source(path: pathlib.Path) -> None:
    """Slab (with a UV map spanning its top face) + top camera + sun + world; material "Skin" (plain Principled);
    deterministic Cycles settings stored in the .blend; saved to ``path``."""
    scene = reset_scene()
    set_world(scene, 0.3)
    slab = add_slab(1.0, 0.2)
    mesh = slab.data
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        co = mesh.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (co.x + 0.5, co.y + 0.5)
    add_top_camera(scene, 1.0, SIZE, SIZE)
    add_sun(scene, 3.0)
    material, _ = new_material("Skin")
    assign(slab, material)
    scene.cycles.samples = SAMPLES
    scene.cycles.seed = SEED
    scene.cycles.filter_width = 1.5
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))


def _skin_blend(tmp: pathlib.Path, name: str, pack: bool) -> pathlib.Path:
    """The source scene with Spectral Skin applied from the melanin map; saved as ``tmp/name/scene.blend`` with its
    textures in ``tmp/name/skin_maps`` (relative paths) or packed."""
    source = tmp / "source" / "scene.blend"
    if not source.exists():
        _build_source(source)
    out = tmp / name / "scene.blend"
    settings = SkinSettings.from_preset(
        "asian", maps={"melanin": ParameterMap(MELANIN, normalized=False)}, output_dir=str(tmp / name / "skin_maps"))
    batch.apply_to_materials(str(source), ["Skin"], settings, str(out), pack=pack)
    assert _registered()
    return out


def _farm_render(blend: pathlib.Path, out: pathlib.Path) -> dict:
    """Render ``blend`` in a fresh isolated Python (-I: no PYTHONPATH, no cwd on sys.path) without the add-on."""
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONSTARTUP"}}
    proc = subprocess.run([sys.executable, "-I", "-c", FARM_SCRIPT, str(blend), str(out)], cwd=str(out.parent),
                          env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:] + proc.stdout[-2000:]
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("FARM ")][-1]
    info = json.loads(line[5:])
    assert not info["spectral_skin_loaded"] and not info["addon_loaded"], info
    return info


def _rgb(path) -> np.ndarray:
    img = read_exr(str(path))
    assert img.shape[:2] == (SIZE, SIZE), img.shape
    return img[:, :, :3]


def test_render_on_farm_node_without_addon_matches(addon, tmp_path):
    blend = _skin_blend(tmp_path, "job", pack=False)
    assert sorted(p.name for p in (tmp_path / "job" / "skin_maps").iterdir()) == ["scene_Skin_albedo.exr",
                                                                                   "scene_Skin_radius.exr"]
    # Reference: rendered here, with the add-on registered (render_frames reopens the saved file).
    [reference_path] = render_blend.render_frames(str(blend), str(tmp_path / "ref"), frames=[1])
    assert _registered()
    reference = _rgb(reference_path)
    # The job folder is copied elsewhere, as onto a render node: the relative texture paths must follow.
    node_dir = tmp_path / "node" / "job"
    shutil.copytree(tmp_path / "job", node_dir)
    shutil.rmtree(tmp_path / "job")
    info = _farm_render(node_dir / "scene.blend", tmp_path / "node" / "frame.exr")
    assert {v["filepath"] for v in info["images"].values()} == {"//skin_maps/scene_Skin_albedo.exr",
                                                                "//skin_maps/scene_Skin_radius.exr"}
    assert all(v["size"] == [4, 4] and not v["packed"] for v in info["images"].values()), info
    farm = _rgb(tmp_path / "node" / "frame.exr")
    # The texture shows (columns of the melanin map differ) and is not Blender's magenta "missing texture".
    assert np.all(np.isfinite(reference)) and reference.mean() > 0.01
    left, right = reference[:, : SIZE // 4].mean(), reference[:, -SIZE // 4:].mean()
    assert left > 1.5 * right, (left, right)
    diff = float(np.abs(farm - reference).max())
    print(f"\nfarm-ready: max |farm - reference| = {diff:.3g} over {SIZE}x{SIZE} px, mean {reference.mean():.4f}")
    assert diff <= 1e-6
    assert np.array_equal(farm, reference)  # same seed: bit-identical


def test_packed_blend_renders_after_texture_folder_deleted(addon, tmp_path):
    reference_blend = _skin_blend(tmp_path, "plain", pack=False)
    [reference_path] = render_blend.render_frames(str(reference_blend), str(tmp_path / "ref"))
    packed = _skin_blend(tmp_path, "packed", pack=True)
    shutil.rmtree(tmp_path / "packed" / "skin_maps")
    info = _farm_render(packed, tmp_path / "packed_frame.exr")
    assert len(info["images"]) == 2 and all(v["packed"] and v["size"] == [4, 4] for v in info["images"].values())
    assert np.array_equal(_rgb(tmp_path / "packed_frame.exr"), _rgb(reference_path))
    # The unpacked .blend without its texture folder: a clear error before rendering, not a magenta frame.
    shutil.rmtree(tmp_path / "plain" / "skin_maps")
    with pytest.raises(FileNotFoundError, match="scene_Skin_albedo.exr"):
        render_blend.render_frames(str(reference_blend), str(tmp_path / "ref2"))
    assert not (tmp_path / "ref2").exists()


def _run_batch(*args: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(BATCH), *args], cwd=str(cwd), capture_output=True, text=True,
                          timeout=300)


def _run_render(*args: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONSTARTUP"}}
    return subprocess.run([sys.executable, "-I", "-c", RENDER_NODE, str(RENDER), *args], cwd=str(cwd), env=env,
                          capture_output=True, text=True, timeout=300)


def test_render_script_cli(addon, tmp_path):
    blend = _skin_blend(tmp_path, "job", pack=True)
    [reference] = render_blend.render_frames(str(blend), str(tmp_path / "ref"), frames=[2], samples=8,
                                             resolution=(32, 24), seed=3)
    proc = _run_render(str(blend), "--out", str(tmp_path / "out"), "--frames", "1-2", "--samples", "8",
                       "--resolution", "32x24", "--seed", "3", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    paths = proc.stdout.split()[-2:]
    assert [os.path.basename(p) for p in paths] == ["scene_0001.exr", "scene_0002.exr"]
    image = read_exr(paths[1])
    assert image.shape[:2] == (24, 32)
    assert np.array_equal(image, read_exr(reference))
    proc = _run_render(str(blend), "--out", str(tmp_path / "png"), "--format", "png", "--samples", "4",
                       "--resolution", "16x16", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert os.path.basename(proc.stdout.split()[-1]) == "scene_0001.png"
    # Errors: one clear line, exit status 2.
    for args, message in [((str(tmp_path / "nope.blend"), "--out", str(tmp_path / "x")), "no such .blend"),
                          ((str(blend), "--out", str(tmp_path / "x"), "--frames", "3-1"), "ends before"),
                          ((str(blend), "--out", str(tmp_path / "x"), "--frames", "a"), "frames must"),
                          ((str(blend), "--out", str(tmp_path / "x"), "--resolution", "12"), "resolution")]:
        proc = _run_render(*args, cwd=tmp_path)
        assert proc.returncode == 2, (args, proc.stderr)
        assert proc.stderr.startswith("render_blend:") and message in proc.stderr, proc.stderr
    # The add-on's batch.py no longer renders: it names the script.
    proc = _run_batch("render", str(blend), "--out", str(tmp_path / "x"), cwd=tmp_path)
    assert proc.returncode == 2 and "scripts/tools/render_blend.py" in proc.stderr, proc.stderr


def test_unreadable_map_changes_nothing(addon, tmp_path):
    """A parameter map whose file is missing or corrupt: the operator reports an error, the batch command exits 2;
    the material is unchanged and no file is written in the texture folder."""
    material = bpy.data.materials.new("Skin")
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    before = material_snapshot(material)
    maps_dir = tmp_path / "skin_maps"
    # An image whose file is gone (e.g. a .blend moved without its maps).
    source = tmp_path / "melanin.exr"
    from blender_scenes import write_exr

    write_exr(str(source), np.repeat(MELANIN[:, :, None], 3, axis=2))
    image = bpy.data.images.load(str(source))
    source.unlink()
    image.reload()
    props = material.spectral_skin
    props.melanin_map = image
    props.output_dir = str(maps_dir)
    with pytest.raises(RuntimeError, match=r"melanin\.exr: cannot read melanin map"):
        bpy.ops.spectral_skin.apply(material="Skin")
    assert material_snapshot(material) == before
    assert not maps_dir.exists() or list(maps_dir.iterdir()) == []
    # A corrupt file.
    corrupt = tmp_path / "corrupt.exr"
    corrupt.write_bytes(b"v/1\x01" + b"\x00garbage" * 50)
    try:
        image = bpy.data.images.load(str(corrupt))
    except RuntimeError:
        image = None  # Blender refuses to load it at all: nothing can be selected as a map
    if image is not None:
        props.melanin_map = image
        with pytest.raises(RuntimeError, match="Spectral Skin"):
            bpy.ops.spectral_skin.apply(material="Skin")
        assert material_snapshot(material) == before
        assert not maps_dir.exists() or list(maps_dir.iterdir()) == []

    # The batch command: missing and corrupt map files.
    props.melanin_map = None
    blend = tmp_path / "in.blend"
    material.use_fake_user = True
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    for bad in (tmp_path / "missing.exr", corrupt):
        proc = _run_batch("apply", str(blend), str(tmp_path / "out.blend"), "--material", "Skin",
                          "--melanin-map", str(bad), "--out-dir", str(maps_dir), cwd=tmp_path)
        assert proc.returncode == 2, proc.stderr[-3000:]
        # Blender 4.2/4.5 print their own "Cannot read image file" line first: the add-on's message is a line of its own.
        ours = [line for line in proc.stderr.splitlines() if line.startswith("spectral-skin batch: ")]
        assert ours, proc.stderr
        assert "melanin map" in proc.stderr and str(bad) in proc.stderr, proc.stderr
        assert not (tmp_path / "out.blend").exists()
        assert not maps_dir.exists() or list(maps_dir.iterdir()) == []
    # The old form (no subcommand) still works.
    proc = _run_batch(str(blend), str(tmp_path / "out.blend"), "--material", "Skin", "--preset", "african",
                      cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "out.blend").exists()


def test_apply_2048_map_timing(addon, tmp_path):
    """Apply Spectral Skin through the operator from 2048x2048 float images for melanin and haemoglobin (prints
    the time: image read + core maps + EXR write + Blender image reload)."""
    n = 2048
    material = bpy.data.materials.new("Skin")
    rng = np.random.default_rng(1)
    props = material.spectral_skin
    for name, low, high in (("melanin", 0.002, 0.4), ("hemoglobin", 0.001, 0.08)):
        image = bpy.data.images.new(f"{name}_2k", n, n, float_buffer=True)
        value = rng.uniform(low, high, size=(n, n)).astype(np.float32)
        rgba = np.repeat(value[:, :, None], 4, axis=2)
        rgba[:, :, 3] = 1.0
        image.pixels.foreach_set(rgba.ravel())
        setattr(props, f"{name}_map", image)
    props.output_dir = str(tmp_path / "maps")
    start = time.perf_counter()
    assert bpy.ops.spectral_skin.apply(material="Skin") == {"FINISHED"}
    seconds = time.perf_counter() - start
    albedo = addon_nodes.tagged_nodes(material.node_tree, "albedo")[0]
    assert tuple(albedo.image.size) == (n, n)
    print(f"\napply 2048x2048 melanin + haemoglobin maps via bpy.ops.spectral_skin.apply: {seconds:.2f} s "
          f"(core: {props.result_seconds:.2f} s, {props.result_computed})")
    assert seconds < 120


def test_render_script_takes_the_engine_apply_computed_for(addon, tmp_path):
    """A .blend whose scene engine was changed after Apply: render_blend.py renders with the engine the skin was
    computed for (stored on the material by Apply), says so on stderr, and warns when told to render another."""
    blend = _skin_blend(tmp_path, "job", pack=True)
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    bpy.context.scene.render.engine = "BLENDER_WORKBENCH"
    bpy.ops.wm.save_mainfile()
    args = ("--out", str(tmp_path / "out"), "--samples", "1", "--resolution", "8x8")
    proc = _run_render(str(blend), *args, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "render_blend: rendering with CYCLES, the engine Apply computed the skin materials for" in proc.stderr
    assert "warning" not in proc.stderr, proc.stderr
    proc = _run_render(str(blend), *args, "--engine", "BLENDER_WORKBENCH", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "rendering with BLENDER_WORKBENCH, as asked (--engine); warning: Skin was computed for CYCLES" in proc.stderr
