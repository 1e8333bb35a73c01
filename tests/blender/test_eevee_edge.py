"""EEVEE's subsurface edge with the core's EEVEE radius vs Cycles' Christensen-Burley edge of the same material.

EEVEE renders every subsurface method as a screen-space Burley convolution of length d = Radius x Scale / (4 pi) /
s(A_n) (docs/blender-targets.md, EEVEE); the core's EEVEE target multiplies the Cycles radius by s(A_n) so that the
EEVEE edge matches Cycles'. This module renders one half-lit edge per preset in EEVEE with the core's EEVEE radius
("compensated") and with the Cycles radius ("uncompensated"), and in Cycles (Burley, Cycles radius), and compares them.

The set-up (why each part is there: docs/blender-render-tests.md, "EEVEE edge"):

- No shadow map: a spot light with a hard cone (blend 0, radius 0, no shadow) lights the slab from far above; its
  cone meets the slab in a circle of radius EDGE_RADIUS_U around x = -EDGE_RADIUS_U, so the image sees the
  half-plane x < 0 lit. Both engines cut the cone exactly (test_lighting_edge_is_a_sharp_step); a sun's shadow-map
  edge was not reliable in EEVEE here (bpy 4.5 cast no shadow at all).
- The scene is built in a world unit of U mm chosen per preset so that the radii are near 1 unit: EEVEE stores
  Radius x Scale (in world units) in its g-buffer as 10-bit unorm of x/2 (x < 1) or 1 - 1/(2x), so a radius of a
  few mm in a metre scene is rounded to multiples of ~2 mm.
- The frame is wide and tall enough that every pixel measured has its whole EEVEE sample disk inside the image:
  EEVEE drops samples that fall outside the frame (and renormalises), which narrows the edge. The scene does not
  vary along y, so EEVEE's pixels are made tall (pixel aspect) to keep the image small.

Run: <venv>/bin/python -m pytest tests/blender/test_eevee_edge.py -q -s
"""

from __future__ import annotations

import functools
import math
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

from blender_scenes import (  # noqa: E402
    add_box,
    add_top_camera,
    assign,
    burley_edge_response,
    eevee_engine_id,
    fit_burley_edge,
    pixel_centres_x,
    principled_sss,
    read_exr,
    render,
    reset_scene,
    set_world,
)

BLENDER = "{}.{}".format(*bpy.app.version[:2])
# bpy 4.2's EEVEE subsurface convolution gives a different edge in each run here (Mesa llvmpipe), now and then with
# pixels 10^3 times too bright: its shader fills a group-shared cache and reads it without a barrier() (4.5 and later
# have one, and repeat to the last digit). The module is skipped there; the EEVEE radius of 4.2 is the same as 4.5's.
pytestmark = pytest.mark.skipif(
    bpy.app.version[:2] < (4, 5),
    reason="bpy 4.2's EEVEE subsurface convolution is not repeatable under Mesa llvmpipe (unsynchronised shared "
    "cache); see docs/blender-render-tests.md, EEVEE edge",
)
PRESETS = ("caucasian", "asian")

# Spot light (world units): height above the slab and radius of its lit disk on the slab. The image sees a piece of
# the disk's rim: across a sample disk of radius rho the rim departs from a straight line by rho^2 / (2 x 200 units),
# 0.02 mm for caucasian (rho = 4.8 mm), 0.006 mm for asian (1.4 mm), where the profile is 10^-3 of its peak; both
# engines see the same rim. The irradiance falls by 0.06 % per unit along x: Layout.irradiance divides it out.
SPOT_HEIGHT_U = 1000.0
EDGE_RADIUS_U = 200.0
# Irradiance at the edge (W per unit^2). EEVEE enlarges a light's radius to at least 2e-5 x its power (W)
# (eevee_light.cc, "minimum radius/energy ratio"); at 0.01 the spot's power is 1.3e5 W and that radius 2.7 units,
# small at 1000 units. At irradiance 1 the radius was 250 units and EEVEE's diffuse level came out 7 % low (4.2).
IRRADIANCE = 0.01

