#!/usr/bin/env python3
"""Fit the measured skin surface's two Principled roughnesses (base Roughness for the broad lobe, Coat Roughness for
the sharp lobe) to rendered in-plane BRDF slices, per oiliness node and engine, in the running bpy.

For each oiliness node and each candidate pair on a grid, the Specular IOR Level is first solved from a
normal-incidence render (`blender_scenes.render_normal_incidence_reflection`, several levels, linear between them) so
that Blender's normal-incidence reflection equals the model's E(0); then the candidates' in-plane slices are rendered
at once (`blender_scenes.render_in_plane_slices`) and scored by the RMS of rendered minus model
(`spectral_skin.surface_brdf` x cos theta_in) over the model's peak, averaged over the incidences. Coat Weight and the
IORs are the core's (`evaluate(surface="measured")`). The base Roughness is one value for every oiliness (the model's
broad lobe does not change with oil: its m is 0.5 throughout), the one whose best Coat Roughness per node gives the
least summed score; the Coat Roughness is chosen per node. Prints the best pairs per node; writes the choice.

    <venv>/bin/python scripts/calibration/fit_surface_roughness.py --engine cycles  # docs/data/surface_roughness_cycles.json
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

OILINESS = (0.0, 0.5, 1.0)
BASE_ROUGHNESS = tuple(round(0.45 + 0.05 * i, 2) for i in range(8))  # 0.45 .. 0.80
COAT_ROUGHNESS = tuple(round(0.25 + 0.05 * i, 2) for i in range(8))  # 0.25 .. 0.60
LEVELS = (0.1, 0.4, 0.7, 1.0)
INCIDENCES_DEG = (0, 15, 30, 45, 60, 75)
SAMPLES = {"cycles": {"level": 256, "slices": 128}, "eevee": {"level": 16, "slices": 16}}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    engine, out = engine_and_output(__doc__ or "", "surface_roughness", argv)

    import blender_scenes as helpers
    import bpy
    import numpy as np
    import spectral_skin

    samples = SAMPLES[engine]
    pairs = [(rb, rc) for rb in BASE_ROUGHNESS for rc in COAT_ROUGHNESS]
    nodes: list[dict[str, Any]] = []
    per_node: list[tuple[float, dict]] = []
    start = time.perf_counter()
    for oiliness in OILINESS:
        spec = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",),
                                      surface="measured", engine=engine)["specular"]
        common = {"IOR": spec["ior"], "Coat Weight": spec["coat_weight"], "Coat IOR": spec["coat_ior"]}
        target = float(spectral_skin.surface_albedo(0.0, oiliness=oiliness, surface="measured"))
        planes = [{**common, "Roughness": rb, "Coat Roughness": rc, "Specular IOR Level": level}
                  for rb, rc in pairs for level in LEVELS]
        rendered = np.array(helpers.render_normal_incidence_reflection(planes, engine, samples["level"]))
        rendered = rendered.reshape(len(pairs), len(LEVELS))
        levels = [float(np.interp(target, row, LEVELS, left=np.nan, right=np.nan)) for row in rendered]
        usable = [k for k, level in enumerate(levels) if np.isfinite(level)]
        surfaces = [{**common, "Roughness": pairs[k][0], "Coat Roughness": pairs[k][1],
                     "Specular IOR Level": levels[k]} for k in usable]
        slices = helpers.render_in_plane_slices(surfaces, engine, INCIDENCES_DEG, samples["slices"])
        scores = {}
        for k, per_incidence in zip(usable, slices, strict=True):
            rms = []
            for s in per_incidence:
                model = spectral_skin.surface_brdf(s["theta_in_deg"], s["theta_out_deg"], s["phi_deg"],
                                                   oiliness=oiliness, surface="measured")
                model = model * np.cos(np.radians(s["theta_in_deg"]))
                rms.append(float(np.sqrt(np.mean((s["radiance"] - model) ** 2)) / model.max()))
            scores[pairs[k]] = (float(np.mean(rms)), levels[k], rms)
        for (rb, rc), (mean, level, rms) in sorted(scores.items(), key=lambda item: item[1][0])[:5]:
            print(f"[{bpy.app.version_string} {engine}] oiliness {oiliness}: Roughness {rb:.2f}, Coat Roughness "
                  f"{rc:.2f}, level {level:.3f}: RMS/peak {mean:.3f} (" + ", ".join(f"{r:.3f}" for r in rms) + ")",
                  flush=True)
        per_node.append((oiliness, scores))
    # One base Roughness for every node: the least sum over the nodes of each node's best score with it.
    def best_coat(scores: dict, rb: float) -> tuple[float, tuple[float, float]] | None:
        options = [(v[0], pair) for pair, v in scores.items() if pair[0] == rb]
        return min(options) if options else None

    totals = {}
    for rb in BASE_ROUGHNESS:
        best = [best_coat(scores, rb) for _, scores in per_node]
        if all(b is not None for b in best):
            totals[rb] = sum(b[0] for b in best if b is not None)
    base = min(totals, key=lambda rb: totals[rb])
    for oiliness, scores in per_node:
        found = best_coat(scores, base)
        assert found is not None
        mean, pair = found
        _, level, rms = scores[pair]
        nodes.append({"oiliness": oiliness, "roughness": base, "coat_roughness": pair[1], "specular_ior_level": level,
                      "rms_over_peak": rms, "incidences_deg": list(INCIDENCES_DEG)})
        print(f"chosen: oiliness {oiliness}: Roughness {base:.2f}, Coat Roughness {pair[1]:.2f}, level {level:.3f}, "
              f"RMS/peak {mean:.3f}", flush=True)
    data = {
        **provenance("Principled Roughness and Coat Roughness of the measured surface fitted to rendered in-plane "
                     "BRDF slices per oiliness node (the level solved per pair for the model's normal-incidence "
                     "reflection)", __file__, engine),
        "grid": {"roughness": list(BASE_ROUGHNESS), "coat_roughness": list(COAT_ROUGHNESS), "levels": list(LEVELS)},
        "samples": samples,
        "seconds": round(time.perf_counter() - start, 1),
        "nodes": nodes,
    }
    helpers.write_json_atomically(out, data)
    return data


if __name__ == "__main__":
    run_and_exit(main)
