#!/usr/bin/env python3
"""Price of Cycles render samples: per-pixel noise and region-mean error against render time, for the
Christensen-Burley and Random Walk subsurface methods at the presets' albedos, rendered through bpy.

Scene: the flat-slab albedo test of tests/blender/test_renders.py (a Principled BSDF slab, Subsurface Weight 1,
Specular IOR Level 0, under a uniform white world, seen by an orthographic top camera over 100 mm of the slab's
centre). The scene helpers are those of the render tests, scripts/lib/blender_scenes.py. Every pixel of the image lies
more than 450 mm from the slab's edges, so every pixel's expected value is the core's ``expected_albedo`` for the
method.

    .venv/bin/python scripts/reports/cycles_samples.py                      # 3 presets x 2 methods, 64x64 px, 1-1024 spp
    .venv/bin/python scripts/reports/cycles_samples.py --quick --out /tmp/cs.json   # caucasian, 32x32 px, 1-64 spp

Per render it records the wall time of the bpy.ops.render.render call alone (after a warm-up render of the same
scene, so kernel loading and the first scene sync are not counted), per channel: the relative rms pixel noise
std(pixels)/mean (the noise of one pixel), the relative error of the image mean vs the expected albedo, and the
rms over pixels of (pixel - expected)/expected. Cycles CPU, fixed seed, no adaptive sampling, no denoising (as
blender_scenes.reset_scene sets up), threads left at AUTO (the count used is recorded). Writes JSON atomically.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SCENES_DIR = ROOT / "scripts" / "lib"  # blender_scenes
DEFAULT_OUT = ROOT / "docs" / "data" / "cycles_samples.json"

METHODS: dict[str, str] = {"burley": "BURLEY", "random_walk": "RANDOM_WALK"}  # core name -> Cycles method
FULL_SAMPLES: tuple[int, ...] = (1, 4, 16, 64, 256, 1024)
QUICK_SAMPLES: tuple[int, ...] = (1, 4, 16, 64)
FULL_SIZE_PX = 64
QUICK_SIZE_PX = 32
QUICK_PRESETS: tuple[str, ...] = ("caucasian",)
ORTHO_SCALE_M = 0.1  # image width on the slab (100 mm), as the render tests' flat slab
SEED = 1
FILTER_WIDTH = 1.5  # Cycles' default pixel filter width (px), as blender_scenes.render
WARMUP_SAMPLES = 1


def load_helpers() -> ModuleType:
    """The scene helpers the render tests share (scripts/lib/blender_scenes.py, a plain module without pytest)."""
    if str(SCENES_DIR) not in sys.path:
        sys.path.insert(0, str(SCENES_DIR))
    import blender_scenes

    return blender_scenes


def setup_flat_slab(helpers: ModuleType, method: str, base_color: np.ndarray, radius_mm: np.ndarray, size_px: int):
    """A fresh deterministic scene holding the white-world flat slab with a pure-subsurface Principled material and
    an orthographic top camera of size_px x size_px over the slab's centre; returns the scene."""
    scene = helpers.reset_scene()
    helpers.set_world(scene, strength=1.0)
    slab = helpers.add_slab()
    mat, _ = helpers.principled_sss("Skin", method, base_color, radius_mm)
    helpers.assign(slab, mat)
    helpers.add_top_camera(scene, ortho_scale=ORTHO_SCALE_M, width=size_px, height=size_px)
    return scene


