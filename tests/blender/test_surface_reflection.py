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
