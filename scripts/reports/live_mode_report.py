#!/usr/bin/env python3
"""What Live mode costs: the shader table's build time (cold cache, and reused) and the add-on's Apply, and the
render time of a Live material against its Baked twin in the same scene (Cycles), through bpy.

Scene: the flat slab of tests/blender/test_live_mode.py (thick slab, white world, orthographic top camera over
100 mm of it; Burley, oiliness 0; Cycles CPU, fixed seed, no adaptive sampling or denoising, threads AUTO), with one
material at a time, applied by the add-on's own path (apply.apply_skins):

- constants: caucasian's parameters as values (Live: the "Spectral Skin" group with constant inputs, four table
  lookups per shading point; Baked: Base Color and Radius as values);
- haemoglobin map: a 256 x 256 painted haemoglobin image over the slab (Live: the image and the group; Baked: the
  albedo and radius textures computed from it).

Render time is the wall time of bpy.ops.render.render alone (writing no file), after one warm-up render of each
material in that scene; the median of REPEATS renders, Live and Baked alternated so that both see the same load.
"Cost per shading sample" is (Live - Baked) / (pixels x samples). Cold table builds use a new empty
SPECTRAL_SKIN_CACHE_DIR each (the shader table is the map pipeline's lookup table and shares its cache).

    .venv-blender/5.0/bin/python scripts/reports/live_mode_report.py            # -> docs/live-mode.md, docs/data/live_mode.json
    .venv-blender/5.0/bin/python scripts/reports/live_mode_report.py --quick --out /tmp/live.md   # one size, 1 repeat
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
for path in (ROOT, ROOT / "scripts" / "lib"):  # blender_addon; blender_scenes
    if str(path) not in sys.path:
        sys.path.insert(0, str(path))

import blender_scenes  # noqa: E402
import bpy  # noqa: E402
import doc_stamp  # noqa: E402
import spectral_skin  # noqa: E402

REPEATS = 3
SIZES_PX = (64, 128, 256)
SAMPLES = (16, 128)
MAP_PX = 256
ORTHO_SCALE_M = 0.1
TABLE_METHODS = ("burley", "random_walk")
DEFAULT_DOC = ROOT / "docs" / "live-mode.md"
DEFAULT_JSON = ROOT / "docs" / "data" / "live_mode.json"
COMMAND = ".venv-blender/5.0/bin/python scripts/reports/live_mode_report.py"


def _median(values: list[float]) -> float:
    return float(statistics.median(values))


def table_build_times(repeats: int) -> dict[str, Any]:
    """Cold (empty cache) and warm (cached) shader-table build times per method, for this Blender's Cycles target."""
    blender = "{}.{}".format(*bpy.app.version[:2])
    out: dict[str, Any] = {}
    saved = os.environ.get("SPECTRAL_SKIN_CACHE_DIR")
    try:
        for method in TABLE_METHODS:
            cold, warm = [], []
            for _ in range(repeats):
                with tempfile.TemporaryDirectory(prefix="spectral_skin_cache_") as cache:
                    os.environ["SPECTRAL_SKIN_CACHE_DIR"] = cache
                    t0 = time.perf_counter()
                    table = spectral_skin.shader_table(method=method, blender=blender, engine="cycles")
                    cold.append(time.perf_counter() - t0)
                    t0 = time.perf_counter()
                    spectral_skin.shader_table(method=method, blender=blender, engine="cycles")
                    warm.append(time.perf_counter() - t0)
            meta = table["metadata"]
            out[method] = {"cold_s": _median(cold), "warm_s": _median(warm), "cold_all_s": cold,
                           "image": [int(meta["width"]), int(table["base_color_log"].shape[0])]}
            print(f"[live-report] table {method}: cold {out[method]['cold_s']:.2f} s, cached "
                  f"{out[method]['warm_s'] * 1000:.1f} ms", flush=True)
    finally:
        if saved is None:
            os.environ.pop("SPECTRAL_SKIN_CACHE_DIR", None)
        else:
            os.environ["SPECTRAL_SKIN_CACHE_DIR"] = saved
    return out


def _register() -> None:
    import blender_addon

    bpy.ops.wm.read_factory_settings(use_empty=True)
    if not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply"):
        blender_addon.register()


def _skin(name: str, mode: str, hemoglobin_map: Any = None) -> Any:
    preset = spectral_skin.presets()["caucasian"]
    material = bpy.data.materials.new(name)
    props = material.spectral_skin
    props.mode = mode
    props.override_subsurface = "ON"
    for key in ("melanin", "melanin_blend", "hemoglobin"):
        setattr(props, key, float(preset[key]))
    props.oiliness = 0.0
    if hemoglobin_map is not None:
        props.hemoglobin_map = hemoglobin_map
    return material