@contextlib.contextmanager
def quiet_stdout() -> Iterator[None]:
    """Send file descriptor 1 to /dev/null for the duration (Blender's C code prints a progress line per render
    there), so that only this script's table reaches stdout."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def timed_render(helpers: ModuleType, scene, samples: int, workdir: str) -> tuple[np.ndarray, float]:
    """Render the scene with Cycles at `samples` spp; returns (RGB float64 (H, W, 3), wall seconds of the
    bpy.ops.render.render call alone). Same settings as blender_scenes.render; the Render Result is saved to a 32-bit
    float EXR after the timed call (save_render: the same pixels as write_still) and read back with OpenImageIO."""
    import bpy

    scene.cycles.samples = samples
    scene.cycles.seed = SEED
    scene.cycles.filter_width = FILTER_WIDTH
    path = os.path.join(workdir, f"render_{samples}.exr")
    scene.render.filepath = path
    with quiet_stdout():
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=False)
        seconds = time.perf_counter() - t0
        bpy.data.images["Render Result"].save_render(path)
    img = helpers.read_exr(path)
    os.remove(path)
    if img.shape[:2] != (scene.render.resolution_y, scene.render.resolution_x):
        raise RuntimeError(f"unexpected render size {img.shape}")
    return img[:, :, :3].astype(np.float64), seconds


def image_stats(img: np.ndarray, expected: np.ndarray) -> dict[str, list[float]]:
    """Per-channel statistics of an (H, W, 3) render of a uniform region whose true value is `expected` (3,).

    mean_rgb: the image mean; noise_rel_rgb: std over pixels / mean (ddof 1: the relative noise of one pixel);
    mean_error_rel_rgb: mean / expected - 1; pixel_rms_error_rel_rgb: sqrt(mean over pixels of
    ((pixel - expected) / expected)^2), i.e. the noise and the bias of one pixel together.
    """
    px = img.reshape(-1, 3)
    mean = px.mean(axis=0)
    std = px.std(axis=0, ddof=1)
    rel = px / expected[None, :] - 1.0
    return {
        "mean_rgb": mean.tolist(),
        "noise_rel_rgb": (std / mean).tolist(),
        "mean_error_rel_rgb": (mean / expected - 1.0).tolist(),
        "pixel_rms_error_rel_rgb": np.sqrt(np.mean(rel**2, axis=0)).tolist(),
    }


def measure(
    presets: list[str], samples_list: tuple[int, ...], size_px: int, log: Callable[[str], None] = print
) -> tuple[list[dict[str, Any]], int]:
    """Render every (preset, method, samples) case; returns (cases, threads used by Cycles)."""
    import bpy
    import spectral_skin

    helpers = load_helpers()
    cases: list[dict[str, Any]] = []
    threads = 0
    with tempfile.TemporaryDirectory(prefix="cycles_samples_") as workdir:
        for preset in presets:
            # The mapping for the Blender that renders (Random Walk changed in 5.2).
            res = spectral_skin.evaluate(preset=preset, outputs=("albedo", "radius"), blender=tuple(bpy.app.version))
            for method, cycles_method in METHODS.items():
                m = res["methods"][method]
                base = np.asarray(m["base_color"], dtype=np.float64)
                radius = np.asarray(m["subsurface_radius_mm"], dtype=np.float64)
                expected = np.asarray(m["expected_albedo"], dtype=np.float64)
                scene = setup_flat_slab(helpers, cycles_method, base, radius, size_px)
                threads = int(scene.render.threads)  # with threads_mode AUTO: the count Cycles uses
                timed_render(helpers, scene, WARMUP_SAMPLES, workdir)  # warm-up: kernels, first sync
                for spp in samples_list:
                    img, seconds = timed_render(helpers, scene, spp, workdir)
                    case = {
                        "preset": preset,
                        "method": method,
                        "samples": spp,
                        "seconds": seconds,
                        **image_stats(img, expected),
                        "expected_albedo_rgb": expected.tolist(),
                    }
                    cases.append(case)
                    log(format_row(case))
    return cases, threads


def format_header() -> str:
    """The stdout table's header."""
    return (
        f"{'preset':<10} {'method':<12} {'spp':>5} {'seconds':>8}  {'pixel noise % (R G B)':<24}"
        f"{'mean error % (R G B)':<27}{'pixel rms error % (R G B)'}"
    )


def format_row(case: dict[str, Any]) -> str:
    """One line of the stdout table."""

    def pct(values: list[float], width: int, prec: int) -> str:
        return " ".join(f"{100 * v:{width}.{prec}f}" for v in values)

    return (
        f"{case['preset']:<10} {case['method']:<12} {case['samples']:>5} {case['seconds']:>8.3f}  "
        f"{pct(case['noise_rel_rgb'], 7, 3):<24}{pct(case['mean_error_rel_rgb'], 8, 3):<27}"
        f"{pct(case['pixel_rms_error_rel_rgb'], 7, 3)}"
    )


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write `data` as JSON to `path` through a temporary file in the same folder and os.replace (creating the
    folder if needed), so readers never see a partial file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(data, f, indent=1)
            f.write("\n")
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Parse the arguments, render every case, print the table, write the JSON; returns the JSON's data."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="caucasian only, 32x32 px, 1-64 spp (under a minute)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"JSON output (default: {DEFAULT_OUT})")
    opts = ap.parse_args(argv)

    import bpy
    import spectral_skin

    presets = list(QUICK_PRESETS) if opts.quick else list(spectral_skin.presets())
    samples_list = QUICK_SAMPLES if opts.quick else FULL_SAMPLES
    size_px = QUICK_SIZE_PX if opts.quick else FULL_SIZE_PX

    print(f"Blender {bpy.app.version_string}, Cycles CPU, {size_px}x{size_px} px over {ORTHO_SCALE_M * 1000:g} mm")
    print(format_header())
    t0 = time.perf_counter()
    cases, threads = measure(presets, samples_list, size_px)
    total = time.perf_counter() - t0
    data: dict[str, Any] = {
        "blender": bpy.app.version_string,
        "spectral_skin": spectral_skin.__version__,
        "threads": threads,
        "device": "CPU",
        "image_px": [size_px, size_px],
        "ortho_scale_mm": ORTHO_SCALE_M * 1000,
        "seed": SEED,
        "filter_width_px": FILTER_WIDTH,
        "quick": bool(opts.quick),
        "total_seconds": total,
        "cases": cases,
    }
    write_json_atomic(opts.out, data)
    print(f"{len(cases)} renders on {threads} threads in {total:.1f} s; wrote {opts.out}")
    return data


if __name__ == "__main__":
    main()