# The pixel grid, per preset: the image spans +-HALF_WIDTH_D x d_disk, where d_disk = max(Radius x Scale) /
# (4 pi s(1)) is the Burley length EEVEE draws its sample disk from (eevee_subsurface.cc, precompute_samples_location;
# its samples reach 13.8 d_disk: CDF 0.9924); every column is measured. A column's disk crosses both the edge and the
# frame's side only if |x| < 13.8 d_disk and |x| > HALF_WIDTH_D d_disk - 13.8 d_disk: none at 28.
HALF_WIDTH_D = 28.0
WIDTH_PX = 312  # 0.18 d_disk per pixel: caucasian 0.062 mm (its bluest d is 1.3 px), asian 0.018 mm (1.0 px)
# EEVEE image: 24 rows of pixels 8 times as tall as wide (192 columns' worth), the central 4 rows measured: their
# distance to the top and bottom is 80 columns = 14.4 d_disk, more than the disk's reach.
EEVEE_ROWS = 24
EEVEE_PIXEL_ASPECT = 8.0
EEVEE_BAND_ROWS = 4
CYCLES_ROWS = 8

# Sample counts. EEVEE: render samples (each draws a new rotation and radial jitter of its 16-sample disk).
EEVEE_TAA = 16
CYCLES_SPP = 1024
LIGHTING_TAA = 4
LIGHTING_SPP = 16


def _s(albedo_n):
    """Christensen & Burley 2015, eq. 6 (what EEVEE divides Radius x Scale / (4 pi) by)."""
    return 1.9 - albedo_n + 3.5 * (albedo_n - 0.8) ** 2


class Layout:
    """The preset's scene scale and pixel grid."""

    def __init__(self, eevee_radius_mm: np.ndarray, width_px: int = WIDTH_PX):
        # mm per world unit: the EEVEE radii lie within a factor 1.9 of 1 unit, where EEVEE's g-buffer rounds them by
        # <= 0.2 % (the Cycles radii, down to 0.30 units, by <= 0.35 %).
        self.unit_mm = math.sqrt(float(eevee_radius_mm.max() * eevee_radius_mm.min()))
        self.d_disk_mm = float(eevee_radius_mm.max()) / (4 * math.pi * _s(1.0))
        self.width_mm: float = 2 * HALF_WIDTH_D * self.d_disk_mm
        self.width_px = width_px
        self.pitch_mm = self.width_mm / width_px
        self.x_mm = pixel_centres_x(self.width_mm, width_px)

    def irradiance(self) -> np.ndarray:
        """Irradiance at each column's centre (y = 0), from the spot's inverse square law and cosine: E = I H / r^3."""
        x_u = self.x_mm / self.unit_mm
        cos_edge = SPOT_HEIGHT_U / math.hypot(SPOT_HEIGHT_U, EDGE_RADIUS_U)
        intensity = IRRADIANCE * SPOT_HEIGHT_U**2 / cos_edge**3
        dist = np.hypot(x_u + EDGE_RADIUS_U, SPOT_HEIGHT_U)
        return intensity * SPOT_HEIGHT_U / dist**3


def _build_scene(layout: Layout, material: Material, rows: int, pixel_aspect_y: float):
    """A fresh scene: black world, a 400 x 400 x 40 unit slab with the material (top face z = 0), the hard-edged
    spot, and an orthographic top camera over the layout's columns."""
    scene = reset_scene()
    set_world(scene, strength=0.0, color=(0.0, 0.0, 0.0))
    slab = add_box("Slab", -200.0, 200.0, -200.0, 200.0, -40.0, 0.0)
    assign(slab, material.make(layout.unit_mm))
    half_angle = math.atan(EDGE_RADIUS_U / SPOT_HEIGHT_U)
    light = bpy.data.lights.new("Spot", type="SPOT")
    light.spot_size = 2 * half_angle
    light.spot_blend = 0.0
    light.shadow_soft_size = 0.0
    light.use_shadow = False
    light.use_custom_distance = True  # EEVEE: no influence cut-off within the scene
    light.cutoff_distance = 100 * SPOT_HEIGHT_U
    # Power P gives intensity P / (4 pi) per steradian in both engines; at the edge E = I cos^3 / H^2.
    light.energy = 4 * math.pi * IRRADIANCE * SPOT_HEIGHT_U**2 / math.cos(half_angle) ** 3
    spot = bpy.data.objects.new("Spot", light)
    spot.location = (-EDGE_RADIUS_U, 0.0, SPOT_HEIGHT_U)  # points down -z
    scene.collection.objects.link(spot)
    cam = add_top_camera(scene, ortho_scale=layout.width_mm / layout.unit_mm, width=layout.width_px, height=rows, z=10.0)
    cam.data.clip_start = 0.1
    cam.data.clip_end = 100.0
    scene.render.pixel_aspect_y = pixel_aspect_y
    return scene