def _painted_hemoglobin() -> Any:
    """A generated (painted, unsaved) float image: haemoglobin 0.002-0.08 in blobs, as a blush would be."""
    y, x = np.mgrid[0:MAP_PX, 0:MAP_PX] / MAP_PX
    value = 0.002 + 0.078 * np.exp(-(((x - 0.4) ** 2 + (y - 0.6) ** 2) / 0.03))
    image = bpy.data.images.new("Painted", width=MAP_PX, height=MAP_PX, float_buffer=True)
    rgba = np.ones((MAP_PX, MAP_PX, 4), dtype=np.float32)
    rgba[..., :3] = value[:, :, None]
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image


def _scene(variant: str, folder: str) -> tuple[Any, dict[str, Any], dict[str, float]]:
    """A fresh scene with the slab, a Live and a Baked material applied (timed), the slab UV-mapped over the view."""
    from blender_addon import nodes
    from blender_addon.apply import apply_skins
    from blender_addon.props import settings_from_material

    _register()
    scene = blender_scenes.reset_scene()
    blender_scenes.set_world(scene, strength=1.0)
    slab = blender_scenes.add_slab()
    uv = slab.data.uv_layers.new(name="UVMap")
    for loop in slab.data.loops:
        px, py, _ = slab.data.vertices[loop.vertex_index].co
        uv.data[loop.index].uv = (px / ORTHO_SCALE_M + 0.5, py / ORTHO_SCALE_M + 0.5)
    image = _painted_hemoglobin() if variant == "haemoglobin map" else None
    materials = {mode: _skin(mode.title(), mode, image) for mode in ("LIVE", "BAKED")}
    materials["BAKED"].spectral_skin.output_dir = folder
    blender_scenes.assign(slab, materials["LIVE"])
    blender_scenes.add_top_camera(scene, ortho_scale=ORTHO_SCALE_M, width=64, height=64)
    apply_s = {}

    def timed_apply(mode: str) -> float:
        material = materials[mode]
        t0 = time.perf_counter()
        apply_skins([(material, settings_from_material(material, scene))], scene)
        return time.perf_counter() - t0

    with tempfile.TemporaryDirectory(prefix="spectral_skin_cache_") as cache:
        saved = os.environ.get("SPECTRAL_SKIN_CACHE_DIR")
        os.environ["SPECTRAL_SKIN_CACHE_DIR"] = cache  # cold: the table is built
        try:
            apply_s["LIVE"] = timed_apply("LIVE")
            apply_s["LIVE again"] = timed_apply("LIVE")  # the table reused from the .blend
            apply_s["BAKED"] = timed_apply("BAKED")  # maps: the map pipeline's strategies, its own table cold
        finally:
            if saved is None:
                os.environ.pop("SPECTRAL_SKIN_CACHE_DIR", None)
            else:
                os.environ["SPECTRAL_SKIN_CACHE_DIR"] = saved
    assert nodes.tagged_nodes(materials["LIVE"].node_tree, "live")
    return scene, materials, apply_s


def _render_s(scene: Any, samples: int) -> float:
    scene.cycles.samples = samples
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    return time.perf_counter() - t0


def render_times(variant: str, sizes: tuple[int, ...], samples_list: tuple[int, ...], repeats: int) -> dict[str, Any]:
    with tempfile.TemporaryDirectory(prefix="spectral_skin_live_report_") as folder:
        scene, materials, apply_s = _scene(variant, folder)
        slab = bpy.data.objects["Slab"]
        rows = []
        for size in sizes:
            scene.render.resolution_x = scene.render.resolution_y = size
            for samples in samples_list:
                times: dict[str, list[float]] = {"LIVE": [], "BAKED": []}
                for mode in times:  # warm-up: image loading and the first sync of each material
                    blender_scenes.assign(slab, materials[mode])
                    _render_s(scene, 1)
                for _ in range(repeats):
                    for mode in times:
                        blender_scenes.assign(slab, materials[mode])
                        times[mode].append(_render_s(scene, samples))
                live, baked = _median(times["LIVE"]), _median(times["BAKED"])
                row = {"size_px": size, "samples": samples, "live_s": live, "baked_s": baked,
                       "ratio": live / baked, "extra_ns_per_sample": (live - baked) / (size * size * samples) * 1e9,
                       "live_all_s": times["LIVE"], "baked_all_s": times["BAKED"]}
                rows.append(row)
                print(f"[live-report] {variant} {size}^2 {samples} spp: live {live:.3f} s, baked {baked:.3f} s, "
                      f"ratio {row['ratio']:.3f}, {row['extra_ns_per_sample']:+.1f} ns per sample", flush=True)
    return {"apply_s": apply_s, "renders": rows}


