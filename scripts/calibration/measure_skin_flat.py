#!/usr/bin/env python3
"""Measure the flat-slab response of Cycles' Random Walk (Skin): what a thick slab under a uniform white world renders,
divided by its Base Color, against Base Color, in the running bpy.

Random Walk (Skin) turns Base Color into the walk's albedo through a dipole inversion and enters the surface half by
a diffuse and half by a rough refraction, so its flat slab does not render Base Color; the core's Skin mapping
(src/fit/random_walk_skin.rs) inverts this measured response. Scene: the flat-slab scene of
tests/blender/test_renders.py (thick slab, uniform white world of strength 1, orthographic top view of 10 mm at
64 x 64 px, central 48 x 48 px averaged), Subsurface Weight 1, Specular IOR Level 0, Roughness 0, the default
Subsurface IOR 1.4, Radius 1 mm (the response does not depend on it: 0.3 mm gives the same figures to 4 digits).
Three Base Colors share one render (one per RGB channel).

    .venv-blender/5.0/bin/python scripts/calibration/measure_skin_flat.py        # rewrites docs/data/random_walk_skin_flat.json

The JSON is compiled into the core (`fit::random_walk_skin`); written atomically.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "scripts" / "lib"  # blender_scenes
DEFAULT_OUT = ROOT / "docs" / "data" / "random_walk_skin_flat.json"
# Dense below 0.05, where the african preset's Base Colors lie (0.02-0.04) and the response bends fastest.
BASE_COLORS = (0.005, 0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04, 0.05, 0.07, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9,
               0.95)
RADIUS_MM = 1.0
ORTHO_M = 0.01
SIZE_PX, REGION_PX = 64, 48
SAMPLES = 1024
SEED = 1


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base-colors", type=float, nargs="+", default=list(BASE_COLORS))
    parser.add_argument("--samples", type=int, default=SAMPLES)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    for a in args.base_colors:
        if not 0.0 < a < 1.0:
            parser.error(f"--base-colors: {a} is outside (0, 1)")
    if args.samples < 1:
        parser.error("--samples must be >= 1")

    import bpy


    sys.path.insert(0, str(LIB))
    import blender_scenes as helpers
    colors = sorted(args.base_colors)
    cases = []
    for start in range(0, len(colors), 3):
        group = colors[start : start + 3]
        base = group + [group[-1]] * (3 - len(group))
        scene = helpers.reset_scene()
        helpers.set_world(scene, strength=1.0)
        slab = helpers.add_slab()
        mat, _ = helpers.principled_sss("Skin", "RANDOM_WALK_SKIN", base, [RADIUS_MM] * 3)
        helpers.assign(slab, mat)
        helpers.add_top_camera(scene, ortho_scale=ORTHO_M, width=SIZE_PX, height=SIZE_PX)
        t0 = time.perf_counter()
        img = helpers.render(scene, samples=args.samples, seed=SEED)
        seconds = time.perf_counter() - t0
        lo = (SIZE_PX - REGION_PX) // 2
        mean = img[lo : lo + REGION_PX, lo : lo + REGION_PX].reshape(-1, 3).mean(axis=0)
        for c, a in enumerate(group):
            ratio = float(mean[c]) / a
            cases.append({"base_color": a, "rendered": float(mean[c]), "ratio": ratio})
            print(f"[{bpy.app.version_string} RANDOM_WALK_SKIN] Base Color {a:.3f}: rendered {mean[c]:.6f} = "
                  f"{ratio:.4f} x Base Color ({seconds:.1f} s)", flush=True)
    if any(b["rendered"] <= a["rendered"] for a, b in zip(cases, cases[1:], strict=False)):
        raise SystemExit("measured response is not rising in Base Color: more samples needed")
    data = {
        "description": "Random Walk (Skin) thick flat slab under a uniform white world: rendered value / Base Color; "
        "regenerate: <venv>/bin/python scripts/calibration/measure_skin_flat.py",
        "blender": "{}.{}".format(*bpy.app.version[:2]),
        "bpy": bpy.app.version_string,
        "scene": {"ortho_m": ORTHO_M, "image_px": SIZE_PX, "region_px": REGION_PX, "samples": args.samples,
                  "seed": SEED, "radius_mm": RADIUS_MM, "subsurface_ior": 1.4, "roughness": 0.0},
        "cases": cases,
    }

    helpers.write_json_atomically(args.out, data)
    return data


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # bpy 4.5 can hang at interpreter exit
