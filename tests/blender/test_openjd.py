"""The Open Job Description template farm/spectral_skin_render.openjd.yaml run by ``openjd run`` (openjd-cli, as a
Deadline Cloud worker runs a job) on a tiny scene: haemoglobin keyed on a Baked skin, two frames, 32 x 32 px. The
template's "blender" is this Blender's stand-in (tests/farm/blender_cli.py: no add-on, no spectral_skin, auto-run
off); the frames it writes must equal the same frames rendered locally by scripts/tools/render_blend.py. Oldest and
newest supported Blender only.

Run: python -m pytest tests/blender/test_openjd.py -s
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
import render_blend  # noqa: E402  (scripts/tools/render_blend.py)
from farm_worker import BLENDER_CLI, REPO, only_in_edge_versions  # noqa: E402
from live_scene import apply_materials, skin_material, slab_scene  # noqa: E402

pytestmark = only_in_edge_versions(bpy.app.version)

TEMPLATE = REPO / "farm" / "spectral_skin_render.openjd.yaml"


def _openjd() -> str:
    """openjd from the project's .venv (scripts/pins/requirements-dev.txt), else a .venv-openjd, else PATH."""
    for candidate in (REPO / ".venv" / "bin" / "openjd", REPO / ".venv-openjd" / "bin" / "openjd"):
        if candidate.exists():
            return str(candidate)
    found = shutil.which("openjd")
    if found is None:
        pytest.skip("openjd not installed: bash scripts/setup-python.sh --test (scripts/pins/requirements-dev.txt)")
    return found


def test_openjd_run_renders_the_frames_of_a_local_render(addon, tmp_path):
    scene = blender_scenes.reset_scene()
    material = skin_material("Skin", "BAKED", melanin=0.005)
    slab_scene(material)
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.frame_start, scene.frame_end = 1, 2
    scene.cycles.samples = 16
    for frame, value in ((1, 0.005), (2, 0.05)):
        material.spectral_skin.hemoglobin = value
        material.keyframe_insert("spectral_skin.hemoglobin", frame=frame)
    scene.frame_set(1)
    apply_materials(scene, material)
    blend = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    local = render_blend.render_frames(str(blend), str(tmp_path / "local"), frames=[1, 2])
    # The worker's "blender": this Blender's stand-in, in an isolated Python.
    blender = tmp_path / "blender"
    blender.write_text(f"#!/bin/sh\nexec {sys.executable} -I {BLENDER_CLI} \"$@\"\n")
    blender.chmod(blender.stat().st_mode | stat.S_IEXEC)
    out = tmp_path / "farm"
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONSTARTUP"}}
    proc = subprocess.run([_openjd(), "run", str(TEMPLATE), "-p", f"BlendFile={blend}", "-p", f"OutputDir={out}",
                           "-p", "Frames=1-2", "-p", f"Blender={blender}"], capture_output=True, text=True,
                          timeout=600, env=env, cwd=str(tmp_path))
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    written = sorted(p.name for p in out.iterdir())
    assert written == ["frame_0001.exr", "frame_0002.exr"], (written, proc.stdout[-3000:])
    frames = [blender_scenes.read_exr(str(out / name))[:, :, :3] for name in written]
    references = [blender_scenes.read_exr(path)[:, :, :3] for path in local]
    for frame, (got, reference) in enumerate(zip(frames, references, strict=True), start=1):
        diff = float(np.abs(got - reference).max())
        print(f"\n[openjd] Blender {bpy.app.version_string} frame {frame}: max |openjd - local| = {diff:.3g}, "
              f"mean {reference.mean():.4f}")
        assert got.shape == (32, 32, 3) and diff <= 1e-6
    assert float(np.abs(frames[1] - frames[0]).mean()) > 0.01  # the keyed frames differ
