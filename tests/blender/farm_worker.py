"""Helpers of the farm tests: which Blender versions run them (the oldest and the newest supported) and a render on
a plain worker: a separate process of this Blender with no add-on, no ``spectral_skin``, no project script on its
path, Python auto-run off (tests/farm/blender_cli.py: Blender's command line over bpy)."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from blender_scenes import read_exr

REPO = pathlib.Path(__file__).resolve().parents[2]
BLENDER_CLI = REPO / "tests" / "farm" / "blender_cli.py"
PINS = REPO / "scripts" / "pins" / "blender-versions.txt"


def edge_versions() -> tuple[tuple[int, int], tuple[int, int]]:
    """The oldest and the newest Blender of scripts/pins/blender-versions.txt, as (major, minor)."""
    rows = [line.split()[0] for line in PINS.read_text().splitlines() if line.strip() and not line.startswith("#")]
    versions = sorted(tuple(int(p) for p in v.split(".")) for v in rows)
    return versions[0], versions[-1]  # type: ignore[return-value]


def is_edge_version(version: tuple[int, ...]) -> bool:
    return tuple(version[:2]) in edge_versions()


def only_in_edge_versions(version: tuple[int, ...]) -> pytest.MarkDecorator:
    """The module mark of a farm test: skipped in every Blender but the oldest and the newest supported."""
    return pytest.mark.skipif(not is_edge_version(version),
                              reason=f"farm tests run in the oldest and newest Blender {edge_versions()}")


def worker_render(blend: pathlib.Path, out_dir: pathlib.Path, frames: str, *extra: str) -> dict[int, np.ndarray]:
    """Render ``frames`` ("1..2") of ``blend`` as a plain render node does (``blender -b FILE -o OUT -f FRAMES``);
    returns {frame: RGB float64}."""
    out_dir.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k not in {"PYTHONPATH", "PYTHONSTARTUP"}}
    proc = subprocess.run([sys.executable, "-I", str(BLENDER_CLI), "-b", str(blend), *extra, "-o",
                           str(out_dir / "frame_####"), "-f", frames], cwd=str(out_dir), env=env,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:] + proc.stdout[-2000:]
    assert "auto-run is off" not in proc.stderr, proc.stderr  # nothing in the .blend needed Python to run
    images = {}
    for path in sorted(out_dir.glob("frame_*.exr")):
        images[int(path.stem.split("_")[1])] = read_exr(str(path))[:, :, :3].astype(np.float64)
    return images
