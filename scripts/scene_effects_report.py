#!/usr/bin/env python3
"""When can the add-on drop subsurface scattering? Renders a Burley skin slab with the caucasian preset's values
(Base Color and Subsurface Radius from the core) across a sunlit shadow edge, seen with the largest radius at several
sizes in pixels, once with subsurface (Subsurface Weight 1) and once as plain diffuse (Subsurface Weight 0, same Base
Color: the decision of blender_addon/core/scene.py), and writes the differences and render times to
docs/scene-effects.md.

    .venv-blender/5.0/bin/python scripts/scene_effects_report.py            # 6 footprints, 96x16 px, 512 spp
    .venv-blender/5.0/bin/python scripts/scene_effects_report.py --quick --out /tmp/se.md   # 3 footprints, 128 spp

Scene: tests/blender/blender_scenes.shadow_edge_scene (a thick slab under a sun of irradiance 1 W/m^2 from straight
above, a black world, and a black occluder, invisible to the camera, casting a hard shadow over x > 0), orthographic
top camera, Cycles CPU, fixed seed, no denoising, Blender's default pixel filter (Blackman-Harris 1.5 px). A uniformly
lit slab would show no difference at all (the Base Color is the total reflectance either way): the shadow edge is
where subsurface scattering shows, so the figures are the worst case of a sharp light-shadow edge.

Figures per footprint, relative to the albedo (per channel, the worst channel): the mean absolute pixel difference
over the image, and the largest absolute difference of the rows' mean (the edge profile, where the pixel noise is
averaged over rows). The chosen threshold is the largest radius in pixels at which the profile difference stays
under ``--bound`` (default 0.5 % of the albedo: the issue's example bound, applied to the worst column rather than
to the image mean, which a narrow edge hardly moves) and the mean under 0.5 %.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "blender"))
sys.path.insert(0, str(ROOT))

MEAN_BOUND = 0.005  # mean |difference| / albedo over the image: the example bound


def _render(scene, blender_scenes, ortho_mm: float, width: int, height: int, samples: int, weight: float,
            color, radius_mm, seed: int = 1) -> tuple[np.ndarray, float]:
    blender_scenes.reset_scene()
    scene = blender_scenes._bpy().context.scene
    material, bsdf = blender_scenes.principled_sss("Skin", "BURLEY", color, radius_mm)
    bsdf.inputs["Subsurface Weight"].default_value = weight
    blender_scenes.shadow_edge_scene(scene, material, ortho_mm, width, height)
    blender_scenes.render(scene, samples=1)  # warm-up: kernel loading and the first sync are not timed
    start = time.perf_counter()
    image = blender_scenes.render(scene, samples=samples, seed=seed)
    return np.pi * image, time.perf_counter() - start


def _differences(a: np.ndarray, b: np.ndarray, albedo: np.ndarray) -> dict[str, float]:
    """|a - b| / albedo, worst channel: the mean over the image of the rows' mean (the edge profile, pixel noise
    averaged over rows), its largest value, and the largest single pixel."""
    profile = np.abs(a.mean(axis=0) - b.mean(axis=0)) / albedo
    return {"mean": float(profile.mean(axis=0).max()), "profile": float(profile.max()),
            "max": float((np.abs(a - b) / albedo).max())}

# The rest of the report: what the analysis decides besides dropping subsurface (no measurement of this script).
DECISIONS_TEXT = """## Thin and open geometry: which subsurface method

The analysis also recommends a subsurface method per object using the material (the decision `subsurface method`;
figures per object: `thickness_mm`, `thickness_radii`, `closed`, `open_edges`, `recommended`, `reason`). It is a
recommendation: the method stays the one chosen on the material, because the method is the artist's choice (it
changes the look and the render time) and the Auto / On / Off overrides switch effects, not methods. Its check box
(`enabled`) says whether the material's method suits every object; the reason names the objects it does not suit.