@dataclass
class Material:
    """A Principled Burley material (as the render tests' principled_sss), made in each fresh scene."""

    base_color: Sequence[float] | np.ndarray
    radius_mm: Sequence[float] | np.ndarray
    subsurface: bool = True

    def make(self, unit_mm: float):
        """The material with Radius in world units (Scale 1)."""
        mat, bsdf = principled_sss(
            "Skin", "BURLEY", [float(c) for c in self.base_color], [r / unit_mm for r in self.radius_mm]
        )
        bsdf.inputs["Subsurface Scale"].default_value = 1.0
        if not self.subsurface:
            bsdf.inputs["Subsurface Weight"].default_value = 0.0
        return mat


def _render_eevee(scene, samples: int) -> np.ndarray:
    """EEVEE render to a float EXR; returns RGB (H, W, 3) float64."""
    scene.render.engine = eevee_engine_id()
    eevee = scene.eevee
    eevee.taa_render_samples = samples
    for name in ("use_shadows", "use_raytracing", "use_gtao"):  # nothing here casts shadows or needs them
        if hasattr(eevee, name):
            setattr(eevee, name, False)
    scene.render.filter_size = 0.01  # pixel-centre film filter, as Cycles' filter_width 0.01 in render()
    with tempfile.TemporaryDirectory(prefix="spectral_skin_eevee_") as tmp:
        path = os.path.join(tmp, "render.exr")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        img = read_exr(path)
    return img[:, :, :3].astype(np.float64)


def _eevee_profile(layout: Layout, material: Material, samples: int) -> np.ndarray:
    """piL / E per column (W, 3) in EEVEE, over the central rows."""
    scene = _build_scene(layout, material, EEVEE_ROWS, EEVEE_PIXEL_ASPECT)
    img = _render_eevee(scene, samples)
    lo = (EEVEE_ROWS - EEVEE_BAND_ROWS) // 2
    return math.pi * img[lo : lo + EEVEE_BAND_ROWS].mean(axis=0) / layout.irradiance()[:, None]


def _cycles_profile(layout: Layout, material: Material, samples: int) -> np.ndarray:
    """piL / E per column (W, 3) in Cycles (pixel-centre sampling), rows averaged."""
    scene = _build_scene(layout, material, CYCLES_ROWS, 1.0)
    img = render(scene, samples=samples, filter_width=0.01)
    return math.pi * img.mean(axis=0) / layout.irradiance()[:, None]


