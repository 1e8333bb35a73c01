"""Render the README preview: a sphere per preset of the core (the paper's three, the measured thirds, then the ITA
palette: rows of six in the core's order, the first row at the back), applied by the add-on with its defaults (the measured surface).

Headless (bpy as a Python module, no Blender UI): Cycles CPU, Christensen-Burley subsurface, a sun and a dim sky,
480x200 px, 128 samples, written as an sRGB PNG (Standard view transform) stamped with the model's version.

    .venv/bin/python scripts/tools/render_preview.py [--out docs/images/presets.png] [--samples 128] [--size 480x200]
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "scripts" / "lib"))

import bpy  # noqa: E402
import doc_stamp  # noqa: E402
import spectral_skin  # noqa: E402

import blender_addon  # noqa: E402

RADIUS = 0.06  # sphere radius, metres (skin's mean free paths are ~mm: a head-sized curvature)
PER_ROW = 6
SPACING = 2.6 * RADIUS  # centre to centre along a row
ROW_SPACING = 3.4 * RADIUS  # between rows, so that the back row shows above the front one


def build_scene(width: int, height: int, samples: int) -> bpy.types.Scene:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply"):
        blender_addon.register()
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 1.0
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = samples
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.seed = 1
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.display_settings.display_device = "sRGB"
    image = scene.render.image_settings
    image.file_format = "PNG"
    image.color_mode = "RGB"
    image.color_depth = "8"

    world = bpy.data.worlds.new("World")
    background = world.node_tree.nodes.get("Background") or world.node_tree.nodes.new("ShaderNodeBackground")
    background.inputs["Color"].default_value = (0.55, 0.65, 0.8, 1.0)
    background.inputs["Strength"].default_value = 0.35
    scene.world = world

    sun_data = bpy.data.lights.new("Sun", type="SUN")
    sun_data.energy = 3.0
    sun_data.angle = math.radians(3.0)
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (math.radians(50.0), 0.0, math.radians(-35.0))
    scene.collection.objects.link(sun)

    # A light grey floor under the spheres.
    floor_mat = bpy.data.materials.new("Floor")
    floor_bsdf = floor_mat.node_tree.nodes.get("Principled BSDF")
    floor_bsdf.inputs["Base Color"].default_value = (0.35, 0.35, 0.35, 1.0)
    floor_bsdf.inputs["Roughness"].default_value = 0.8
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0.0, 0.0, 0.0))
    bpy.context.object.data.materials.append(floor_mat)

    presets = list(spectral_skin.presets())
    rows = math.ceil(len(presets) / PER_ROW)
    for index, preset in enumerate(presets):
        row, column = divmod(index, PER_ROW)
        location = ((column - (PER_ROW - 1) / 2) * SPACING, ((rows - 1) / 2 - row) * ROW_SPACING, RADIUS)
        material = bpy.data.materials.new(f"Skin {preset.title()}")
        settings = material.spectral_skin
        settings.preset = preset.upper()  # sets the four parameters
        settings.method = "BURLEY"
        result = bpy.ops.spectral_skin.apply(material=material.name)
        assert result == {"FINISHED"}, result
        bpy.ops.mesh.primitive_uv_sphere_add(radius=RADIUS, segments=48, ring_count=24, location=location)
        sphere = bpy.context.object
        sphere.name = f"Sphere {preset}"
        bpy.ops.object.shade_smooth()
        sphere.data.materials.append(material)

    cam_data = bpy.data.cameras.new("Camera")
    cam_data.lens = 50.0
    camera = bpy.data.objects.new("Camera", cam_data)
    camera.location = (0.0, -1.2, 0.78)
    camera.rotation_euler = (math.radians(59.5), 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(REPO / "docs" / "images" / "presets.png"))
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--size", default="480x200")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    start = time.perf_counter()
    scene = build_scene(width, height, args.samples)
    built = time.perf_counter()
    out = os.path.abspath(args.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    scene.render.filepath = out
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True)
    done = time.perf_counter()
    doc_stamp.stamp_png(pathlib.Path(out), doc_stamp.command(__file__))
    for material in bpy.data.materials:
        if material.name.startswith("Skin"):
            print(f"{material.name}: albedo {[round(c, 3) for c in material.spectral_skin.result_albedo]}, "
                  f"radius {[round(r, 3) for r in material.spectral_skin.result_radius_mm]} mm")
    print(f"wrote {out} ({width}x{height}, {args.samples} spp): scene + apply {built - start:.2f} s, "
          f"render {done - built:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
