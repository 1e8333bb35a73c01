#!/usr/bin/env python3
"""Calibrate the width of Cycles' random-walk subsurface profile: the Burley-equivalent length d of a random walk as
a function of Base Color, from half-shadow edge renders in the running bpy.

For each subsurface method this Blender offers among RANDOM_WALK, RANDOM_WALK_LEGACY (5.2+) and RANDOM_WALK_SKIN,
and each Base Color A in --albedos, a thick slab is rendered across a hard shadow edge (the scene of
tests/blender/test_renders.py's edge test: sun from straight above, black world, an invisible black half-plane 1.5 mm
above the slab) with the Radius chosen so that the walk's mean free path is --mfp-mm (the walk reads Radius*Scale
differently per version and method: the convention is taken from the core's table, spectral_skin.blender_targets(),
which tests/blender/test_versions.py checks against thin-slab renders). The rendered edge is fitted by
scale * BurleyEdge(x; d) with the scale (the rendered flat albedo) and d free. Recorded per case: d in mm,
d / (Radius*Scale), d / mfp, the scale, and the rms residual of the fit over the image / scale (how Burley-shaped the
walk's edge is). Three albedos share one render (one per RGB channel, radius per channel).

    .venv-blender/5.0/bin/python scripts/calibration/calibrate_random_walk.py          # adds 5.0's entries to the JSON
    .venv-blender/5.3/bin/python scripts/calibration/calibrate_random_walk.py --samples 256 --out /tmp/rw.json

The JSON (default docs/data/random_walk_width.json) holds one entry per (Blender version, method); running the
script in another version adds or replaces that version's entries. Written atomically.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "scripts" / "lib"  # blender_scenes, walk_reference
DEFAULT_OUT = ROOT / "docs" / "data" / "random_walk_width.json"
ALBEDOS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9)
MFP_MM = 0.3
ORTHO_MM = 12.0
WIDTH, HEIGHT = 256, 32
SAMPLES = 512
SEED = 1
METHODS = ("RANDOM_WALK", "RANDOM_WALK_LEGACY", "RANDOM_WALK_SKIN")


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--albedos", type=float, nargs="+", default=list(ALBEDOS))
    parser.add_argument("--samples", type=int, default=SAMPLES)
    parser.add_argument("--mfp-mm", type=float, default=MFP_MM)
    parser.add_argument("--methods", nargs="+", default=list(METHODS), help="Blender enum ids; absent ones skipped")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    for a in args.albedos:
        if not 0.0 < a < 1.0:
            parser.error(f"--albedos: {a} is outside (0, 1)")
    if args.samples < 1 or args.mfp_mm <= 0:
        parser.error("--samples must be >= 1 and --mfp-mm > 0")

    import bpy

    sys.path.insert(0, str(LIB))
    import blender_scenes as helpers
    import walk_reference as walk
    version = "{}.{}".format(*bpy.app.version[:2])
    models = walk.core_walk_models(bpy.app.version)  # the core's radius convention per method for this Blender
    methods = [m for m in args.methods if m in models and m in walk.subsurface_methods()]
    entries = []
    for method in methods:
        cases = []
        albedos = list(args.albedos)
        for start in range(0, len(albedos), 3):
            group = albedos[start : start + 3]
            base = group + [group[-1]] * (3 - len(group))
            radius_mm = [args.mfp_mm / walk.mean_free_path_per_radius(models[method], a) for a in base]
            scene = helpers.reset_scene()
            mat, _ = helpers.principled_sss("Walk", method, base, radius_mm)
            t0 = time.perf_counter()
            x_mm, edge = helpers.render_edge(scene, mat, ORTHO_MM, WIDTH, HEIGHT, args.samples, seed=SEED)
            seconds = time.perf_counter() - t0
            for c, a in enumerate(group):
                d_mm, scale, rms = helpers.fit_burley_edge(x_mm, edge[:, c], 0.01, 5.0)
                case = {
                    "albedo": a,
                    "radius_mm": radius_mm[c],
                    "mfp_mm": args.mfp_mm,
                    "d_mm": d_mm,
                    "d_over_radius": d_mm / radius_mm[c],
                    "d_over_mfp": d_mm / args.mfp_mm,
                    "flat_albedo": scale,
                    "fit_rms_rel": rms,
                    "render_seconds": seconds,
                }
                cases.append(case)
                print(f"[{version} {method}] A {a:.2f}: d {d_mm:.4f} mm = {case['d_over_radius']:.4f} x Radius*Scale "
                      f"= {case['d_over_mfp']:.4f} x mfp; flat albedo {scale:.4f}; fit rms {rms * 100:.3f} % "
                      f"({seconds:.1f} s)", flush=True)
        entries.append({"blender": version, "bpy": bpy.app.version_string, "method": method, "cases": cases})

    data: dict[str, Any] = {"entries": []}
    if args.out.exists():
        data = json.loads(args.out.read_text())
    keep = [e for e in data.get("entries", []) if (e["blender"], e["method"]) not in {(version, m) for m in methods}]
    data = {
        "description": "Burley-equivalent length d of Cycles' random-walk edge vs Base Color (fit of "
        "scale * BurleyEdge(x; d) to a half-shadow edge render); regenerate: "
        "<venv>/bin/python scripts/calibration/calibrate_random_walk.py",
        "scene": {"ortho_mm": ORTHO_MM, "image_px": [WIDTH, HEIGHT], "samples": args.samples, "seed": SEED,
                  "mfp_mm": args.mfp_mm},
        "entries": sorted(keep + entries, key=lambda e: (e["blender"], e["method"])),
    }
    helpers.write_json_atomically(args.out, data)
    return data


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # bpy 4.5 can hang at interpreter exit