def _targets(preset: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Base Color, Cycles Burley Radius x Scale mm, EEVEE Radius x Scale mm) from the core, for this Blender."""
    out = {}
    for engine in ("cycles", "eevee"):
        res = spectral_skin.evaluate(preset=preset, outputs=("albedo", "radius"), blender=BLENDER, engine=engine)
        assert res["target"]["engine"] == engine
        out[engine] = res["methods"]["burley"]
    base = np.asarray(out["cycles"]["base_color"], dtype=np.float64)
    np.testing.assert_allclose(out["eevee"]["base_color"], base, rtol=1e-12)
    return (
        base,
        np.asarray(out["cycles"]["subsurface_radius_mm"], dtype=np.float64),
        np.asarray(out["eevee"]["subsurface_radius_mm"], dtype=np.float64),
    )


# ---------------------------------------------------------------------------------------------------------------
# 1. The lighting edge itself (diffuse, Subsurface Weight 0): a step at x = 0 in both engines


def test_lighting_edge_is_a_sharp_step():
    """A white Lambertian slab (Subsurface Weight 0) under the spot: every column left of x = 0 lit at the analytic
    irradiance, every column right of it black, i.e. the lighting edge is sharp to within one pixel (0.062 mm here,
    against an edge profile 16 d = 5.5 mm wide)."""
    _, _, eevee_radius = _targets("caucasian")
    layout = Layout(eevee_radius)
    white = Material([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], subsurface=False)
    profiles = {
        "cycles": _cycles_profile(layout, white, LIGHTING_SPP),
        "eevee": _eevee_profile(layout, white, LIGHTING_TAA),
    }
    lit, dark = layout.x_mm < 0, layout.x_mm > 0
    for engine, prof in profiles.items():
        level = prof[lit].mean(axis=0)
        print(
            f"\n[eevee-edge/lighting] Blender {bpy.app.version_string} {engine}: lit piL/E {np.round(level, 5)} "
            f"(min {prof[lit].min():.5f}, max {prof[lit].max():.5f}), dark max {prof[dark].max():.2e}"
        )
        # every lit column at one level (the step is not smeared into the lit side), every dark column black
        np.testing.assert_allclose(prof[lit], np.broadcast_to(level, prof[lit].shape), rtol=5e-3)
        assert prof[dark].max() < 1e-4
        # the level: Cycles exactly the analytic irradiance; EEVEE 0.6 % low (measured; see the docs)
        np.testing.assert_allclose(level, 1.0, atol=1e-3 if engine == "cycles" else 1.5e-2)


# ---------------------------------------------------------------------------------------------------------------
# 2. The subsurface edge: EEVEE (core's EEVEE radius, and the Cycles radius) vs Cycles Burley

# Bounds (measured figures and commands: docs/blender-render-tests.md, "EEVEE edge").
# rms over the image of (EEVEE scaled to Cycles' flat level - Cycles) / A, per channel, compensated radius.
EDGE_RMS_BOUND = 0.004
# EEVEE's flat subsurface level / Cycles': measured 1.4-3.6 % low here, the same with either radius (0.6 % of it is
# EEVEE's lighting level, see test_lighting_edge_is_a_sharp_step; the rest appears with subsurface only: EEVEE
# convolves radiance it stores as 11/11/10-bit floats, SUBSURFACE_RADIANCE_FORMAT).
LEVEL_BOUND = 0.05
# Fitted Burley d of the (level-matched) EEVEE edge / the Cycles d: 1 with the compensated radius, 1 / s(A_n)
# without; within this relative tolerance.
WIDTH_RTOL = 0.03
# The compensation must lower the edge rms by at least this (in % of A) in every channel it changes by >= 10 %.
COMPENSATION_MARGIN = 0.1
# EEVEE draws one set of disk samples per pixel from the material's largest radius and weights them per channel, so a
# channel whose radius is a small fraction of the largest is convolved by the few samples that land within its reach:
# its edge is then EEVEE's sampling, not the radius. Channels below this fraction of their material's largest radius
# are printed but not asserted. Measured in 5.0 with the exact profile shapes (asian: Cycles radius 1.207, 0.334,
# 0.103 mm): blue at 0.085 of red (uncompensated) fitted 0.557 of Cycles' d where 1 / s(A_n) = 0.430, at 0.19
# (compensated) rms 0.51-0.53 % of A (bound 0.4 %) at 312 and at 656 columns alike; the channels at 0.24 and above
# (caucasian's blue, asian's green) meet every bound, as asian's blue at 0.19 did before the exact shapes.
RESOLVED_RADIUS_FRACTION = 0.2


def _resolved(radius_mm: np.ndarray) -> np.ndarray:
    """The channels whose radius EEVEE's shared sample disk resolves (see RESOLVED_RADIUS_FRACTION)."""
    return radius_mm >= RESOLVED_RADIUS_FRACTION * radius_mm.max()