def markdown(data: dict[str, Any]) -> str:
    lines = [
        doc_stamp.stamp(COMMAND),
        "",
        "# Live mode: what it costs",
        "",
        "Live mode (docs/blender-addon.md, \"Live or Baked\") evaluates the skin in the shader: the \"Spectral Skin\" node group looks",
        "its inputs up in the core's shader table (docs/shader-table.md: the table's error and size). What that costs:",
        "the table's build at Apply, and render time per shading sample against the Baked material of the same skin.",
        "",
        f"Measured with Blender {data['blender']} (bpy), Cycles CPU with {data['threads']} threads, on "
        f"{data['machine']}; medians of {data['repeats']} (the shared 2-core machine of these reports, loaded by "
        "other jobs: treat the times as relative).",
        "",
        "## Shader table build",
        "",
        "Cold: an empty table cache (`SPECTRAL_SKIN_CACHE_DIR`), every node evaluated on all threads; cached: the",
        "same table again (read from the cache). The add-on builds it once per target and .blend (packed, reused by",
        "every material of that target).",
        "",
        "| method | image (W × H) | cold build | cached |",
        "|---|---|---:|---:|",
    ]
    for method, row in data["table"].items():
        lines.append(f"| {method} | {row['image'][0]} × {row['image'][1]} | {row['cold_s']:.2f} s | "
                     f"{row['warm_s'] * 1000:.1f} ms |")
    lines += ["", "Apply through the add-on (apply.apply_skins, one run each) in the render scenes below, with an empty",
              "table cache: Live (the table built), Live again (the table reused from the .blend: no evaluation),",
              "then Baked (for the map: the map pipeline's strategy, texture writing):", "",
              "| scene | Apply Live | Apply Live again | Apply Baked |", "|---|---:|---:|---:|"]
    for variant, result in data["renders"].items():
        a = result["apply_s"]
        lines.append(f"| {variant} | {a['LIVE']:.2f} s | {a['LIVE again']:.3f} s | {a['BAKED']:.3f} s |")
    lines += [
        "",
        "## Render time, Live vs Baked (Cycles)",
        "",
        "The flat slab of `tests/blender/test_live_mode.py` (Burley, white world), one material at a time, the",
        f"same scene; constants: caucasian as values; haemoglobin map: a {MAP_PX} × {MAP_PX} painted haemoglobin",
        "image (Live reads it and the table; Baked reads its albedo and radius textures). Time of",
        "`bpy.ops.render.render` alone after a warm-up render; extra per sample = (Live − Baked) / (pixels × samples):",
        "per camera sample, whose path evaluates the material at each surface hit and subsurface exit. The smallest",
        "frames are dominated by Cycles' per-render overhead (and can come out negative); the larger ones give the",
        "cost of the group. EEVEE is not measured here: its group reads four texels per slice (16 reads in all,",
        "against Cycles' 4) and computes the bilinear weights itself (docs/blender-addon.md, \"Live or Baked\").",
        "",
        "| scene | size | samples | Live | Baked | Live / Baked | extra per sample |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for variant, result in data["renders"].items():
        for row in result["renders"]:
            lines.append(f"| {variant} | {row['size_px']}² | {row['samples']} | {row['live_s']:.3f} s | "
                         f"{row['baked_s']:.3f} s | {row['ratio']:.3f} | {row['extra_ns_per_sample']:+.0f} ns |")
    big = [r for result in data["renders"].values() for r in result["renders"] if r["size_px"] >= 128]
    if big:
        ratios = [r["ratio"] for r in big]
        extra = [r["extra_ns_per_sample"] for r in big]
        builds = [row["cold_s"] for row in data["table"].values()]
        lines += ["", f"In short: at 128² and larger, Live renders in {min(ratios):.2f}–{max(ratios):.2f} × Baked's "
                  f"time ({min(extra):+.0f} to {max(extra):+.0f} ns per camera sample); the table's cold build "
                  f"({min(builds):.1f}–{max(builds):.1f} s) is paid once per target and .blend, and an Apply that "
                  "reuses it takes milliseconds."]
    lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="64 px and 16 samples only, one repeat")
    parser.add_argument("--out", type=Path, default=DEFAULT_DOC, help="the markdown report")
    parser.add_argument("--json", type=Path, default=None, help="the figures (default: docs/data/live_mode.json "
                        "beside the default report, none with --out)")
    args = parser.parse_args()
    repeats = 1 if args.quick else REPEATS
    sizes = (64,) if args.quick else SIZES_PX
    samples = (16,) if args.quick else SAMPLES
    data: dict[str, Any] = {
        "blender": bpy.app.version_string, "repeats": repeats,
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs", "command": COMMAND,
    }
    data["table"] = table_build_times(repeats)
    data["renders"] = {variant: render_times(variant, sizes, samples, repeats)
                       for variant in ("constants", "haemoglobin map")}
    data["threads"] = bpy.context.scene.render.threads
    doc_stamp.write_text(args.out, markdown(data))
    json_path = args.json if args.json is not None else (DEFAULT_JSON if args.out == DEFAULT_DOC else None)
    if json_path is not None:
        blender_scenes.write_json_atomically(json_path, data)
    print(f"[live-report] wrote {args.out}" + (f" and {json_path}" if json_path else ""))


if __name__ == "__main__":
    main()
