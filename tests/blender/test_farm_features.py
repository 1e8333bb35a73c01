"""The farm test: every feature of the add-on applied, saved, then rendered by a separate plain Blender process (no
add-on, no ``spectral_skin``, no project script, Python auto-run off: farm_worker.py) and compared, feature by
feature, with the same frames rendered in the session; in Cycles and in EEVEE, in the oldest and the newest supported
Blender (skipped in the others).

One scene per engine: a row of small UV-mapped slabs under a top camera, one material per feature (Baked: constants,
a parameter map, keyed haemoglobin; Live: constants, a painted map, a painted blush mask, keyed haemoglobin, a
driven haemoglobin), Apply from the panel's path, saved, frames 1 and 2 rendered here and on the worker. A feature
passes when its slab's mean colour on the worker equals the session's within the noise of the samples (3 standard
errors of the slab's pixels, at least one EEVEE colour step in EEVEE; the renders use the same seed, so they are
expected identical, and were but for a few EEVEE pixels one step apart in 4.2) at both frames; and the
animated features must change between the frames (or the comparison could not see frame 1's colour at frame 2).

Run: python -m pytest tests/blender/test_farm_features.py -s   (-s prints the per-feature figures)
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from blender_scenes import add_box, add_top_camera, assign, eevee_engine_id, set_world, write_exr  # noqa: E402
from farm_worker import only_in_edge_versions, worker_render  # noqa: E402

from blender_addon import masks  # noqa: E402
from blender_addon.apply import apply_skins  # noqa: E402
from blender_addon.props import settings_from_material  # noqa: E402

pytestmark = only_in_edge_versions(bpy.app.version)

FEATURES = ("baked constants", "baked parameter map", "baked keys", "live constants", "live painted map",
            "live mask", "live keys", "live driver")
ANIMATED = {"baked keys", "live keys", "live driver"}
SLAB_M, GAP_M, PX_PER_SLAB, MARGIN_PX = 0.05, 0.01, 16, 3
SAMPLES = {"CYCLES": 16, "EEVEE": 4}
# Below the samples' noise: float precision in Cycles (the same seed renders the same image); one colour step in EEVEE,
# where Blender 4.2 rendered a few pixels one step apart between two processes (max 0.0029, means 1e-4).
FLOOR = {"CYCLES": 1e-6, "EEVEE": 1.0 / 1024}
MELANIN_MAP = np.array([[0.01, 0.05, 0.10, 0.20],
                        [0.02, 0.08, 0.15, 0.30],
                        [0.03, 0.12, 0.25, 0.40],
                        [0.005, 0.04, 0.18, 0.45]], dtype=np.float32)


def _slab(index: int, name: str):
    step = SLAB_M + GAP_M
    x0 = -len(FEATURES) * step / 2 + GAP_M / 2 + index * step
    obj = add_box(name, x0, x0 + SLAB_M, -SLAB_M / 2, SLAB_M / 2, -0.02, 0.0)
    mesh = obj.data
    uv = mesh.uv_layers.new(name="UVMap")
    for loop in mesh.loops:
        x, y, _ = mesh.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = ((x - x0) / SLAB_M, y / SLAB_M + 0.5)
    return obj


def _material(feature: str, tmp: pathlib.Path):
    material = bpy.data.materials.new(feature.title())
    props = material.spectral_skin
    props.mode = "LIVE" if feature.startswith("live") else "BAKED"
    props.preset = "ASIAN" if "constants" in feature else "CAUCASIAN"
    props.override_subsurface = "ON"
    if feature == "baked parameter map":
        path = tmp / "melanin.exr"
        write_exr(str(path), MELANIN_MAP[:, :, None])  # one channel: the melanin fraction itself
        props.melanin_map = bpy.data.images.load(str(path))
        props.output_dir = str(tmp / "skin_maps")
    elif feature == "live painted map":
        image = bpy.data.images.new("painted melanin", 8, 8, alpha=False, float_buffer=False)
        ramp = np.linspace(0.0, 0.6, 8, dtype=np.float32)  # 8-bit: 0..1 onto the melanin range
        rgba = np.ones((8, 8, 4), dtype=np.float32)
        rgba[:, :, :3] = ramp[None, :, None]
        image.pixels.foreach_set(rgba.ravel())  # painted, not saved: Apply packs it
        image.update()
        props.melanin_map = image
    elif feature.endswith("keys"):
        for frame, value in ((1, 0.005), (2, 0.05)):
            props.hemoglobin = value
            material.keyframe_insert("spectral_skin.hemoglobin", frame=frame)
    elif feature == "live driver":
        curve = material.driver_add("spectral_skin.hemoglobin")
        driver = curve.driver
        driver.type = "SCRIPTED"
        variable = driver.variables.new()
        variable.name, variable.type = "frame", "SINGLE_PROP"
        variable.targets[0].id_type = "SCENE"
        variable.targets[0].id = bpy.context.scene
        variable.targets[0].data_path = "frame_current"
        driver.expression = "0.03 * frame - 0.025"  # a simple expression: evaluated without Python
    return material


def _paint_mask(material) -> None:
    assert bpy.ops.spectral_skin.add_blush_mask(material=material.name) == {"FINISHED"}
    (mask,) = masks.mask_nodes(material.node_tree, "hemoglobin")
    mask.inputs["Strength"].default_value = 0.04
    link = mask.inputs["Mask"].links[0]
    image = link.from_node.inputs["Color"].links[0].from_node.image
    w, h = image.size
    rgba = np.zeros((h, w, 4), dtype=np.float32)
    rgba[..., 3] = 1.0
    rgba[:, : w // 2, :3] = 1.0
    image.pixels.foreach_set(rgba.ravel())  # painted, not packed again: Apply packs it
    image.update()


def _build(engine: str, tmp: pathlib.Path) -> tuple[pathlib.Path, list]:
    scene = blender_scenes.reset_scene()
    set_world(scene, 1.0)
    blender_scenes.add_sun(scene, 2.0, angle=0.3)
    width = len(FEATURES) * PX_PER_SLAB
    add_top_camera(scene, len(FEATURES) * (SLAB_M + GAP_M), width, PX_PER_SLAB)
    scene.frame_start, scene.frame_end = 1, 2
    scene.cycles.samples = SAMPLES["CYCLES"]
    scene.cycles.seed = 5
    if engine == "EEVEE":
        scene.render.engine = eevee_engine_id()
        scene.eevee.taa_render_samples = SAMPLES["EEVEE"]
    blend = tmp / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))  # saved first: the textures get paths relative to it
    scene = bpy.context.scene
    materials = []
    for index, feature in enumerate(FEATURES):
        material = _material(feature, tmp)
        assign(_slab(index, feature.replace(" ", "_")), material)
        materials.append(material)
    scene.frame_set(1)
    apply_skins([(m, settings_from_material(m, scene)) for m in materials], scene)
    _paint_mask(materials[FEATURES.index("live mask")])
    mask_material = materials[FEATURES.index("live mask")]
    apply_skins([(mask_material, settings_from_material(mask_material, scene))], scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    return blend, materials


def _session(blend: pathlib.Path, out: pathlib.Path) -> dict[int, np.ndarray]:
    """Frames 1 and 2 rendered in this session, with the add-on registered, from the saved file."""
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    scene = bpy.context.scene
    out.mkdir(parents=True, exist_ok=True)
    images = {}
    for frame in (1, 2):
        scene.frame_set(frame)
        scene.render.filepath = str(out / f"frame_{frame:04d}.exr")
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)
        images[frame] = blender_scenes.read_exr(scene.render.filepath)[:, :, :3].astype(np.float64)
    return images


def _region(image: np.ndarray, index: int) -> np.ndarray:
    lo = index * PX_PER_SLAB + MARGIN_PX
    return image[MARGIN_PX:PX_PER_SLAB - MARGIN_PX, lo:lo + PX_PER_SLAB - 2 * MARGIN_PX].reshape(-1, 3)


@pytest.mark.parametrize("engine", ["CYCLES", "EEVEE"])
def test_every_feature_renders_on_a_plain_worker_as_in_the_session(addon, tmp_path, engine):
    blend, _ = _build(engine, tmp_path)
    session = _session(blend, tmp_path / "session")
    worker = worker_render(blend, tmp_path / "worker", "1..2")
    assert sorted(worker) == [1, 2]
    failures = []
    for index, feature in enumerate(FEATURES):
        means = {}
        for frame in (1, 2):
            here, there = _region(session[frame], index), _region(worker[frame], index)
            mean_here, mean_there = here.mean(axis=0), there.mean(axis=0)
            noise = here.std(axis=0) / np.sqrt(len(here))
            rel = mean_there / mean_here - 1.0
            ok = bool(np.all(np.abs(mean_there - mean_here) <= 3 * noise + FLOOR[engine]))
            print(f"\n[farm] Blender {bpy.app.version_string} {engine} {feature} frame {frame}: session "
                  f"{np.array2string(mean_here, precision=4)} worker {np.array2string(mean_there, precision=4)} "
                  f"worker/session - 1 = {np.array2string(rel * 100, precision=3)} % (3 s.e. "
                  f"{np.array2string(300 * noise / mean_here, precision=2)} %), max |px diff| "
                  f"{float(np.abs(there - here).max()):.2g}")
            if not ok:
                failures.append(f"{feature} frame {frame}: {rel * 100} %")
            means[frame] = mean_here
        change = float(np.abs(means[2] / means[1] - 1.0).max())
        if feature in ANIMATED and change < 0.05:
            failures.append(f"{feature}: frames 1 and 2 differ by only {change * 100:.2f} % in the session")
        if feature not in ANIMATED and change > 1e-6 and engine == "CYCLES":
            failures.append(f"{feature}: not animated but frames 1 and 2 differ by {change * 100:.2f} %")
    assert not failures, failures