@functools.cache
def _edges(preset: str) -> dict:
    """Render (once per preset per session) the three edges and compute their figures."""
    base, cycles_radius, eevee_radius = _targets(preset)
    layout = Layout(eevee_radius)
    x = layout.x_mm
    d_mm = cycles_radius / (4 * math.pi)
    cycles = _cycles_profile(layout, Material(base, cycles_radius), CYCLES_SPP)
    eevee = {
        "compensated": _eevee_profile(layout, Material(base, eevee_radius), EEVEE_TAA),
        "uncompensated": _eevee_profile(layout, Material(base, cycles_radius), EEVEE_TAA),
    }
    # Columns whose whole sample disk is lit (x < -14 d_disk): the flat level.
    flat = x < -0.5 * HALF_WIDTH_D * layout.d_disk_mm
    out = {
        "base": base,
        "s": _s(base / base.max()),
        "x_mm": x,
        "layout": layout,
        "cycles_level": cycles[flat].mean(axis=0) / base,
        "cycles_radius": cycles_radius,
        "eevee_radius": eevee_radius,
    }
    model = np.stack([burley_edge_response(x, d_mm[c], base[c]) for c in range(3)], axis=1)
    out["cycles_vs_model"] = np.sqrt(np.mean((cycles - model) ** 2, axis=0)) / base
    for name, prof in eevee.items():
        level = prof[flat].mean(axis=0) / cycles[flat].mean(axis=0)
        matched = prof / level
        out[name] = {
            "level": level,
            "rms_raw": np.sqrt(np.mean((prof - cycles) ** 2, axis=0)) / base,
            "rms": np.sqrt(np.mean((matched - cycles) ** 2, axis=0)) / base,
            "rms_model": np.sqrt(np.mean((matched - model) ** 2, axis=0)) / base,
            "width": np.array([fit_burley_edge(x, matched[:, c], 0.05 * d_mm[c], 5 * d_mm[c])[0] for c in range(3)])
            / d_mm,
        }
    pct = lambda v: np.array2string(np.asarray(v) * 100, precision=3)  # noqa: E731
    print(
        f"\n[eevee-edge] Blender {bpy.app.version_string} {preset}: A {np.array2string(base, precision=4)}, Radius "
        f"Cycles {np.array2string(cycles_radius, precision=4)} mm, EEVEE {np.array2string(eevee_radius, precision=4)}"
        f" mm (s(A_n) {np.array2string(out['s'], precision=3)}); unit {layout.unit_mm:.3f} mm, {WIDTH_PX} px over "
        f"{layout.width_mm:.2f} mm; Cycles {CYCLES_SPP} spp, EEVEE {EEVEE_TAA} samples"
    )
    print(
        f"[eevee-edge]   Cycles vs Burley model rms/A {pct(out['cycles_vs_model'])} %, flat level/A "
        f"{np.array2string(out['cycles_level'], precision=4)}"
    )
    for name in eevee:
        r = out[name]
        print(
            f"[eevee-edge]   EEVEE {name:13s}: rms/A vs Cycles {pct(r['rms_raw'])} % (level-matched "
            f"{pct(r['rms'])} %; vs the Burley model {pct(r['rms_model'])} %); flat level / Cycles "
            f"{np.array2string(r['level'], precision=4)}; fitted d / Cycles d {np.array2string(r['width'], precision=3)}"
        )
    return out


@pytest.mark.parametrize("preset", PRESETS)
def test_eevee_edge_matches_cycles(preset):
    """With the core's EEVEE radius, EEVEE's edge (scaled to Cycles' flat level) is Cycles' Burley edge within
    EDGE_RMS_BOUND per channel EEVEE resolves (RESOLVED_RADIUS_FRACTION), and its fitted Burley d is Cycles' d; the
    flat level of every channel within LEVEL_BOUND."""
    out = _edges(preset)
    comp = out["compensated"]
    ok = _resolved(out["eevee_radius"])
    assert np.all(comp["rms"][ok] < EDGE_RMS_BOUND), comp["rms"]
    np.testing.assert_allclose(comp["width"][ok], 1.0, rtol=WIDTH_RTOL)
    assert np.all(np.abs(comp["level"] - 1.0) < LEVEL_BOUND), comp["level"]


@pytest.mark.parametrize("preset", PRESETS)
def test_eevee_compensation_is_seen(preset):
    """Without the compensation EEVEE's edge is narrower by s(A_n) (its fitted d is 1 / s(A_n) of Cycles'), and the
    compensation brings the edge closer to Cycles by at least COMPENSATION_MARGIN in every channel it changes by
    10 % or more; in the channels EEVEE resolves with either radius (RESOLVED_RADIUS_FRACTION)."""
    out = _edges(preset)
    comp, plain = out["compensated"], out["uncompensated"]
    ok = _resolved(out["cycles_radius"])
    np.testing.assert_allclose(plain["width"][ok], 1.0 / out["s"][ok], rtol=WIDTH_RTOL)
    changed = (out["s"] >= 1.1) & ok & _resolved(out["eevee_radius"])
    assert changed.any()
    gain = plain["rms"] - comp["rms"]
    assert np.all(gain[changed] > COMPENSATION_MARGIN / 100), gain
