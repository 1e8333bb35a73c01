#!/usr/bin/env python3
"""How long the per-part thickness of the scene analysis takes (blender_addon/scene_facts.py, ``_shape``: the
closed-mesh count, the BVH tree and the ray casts from up to THICKNESS_SAMPLES faces) on a UV sphere of about 100k
faces, and on the same sphere with a thin plate, in Blender, headless. Prints the figures quoted in
docs/scene-effects.md ("Thin and open geometry").

    .venv-blender/5.0/bin/python scripts/reports/part_thickness_timing.py [--segments 400 --rings 250 --repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=400)
    parser.add_argument("--rings", type=int, default=250)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    import bpy  # first: bpy makes Blender's own modules (bmesh, mathutils) importable

    bpy.ops.wm.read_factory_settings(use_empty=True)
    import bmesh

    from blender_addon import scene_facts

    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=args.segments, v_segments=args.rings, radius=0.08)
    mesh = bpy.data.meshes.new("Sphere")
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new("Sphere", mesh)
    bpy.context.scene.collection.objects.link(obj)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    times = []
    for _ in range(args.repeat):
        start = time.perf_counter()
        shape = scene_facts._shape(obj, depsgraph, 1.0)
        times.append(time.perf_counter() - start)
    print(f"Blender {bpy.app.version_string}: {len(mesh.polygons)} faces, {shape.sampled_faces} sampled, "
          f"{len(shape.parts)} measured; _shape {min(times):.3f} s (best of {args.repeat}; all: "
          f"{', '.join(f'{t:.3f}' for t in times)})")


if __name__ == "__main__":
    main()