- Thickness: the smallest dimension of the object's evaluated bounding box (object axes, with its scale and
  modifiers) × the scene's unit scale, in mm, at the current frame (`scene_facts.py`). Thinner than
  `THIN_RADII` = 3 × the largest Subsurface Radius × Scale (over the animation's frames when it is animated): a
  random walk. Burley's profile is a half-space's; most of its energy lies within one radius, so a part one or two
  radii thick lets light through that Burley projects back onto the near surface; at three radii the half-space
  is a fair model. The 3 is a rule of thumb, not a measurement.
- Closed: every edge of the evaluated mesh is shared by exactly two faces (counted from the faces' loops). An open
  mesh (or one with edges of three or more faces) gets Burley recommended: a random walk leaves the volume through
  the holes and loses light. Thin and open: Burley, with the advice to close the mesh and use a random walk.
- No advice where subsurface is off (dropped or forced off), in EEVEE (every method renders as its screen-space
  blur), or with no object using the material.

Open: the bounding box sees the whole object, not its parts: a head's ears and nostrils are thin parts of a thick
object and are not found (that needs a per-part measure, e.g. ray-cast thickness over the surface).

## Animated parameters

A Spectral Skin parameter (melanin, melanin blend, haemoglobin, oiliness) keyframed or driven on the material
(decision `animation`; figures `parameters`, `first_frame`, `last_frame`, `evaluations`):

- Constant-parameter material: the values at every frame of the scene's range are part of the plan
  (`plan["animation"]`: Base Color, Subsurface Radius, Specular IOR Level per frame), each computed by the core
  (`spectral_skin.evaluate`, once per distinct parameter set) and changed by the same decisions, which hold over
  every frame (subsurface from the largest radius over the frames, specular dropped only if the oiliness is zero at
  every frame). Apply stores them on the material (custom property `spectral_skin_frames`, saved with the .blend);
  a persistent `frame_change_pre` handler (`blender_addon/frame_values.py`, bpy only) sets them on the add-on's
  Principled BSDF at each frame change. The add-on installs it when registered; the headless render
  script (`scripts/render_blend.py`, not part of the extension) loads it from its file and installs it, so a render
  node needs neither the add-on nor `spectral_skin`. Frames
  outside the range take the nearest frame's values. An F-curve is evaluated directly; a driver (which may read
  anything) by setting each frame of the range. Muted curves are left out; NLA strips are not read.
- Material with parameter maps: the maps are computed once, with the values at the current frame; the decision says
  that its animation needs per-frame maps or the live shader (`enabled` false).
- The batch apply follows the material's animation for an animated parameter, whatever constant it was given.

Acceptance (`tests/blender/test_scene_effects.py::test_keyframed_haemoglobin_renders_the_cores_albedo_at_two_frames`,
run with `-s` to print the figures): haemoglobin keyframed 0.005 at frame 1 and 0.05 at frame 2 on a Burley flat
slab under a white world, applied through the operator, saved, and rendered at frames 1 and 2 by
`scripts/render_blend.py` with the add-on unregistered (512 samples, central 32 × 32 of 64 × 64 px): the rendered mean
is the core's albedo of each frame within 0.2 % (measured: −0.005, −0.004, +0.009 % at frame 1; −0.022, +0.008,
+0.014 % at frame 2, the same in Blender 4.2.23, 5.0.1 and 5.3.0). Without the handler frame 2 renders frame 1's
albedo (+22 %, +33 %, +9 %).
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 footprints, 128 spp")
    parser.add_argument("--out", default=str(ROOT / "docs" / "scene-effects.md"))
    parser.add_argument("--bound", type=float, default=0.005, help="edge-profile bound, fraction of the albedo")
    args = parser.parse_args(argv)

    import blender_scenes
    import bpy
    import spectral_skin

    from blender_addon.core import scene as analysis

    radii_px = [0.25, 0.5, 1.0] if args.quick else [0.1, 0.25, 0.5, 1.0, 2.0, 4.0]
    samples = 128 if args.quick else 512
    width, height = (96, 32) if args.quick else (96, 64)
    burley = spectral_skin.evaluate(preset="caucasian", blender=bpy.app.version)["methods"]["burley"]
    albedo = np.asarray(burley["base_color"], dtype=np.float64)
    radius_mm = np.asarray(burley["subsurface_radius_mm"], dtype=np.float64)
    largest = float(radius_mm.max())
    rows = []
    for px in radii_px:
        footprint = largest / px
        full, t_full = _render(None, blender_scenes, footprint * width, width, height, samples, 1.0, albedo, radius_mm)
        plain, t_plain = _render(None, blender_scenes, footprint * width, width, height, samples, 0.0, albedo, radius_mm)
        rows.append({"px": px, "footprint_mm": footprint, **_differences(full, plain, albedo), "t_full": t_full,
                     "t_plain": t_plain})
        if px == radii_px[0]:  # the noise floor: the full render against itself with another seed
            again, _ = _render(None, blender_scenes, footprint * width, width, height, samples, 1.0, albedo,
                               radius_mm, seed=2)
            noise = _differences(full, again, albedo)
        print(f"{px:5.2f} px  footprint {footprint:6.2f} mm  mean {rows[-1]['mean']:.4f}  profile "
              f"{rows[-1]['profile']:.4f}  max {rows[-1]['max']:.4f}  {t_full:.2f} s vs {t_plain:.2f} s", flush=True)
    print(f"noise floor: mean {noise['mean']:.4f} profile {noise['profile']:.4f}")
    passing = [r["px"] for r in rows if r["mean"] < MEAN_BOUND and r["profile"] < args.bound]
    below = [p for p in passing if all(r["px"] in passing for r in rows if r["px"] <= p)]
    chosen = max(below) if below else None

    command = "scripts/scene_effects_report.py" + (" --quick" if args.quick else "")
    lines = [
        "# Scene effects: when subsurface scattering can be dropped",
        "",
        f"Regenerate: `.venv-blender/5.0/bin/python {command}` (Blender {bpy.app.version_string}, Cycles CPU, "
        f"{os.cpu_count()} CPUs, {samples} samples, {width}×{height} px; times are of the render call alone, after "
        "a warm-up render).",
        "",
        "The add-on's scene analysis (`blender_addon/core/scene.py`) drops subsurface scattering of a material when "
        "its largest Subsurface Radius × Scale is under a threshold in pixels of the smallest pixel footprint on the "
        "skin, over every object using the material, every rendering camera and the sampled frames. The material then "
        "renders plain diffuse (Subsurface Weight 0) with the skin's total diffuse reflectance as Base Color, so the "
        "total reflectance is exact and only the blur is lost.",
        "",
        "Measured on a Burley slab with the caucasian preset's values (albedo "
        f"{', '.join(f'{a:.4f}' for a in albedo)}, radius {', '.join(f'{r:.3f}' for r in radius_mm)} mm) across a "
        "hard shadow edge (`shadow_edge_scene` of tests/blender/blender_scenes.py: a sun from straight above, a black "
        "occluder casting the shadow, a black world): the worst case, a sharp edge of light; a uniformly lit slab "
        "shows no difference at all. Differences are |full − plain| / albedo, worst channel, of the rows' mean (the "
        f"edge profile: pixel noise averaged over {height} rows): *mean* over the image's columns, *edge profile* "
        "the largest column; *max pixel* the largest single pixel (mostly the subsurface render's noise). Noise "
        f"floor (the full render against itself with another seed, at {radii_px[0]:g} px): mean "
        f"{100 * noise['mean']:.2f} %, edge profile {100 * noise['profile']:.2f} %, max pixel "
        f"{100 * noise['max']:.1f} %.",
        "",
        "| largest radius (px) | footprint (mm/px) | mean | edge profile | max pixel | render full (s) | render plain (s) |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(f"| {r['px']:g} | {r['footprint_mm']:.2f} | {100 * r['mean']:.2f} % | {100 * r['profile']:.2f} % "
                     f"| {100 * r['max']:.1f} % | {r['t_full']:.2f} | {r['t_plain']:.2f} |")
    lines += [
        "",
        f"Bound: mean under {100 * MEAN_BOUND:g} % and edge profile under {100 * args.bound:g} % of the albedo. "
        + (f"Largest radius passing (with every smaller one): **{chosen:g} px**." if chosen is not None
           else "No footprint passes."),
        f"The add-on's threshold (`SUBSURFACE_MIN_RADIUS_PX`): {analysis.SUBSURFACE_MIN_RADIUS_PX:g} px.",
        "",
        "Reading: the image mean hardly moves even at 4 px (the blur moves light across a narrow edge and keeps "
        "it), so the edge profile's worst column decides; at and below the threshold it stays within the noise "
        "floor, and the largest single-pixel differences are the subsurface render's own noise. Render times: on "
        "this flat slab lit by one sun, Burley costs little more than a diffuse surface, and the two times differ "
        "by about the run-to-run variation of the shared machine; the saving on a head-sized object with parameter "
        "maps, and the apply time with and without the analysis, are not measured yet. Blender 4.2's Cycles "
        "itself renders a subsurface channel under about a quarter pixel as diffuse "
        "([blender-render-tests.md](blender-render-tests.md#what-differs-between-versions-as-the-tests-met-it)): "
        "the same threshold, found independently; 4.5 and later render the blur, which is what the table measures.",
        "",
        DECISIONS_TEXT,
    ]
    Path(args.out).write_text("\n".join(lines))
    print(f"wrote {args.out}; chosen {chosen}")
    return 0


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    os._exit(status)
