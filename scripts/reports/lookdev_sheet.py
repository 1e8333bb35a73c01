#!/usr/bin/env python3
"""The look-dev sheet: every preset (lightest to darkest albedo) as head-sized spheres under one studio light,
applied by the add-on with the paper's surface (top row) and the measured surface (bottom row, the default), rendered
by Cycles and saved in Blender's Standard and AgX view transforms; and the render-time cost of the measured surface's
Coat (the same spheres rendered with Coat Weight 0, the rest unchanged). Writes docs/images/lookdev-*.png and
docs/lookdev.md.

    .venv/bin/python scripts/reports/lookdev_sheet.py              # bpy 5.0 in .venv; a few minutes on 2 cores
    .venv-blender/5.3/bin/python scripts/reports/lookdev_sheet.py --out /tmp/lookdev --samples 32
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LIB = ROOT / "scripts" / "lib"
DOCS = ROOT / "docs"
SURFACES = ("paper", "measured")
VIEW_TRANSFORMS = ("Standard", "AgX")
RADIUS_M = 0.09  # a head's half-width
SPACING_M = 0.24
TIMING_REPEATS = 5
KEY_WATTS = 70.0  # the softbox at the six-preset sheet's distance: the lightest skin just below white in Standard
PX_PER_SPHERE = 150  # the sheet's default width per preset
HEIGHT_PX = 360
LENS_HALF_FIELD = 18.0 / 50.0  # a 50 mm lens on Blender's 36 mm sensor: half the field's width per metre away


def _presets_light_to_dark() -> list[str]:
    import spectral_skin

    def luminance(name: str) -> float:
        r, g, b = spectral_skin.evaluate(preset=name, outputs=["albedo"])["diffuse_reflectance_rgb"]
        return 0.2126 * r + 0.7152 * g + 0.0722 * b  # Rec.709 luminance of the linear albedo

    return sorted(spectral_skin.presets(), key=luminance, reverse=True)


def _camera_distance_m(presets: int) -> float:
    """How far the camera stands so that a row of ``presets`` spheres fills the frame's width with a margin (at
    least the 2.6 m the six-preset sheet used)."""
    return max(2.6, (presets * SPACING_M / 2 + 0.12) / LENS_HALF_FIELD)


def _scene(width: int, height: int, samples: int, distance_m: float):
    import bpy
    import mathutils

    sys.path.insert(0, str(LIB))
    import blender_scenes

    scene = blender_scenes.reset_scene()
    blender_scenes.set_world(scene, strength=0.08)  # a dim grey fill, so the shadow sides are not black
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # reproducible and free of denoiser look; noise is what samples buy
    scene.display_settings.display_device = "sRGB"
    # One studio light: a softbox up and to the left of the camera, 0.6 m square 1.6 m away for the six-preset sheet,
    # moved away and enlarged with the camera (same irradiance at the centre) so that a longer row is lit alike.
    k = distance_m / 2.6
    bpy.ops.object.light_add(type="AREA", location=(-0.9 * k, -1.1 * k, 0.9 * k))
    key = bpy.context.object
    key.data.size = 0.6 * k
    key.data.energy = KEY_WATTS * k * k
    key.rotation_euler = (mathutils.Vector((0.0, 0.0, 0.0)) - key.location).to_track_quat("-Z", "Y").to_euler()
    bpy.ops.object.camera_add(location=(0.0, -distance_m, 0.0), rotation=(1.5707963, 0.0, 0.0))
    camera = bpy.context.object
    camera.data.lens = 50.0
    scene.camera = camera
    return scene


def _spheres(presets: list[str]) -> dict[tuple[str, str], object]:
    """One sphere per (surface, preset): the paper's row above, the measured row below; each material applied by the
    add-on (its Apply operator: what an artist gets)."""
    import bpy

    materials = {}
    n = len(presets)
    for row, surface in enumerate(SURFACES):
        for column, preset in enumerate(presets):
            x = (column - (n - 1) / 2) * SPACING_M
            z = (0.5 - row) * SPACING_M
            bpy.ops.mesh.primitive_uv_sphere_add(radius=RADIUS_M, location=(x, 0.0, z), segments=64, ring_count=32)
            sphere = bpy.context.object
            bpy.ops.object.shade_smooth()
            material = bpy.data.materials.new(f"{surface} {preset}")
            sphere.data.materials.append(material)
            props = material.spectral_skin
            props.preset = preset.upper()  # the panel's preset menu: the core's names, upper case
            props.surface = surface.upper()
            assert bpy.ops.spectral_skin.apply(material=material.name) == {"FINISHED"}, material.name
            materials[(surface, preset)] = material
    return materials


def _render_seconds(scene) -> float:
    import bpy

    start = time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DOCS, help="folder for lookdev.md (images in its images/)")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--width", type=int, default=None, help=f"default: {PX_PER_SPHERE} px per preset")
    args = parser.parse_args(argv)

    import bpy

    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(LIB))
    import doc_stamp

    import blender_addon

    regenerate = doc_stamp.command(__file__)
    presets = _presets_light_to_dark()
    width, height = args.width or PX_PER_SPHERE * len(presets), HEIGHT_PX
    distance_m = _camera_distance_m(len(presets))
    scene = _scene(width, height, args.samples, distance_m)
    blender_addon.register()
    start = time.perf_counter()
    materials = _spheres(presets)
    apply_seconds = time.perf_counter() - start
    (args.out / "images").mkdir(parents=True, exist_ok=True)
    bpy.ops.render.render()
    images = {}
    for view in VIEW_TRANSFORMS:
        scene.view_settings.view_transform = view
        scene.view_settings.look = "None"
        scene.render.image_settings.file_format = "PNG"
        scene.render.image_settings.color_mode = "RGB"
        scene.render.image_settings.color_depth = "8"
        path = args.out / "images" / f"lookdev-{view.lower()}.png"
        bpy.data.images["Render Result"].save_render(str(path), scene=scene)
        doc_stamp.stamp_png(path, regenerate)
        images[view] = path

    # The Coat's render time: only the measured row, rendered with its Coat and with Coat Weight 0, alternating.
    for (surface, _), material in materials.items():
        if surface == "paper":
            for obj in [o for o in scene.objects if o.type == "MESH" and o.active_material == material]:
                obj.hide_render = True
    principled = [next(n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
                  for (s, _), m in materials.items() if s == "measured"]
    weights = [p.inputs["Coat Weight"].default_value for p in principled]
    with_coat, without_coat = [], []
    for _ in range(TIMING_REPEATS):
        for p, w in zip(principled, weights, strict=True):
            p.inputs["Coat Weight"].default_value = w
        with_coat.append(_render_seconds(scene))
        for p in principled:
            p.inputs["Coat Weight"].default_value = 0.0
        without_coat.append(_render_seconds(scene))
    coat, plain = statistics.median(with_coat), statistics.median(without_coat)

    lines = [
        doc_stamp.stamp(regenerate),
        "",
        "# Look-dev sheet: paper and measured surface",
        "",
        "Written by `scripts/reports/lookdev_sheet.py`; do not edit by hand. Regenerate:",
        "",
        f"    {regenerate}",
        "",
        f"Blender {bpy.app.version_string}, Cycles CPU, {args.samples} samples, no denoising, {width}×{height}. "
        f"The {len(presets)} presets (the paper's three, the measured thirds and the ITA palette), lightest albedo "
        f"first ({', '.join(presets)}), as spheres of radius {RADIUS_M * 100:.0f} cm "
        f"(a head's half-width) under one {0.6 * distance_m / 2.6:.1f} m softbox up and to the left and a dim grey "
        "world. Each material is "
        "applied by the add-on (Subsurface Method Burley); **top row: the paper's surface** (Donner & Jensen's oil "
        "layer: one lobe scaled by the oiliness, 0.3 in every preset), **bottom row: the measured surface** (the "
        "default: a broad base lobe and a sharp Coat that reflect like a dielectric, about 2.8 % along the normal; "
        "[model.md](model.md#principled-mapping-of-the-measured-surface)).",
        "",
    ]
    for view, path in images.items():
        lines += [f"**{view}** view transform:", "", f"![{view}](images/{path.name})", ""]
    lines += [
        "What to look for: the measured surface's highlight is broader and its rim brighter (Fresnel at grazing angles "
        "on both lobes), most visible on the darkest skin, where the surface reflection is a larger share of what is "
        "seen; the paper's lobe at oiliness 0.3 reflects 0.3 × F0 along the normal, under a third of the measured "
        "surface's.",
        "",
        "## Render-time cost of the Coat",
        "",
        f"The measured row alone ({len(presets)} spheres, the same frame and samples), rendered {TIMING_REPEATS} "
        "times with its Coat and with Coat Weight 0 (everything else unchanged), alternating; medians:",
        "",
        "| set-up | median render time (s) | renders (s) |",
        "|---|---|---|",
        f"| measured surface, Coat on | {coat:.2f} | {', '.join(f'{t:.2f}' for t in with_coat)} |",
        f"| Coat Weight 0 | {plain:.2f} | {', '.join(f'{t:.2f}' for t in without_coat)} |",
        "",
        f"Ratio: **{coat / plain:.3f}** (the Coat adds {100 * (coat / plain - 1):+.1f} % to the render time on this "
        f"{os.cpu_count()}-core machine; medians of {TIMING_REPEATS}: the machines are noisy). Applying the "
        f"{len(materials)} materials took {apply_seconds:.1f} s.",
        "",
    ]
    doc_stamp.write_text(args.out / "lookdev.md", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
