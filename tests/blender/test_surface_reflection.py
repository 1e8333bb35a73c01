"""The measured skin surface as Blender renders it (issue 24): the Principled inputs of
``evaluate(surface="measured")`` (base lobe plus Coat, docs/model.md "Principled mapping of the measured surface")
on flat planes with Base Color black under a uniform white world, seen along the normal: the rendered
normal-incidence reflection against the two-lobe model's E(0) (``surface_albedo(0)``, the core's quadrature of the
model's BRDF, checked against a numpy transcription in tests/python/test_surface_brdf.py), and inside the 0.024-0.05
a dielectric skin surface reflects at every oiliness; the paper's surface, for contrast, reflects nothing when dry.

The level of the base lobe was measured in Cycles 5.0 and EEVEE 5.0 (scripts/calibration/measure_coat_level.py);
this test renders in the running Blender, so it also bounds the other versions' difference: Cycles within 1 %
(measured: within 0.3 % in 4.2 and 5.3). EEVEE within 2.5 %: it renders this reflection in steps of 0.00098, 3.6 % of
it, whatever the level (the same relative steps at world strengths 1 to 8; presumably the precision it stores the
closure's colour at), so the nearest step is up to 1.8 % away (measured -0.6 to +1.6 % in 4.2, +0.3 to +1.4 % in 5.3,
whose coat differs). EEVEE renders in the oldest and the newest Blender only (Mesa llvmpipe is slow)."""

from __future__ import annotations

import pytest

bpy = pytest.importorskip("bpy")
pytest.importorskip("OpenImageIO")

import spectral_skin  # noqa: E402
from blender_scenes import principled_surface_inputs, render_normal_incidence_reflection  # noqa: E402

OILINESS = (0.0, 0.3, 1.0)
TOLERANCE = {"cycles": 0.01, "eevee": 0.025}
SAMPLES = {"cycles": 512, "eevee": 16}
EEVEE_VERSIONS = ((4, 2), (5, 3))


def _surface_inputs(oiliness: float, engine: str, surface: str) -> dict[str, float]:
    specular = spectral_skin.evaluate(preset="caucasian", oiliness=oiliness, outputs=("specular",), surface=surface,
                                      engine=engine, blender=bpy.app.version)["specular"]
    return principled_surface_inputs(specular)


@pytest.mark.parametrize("engine", ["cycles", "eevee"])
def test_measured_surface_renders_the_models_normal_incidence_reflection(engine: str) -> None:
    if engine == "eevee" and tuple(bpy.app.version[:2]) not in EEVEE_VERSIONS:
        pytest.skip("EEVEE is checked in the oldest and the newest Blender")
    surfaces = [_surface_inputs(o, engine, "measured") for o in OILINESS]
    rendered = render_normal_incidence_reflection(surfaces, engine, SAMPLES[engine])
    for oiliness, got in zip(OILINESS, rendered, strict=True):
        model = float(spectral_skin.surface_albedo(0.0, oiliness=oiliness, surface="measured"))
        print(f"[{bpy.app.version_string} {engine}] oiliness {oiliness}: rendered {got:.5f}, model {model:.5f}, "
              f"{got / model - 1:+.2%}")
        assert 0.024 <= got <= 0.05, (oiliness, got)
        assert abs(got / model - 1) <= TOLERANCE[engine], (oiliness, got, model)


def test_paper_surface_reflects_nothing_when_dry() -> None:
    """DJ2006's oil layer scales its lobe by the oiliness: dry skin (level 0) has no surface reflection; oily skin's
    is about 0.3 x F0(1.4) at the presets' 0.3."""
    rendered = render_normal_incidence_reflection([_surface_inputs(o, "cycles", "paper") for o in OILINESS], "cycles",
                                                  SAMPLES["cycles"])
    print(f"[{bpy.app.version_string}] paper surface, oiliness {OILINESS}: rendered {rendered}")
    assert rendered[0] < 1e-6, rendered
    assert 0.005 < rendered[1] < 0.012 and rendered[1] < rendered[2], rendered


# Slices: the largest RMS difference over the incidences, as a share of the model's peak, that each engine may show at
# each oiliness. The aim is 5 % (Cycles) and 10 % (EEVEE); measured in 5.0 (docs/surface-slices.md): Cycles
# 10.1 / 4.6 / 5.6 %, EEVEE 12.3 / 9.1 / 7.6 % at oiliness 0 / 0.3 / 1. Dry skin misses the aim: its raised level lifts
# the peak by 15-23 % (GGX alpha = m matches Beckmann's peak, not its shape; the roughness fit to the slices is open:
# docs/model.md). The bounds are the measured figures with a margin for the other versions and the noise.
SLICE_BOUNDS = {"cycles": {0.0: 0.11, 0.3: 0.05, 1.0: 0.06}, "eevee": {0.0: 0.135, 0.3: 0.10, 1.0: 0.085}}
SLICE_INCIDENCES_DEG = (0, 30, 60, 75)
SLICE_SAMPLES = {"cycles": 128, "eevee": 16}


@pytest.mark.parametrize("engine", ["cycles", "eevee"])
def test_measured_surface_slices_follow_the_model(engine: str) -> None:
    """In-plane BRDF slices of the measured surface's Principled inputs (a cylinder under a small sun seen from above:
    each pixel column one angle pair of the plane of incidence; Base Color black, so only the surface reflects) at
    incidences 0-75 deg, against the two-lobe model's BRDF (``surface_brdf``): the RMS over each slice within the
    bounds above. Oldest and newest Blender (the slices take seconds in Cycles, minutes in EEVEE under llvmpipe)."""
    from blender_scenes import render_in_plane_slices, slice_error

    if tuple(bpy.app.version[:2]) not in EEVEE_VERSIONS:
        pytest.skip("the slices are checked in the oldest and the newest Blender")
    surfaces = [_surface_inputs(o, engine, "measured") for o in OILINESS]
    rendered = render_in_plane_slices(surfaces, engine, SLICE_INCIDENCES_DEG, SLICE_SAMPLES[engine])
    for oiliness, slices in zip(OILINESS, rendered, strict=True):
        errors = [slice_error(s, oiliness, "measured") for s in slices]
        print(f"[{bpy.app.version_string} {engine}] oiliness {oiliness}: RMS/peak "
              + ", ".join(f"{r:.3f} (peak {p:.2f})" for r, p in errors))
        worst = max(r for r, _ in errors)
        assert worst <= SLICE_BOUNDS[engine][oiliness], (oiliness, errors)
