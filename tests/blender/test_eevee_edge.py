"""EEVEE's subsurface edge with the core's EEVEE radius vs Cycles' Christensen-Burley edge of the same material.

EEVEE renders every subsurface method as a screen-space Burley convolution of length d = Radius x Scale / (4 pi) /
s(A_n) (docs/blender-targets.md, EEVEE); the core's EEVEE target multiplies the Cycles radius by s(A_n) so that the
EEVEE edge matches Cycles'. This module renders one half-lit edge per preset in EEVEE with the core's EEVEE radius
("compensated") and with the Cycles radius ("uncompensated"), and in Cycles (Burley, Cycles radius), and compares them.

The scene and why each part of it is there: eevee_scene.py (and docs/blender-render-tests.md, "EEVEE edge").

Run: <venv>/bin/python -m pytest tests/blender/test_eevee_edge.py -q -s
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")

from blender_scenes import burley_edge_response, fit_burley_edge  # noqa: E402
from eevee_scene import (  # noqa: E402
    CYCLES_SPP,
    EEVEE_TAA,
    HALF_WIDTH_D,
    LIGHTING_SPP,
    LIGHTING_TAA,
    PRESETS,
    REPEATABLE_EEVEE_ONLY,
    WIDTH_PX,
    Layout,
    Material,
    core_targets,
    cycles_profile,
    eevee_profile,
    s_of_albedo,
)

pytestmark = REPEATABLE_EEVEE_ONLY


# ---------------------------------------------------------------------------------------------------------------
# 1. The lighting edge itself (diffuse, Subsurface Weight 0): a step at x = 0 in both engines


def test_lighting_edge_is_a_sharp_step():
    """A white Lambertian slab (Subsurface Weight 0) under the spot: every column left of x = 0 lit at the analytic
    irradiance, every column right of it black, i.e. the lighting edge is sharp to within one pixel (0.062 mm here,
    against an edge profile 16 d = 5.5 mm wide)."""
    _, _, eevee_radius = core_targets("caucasian")
    layout = Layout(eevee_radius)
    white = Material([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], subsurface=False)
    profiles = {
        "cycles": cycles_profile(layout, white, LIGHTING_SPP),
        "eevee": eevee_profile(layout, white, LIGHTING_TAA),
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
    base, cycles_radius, eevee_radius = core_targets(preset)
    layout = Layout(eevee_radius)
    x = layout.x_mm
    d_mm = cycles_radius / (4 * math.pi)
    cycles = cycles_profile(layout, Material(base, cycles_radius), CYCLES_SPP)
    eevee = {
        "compensated": eevee_profile(layout, Material(base, eevee_radius), EEVEE_TAA),
        "uncompensated": eevee_profile(layout, Material(base, cycles_radius), EEVEE_TAA),
    }
    # Columns whose whole sample disk is lit (x < -14 d_disk): the flat level.
    flat = x < -0.5 * HALF_WIDTH_D * layout.d_disk_mm
    out = {
        "base": base,
        "s": s_of_albedo(base / base.max()),
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
