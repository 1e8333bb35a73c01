"""The EEVEE edge scene, shared by test_eevee_edge.py and test_live_eevee_edge.py: one half-lit edge rendered in
EEVEE and in Cycles (Burley), its layout in a world unit near the radii, and the core's targets for it.

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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")
spectral_skin = pytest.importorskip("spectral_skin")

import blender_scenes  # noqa: E402
from blender_scenes import (  # noqa: E402
    add_box,
    add_top_camera,
    assign,
    pixel_centres_x,
    principled_sss,
    render,
    reset_scene,
    set_world,
)

BLENDER = "{}.{}".format(*bpy.app.version[:2])
# bpy 4.2's EEVEE subsurface convolution gives a different edge in each run here (Mesa llvmpipe), now and then with
# pixels 10^3 times too bright: its shader fills a group-shared cache and reads it without a barrier() (4.5 and later
# have one, and repeat to the last digit). The modules that render EEVEE edges are skipped there (their pytestmark);
# the EEVEE radius of 4.2 is the same as 4.5's.
REPEATABLE_EEVEE_ONLY = pytest.mark.skipif(
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


def s_of_albedo(albedo_n):
    """Christensen & Burley 2015, eq. 6 (what EEVEE divides Radius x Scale / (4 pi) by)."""
    return 1.9 - albedo_n + 3.5 * (albedo_n - 0.8) ** 2


class Layout:
    """The preset's scene scale and pixel grid."""

    def __init__(self, eevee_radius_mm: np.ndarray, width_px: int = WIDTH_PX):
        # mm per world unit: the EEVEE radii lie within a factor 1.9 of 1 unit, where EEVEE's g-buffer rounds them by
        # <= 0.2 % (the Cycles radii, down to 0.30 units, by <= 0.35 %).
        self.unit_mm = math.sqrt(float(eevee_radius_mm.max() * eevee_radius_mm.min()))
        self.d_disk_mm = float(eevee_radius_mm.max()) / (4 * math.pi * s_of_albedo(1.0))
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


def build_scene(layout: Layout, material: Material, rows: int, pixel_aspect_y: float):
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


def render_eevee(scene, samples: int) -> np.ndarray:
    """EEVEE render (blender_scenes.render_eevee) with no shadows, ray tracing or ambient occlusion and a pixel-centre
    film filter; returns RGB (H, W, 3) float64."""
    for name in ("use_shadows", "use_raytracing", "use_gtao"):  # nothing here casts shadows or needs them
        if hasattr(scene.eevee, name):
            setattr(scene.eevee, name, False)
    scene.render.filter_size = 0.01  # pixel-centre film filter, as Cycles' filter_width 0.01 in render()
    return blender_scenes.render_eevee(scene, samples)


def eevee_profile(layout: Layout, material: Material, samples: int) -> np.ndarray:
    """piL / E per column (W, 3) in EEVEE, over the central rows."""
    scene = build_scene(layout, material, EEVEE_ROWS, EEVEE_PIXEL_ASPECT)
    img = render_eevee(scene, samples)
    lo = (EEVEE_ROWS - EEVEE_BAND_ROWS) // 2
    return math.pi * img[lo : lo + EEVEE_BAND_ROWS].mean(axis=0) / layout.irradiance()[:, None]


def cycles_profile(layout: Layout, material: Material, samples: int) -> np.ndarray:
    """piL / E per column (W, 3) in Cycles (pixel-centre sampling), rows averaged."""
    scene = build_scene(layout, material, CYCLES_ROWS, 1.0)
    img = render(scene, samples=samples, filter_width=0.01)
    return math.pi * img.mean(axis=0) / layout.irradiance()[:, None]


def core_targets(preset: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
