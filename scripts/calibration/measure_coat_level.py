#!/usr/bin/env python3
"""Measure the normal-incidence surface reflection of the measured skin surface's Principled set-up (base lobe under a
Coat) against Specular IOR Level, in the running bpy and engine: what the core's `surface="measured"` mapping
inverts for the level that makes Blender's reflection equal to the model's.

The measured model's two lobes go onto one Principled BSDF: the broad lobe as the base specular (Roughness =
sqrt(m_broad), IOR 1.4) and the sharp lobe as the Coat (Weight = w_sharp(o), Roughness = sqrt(m_sharp(o)), IOR 1.4),
all as the core gives them (`spectral_skin.evaluate(surface="measured", outputs=("specular",))`; only the level is
varied here). Under a coat Blender leaves the base lobe's index alone
and scales it by what the coat leaves, and its rough GGX lobes reflect less than the Fresnel factor at normal
incidence (docs/blender-coat.md), so the level that gives the model's normal-incidence reflectance is measured, not
derived. Scene: `blender_scenes.render_normal_incidence_reflection`, one plane per (oiliness, level), Base Color
black, Subsurface Weight 0, under a uniform white world, seen along the normal: each plane's pixels are its directional
albedo at normal incidence.

    <venv>/bin/python scripts/calibration/measure_coat_level.py --engine cycles   # rewrites docs/data/coat_level_cycles.json
    <venv>/bin/python scripts/calibration/measure_coat_level.py --engine eevee    # rewrites docs/data/coat_level_eevee.json

The JSON is compiled into the core (`surface::principled`); written atomically.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "scripts" / "lib"  # blender_scenes, calibration
sys.path.insert(0, str(LIB))
from calibration import engine_and_output, provenance, run_and_exit  # noqa: E402

OILINESS = tuple(i / 10 for i in range(11))
LEVELS = (0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
SAMPLES = {"cycles": 1024, "eevee": 16}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    engine, out = engine_and_output(__doc__ or "", "coat_level", argv)

    import blender_scenes as helpers
    import bpy
    import spectral_skin

    inputs = {o: spectral_skin.evaluate(preset="caucasian", oiliness=o, surface="measured", outputs=("specular",),
                                        engine=engine)["specular"] for o in OILINESS}
    grid = [(o, level) for level in LEVELS for o in OILINESS]
    surfaces = [{**helpers.principled_surface_inputs(inputs[o]), "Specular IOR Level": level} for o, level in grid]
    t0 = time.perf_counter()
    rendered = helpers.render_normal_incidence_reflection(surfaces, engine, SAMPLES[engine])
    seconds = time.perf_counter() - t0
    cases = [{"oiliness": o, "specular_ior_level": level, "rendered": r} for (o, level), r in zip(grid, rendered,
                                                                                                   strict=True)]
    for oiliness in OILINESS:
        row = [c for c in cases if c["oiliness"] == oiliness]
        print(f"[{bpy.app.version_string} {engine}] oiliness {oiliness:.1f}: "
              + ", ".join(f"level {c['specular_ior_level']:.2f} -> {c['rendered']:.5f}" for c in row), flush=True)
        if any(b["rendered"] <= a["rendered"] for a, b in zip(row, row[1:], strict=False)):
            raise SystemExit(f"the reflection does not rise with the level at oiliness {oiliness}")
    data = {
        **provenance("Normal-incidence directional albedo of the measured surface's Principled set-up (base lobe "
                     "under a Coat, Base Color black) under a uniform white world, per oiliness and Specular IOR Level",
                     __file__, engine),
        "scene": {"samples": SAMPLES[engine], "seconds": round(seconds, 1)},
        "cases": cases,
    }
    helpers.write_json_atomically(out, data)
    return data


if __name__ == "__main__":
    run_and_exit(main)
