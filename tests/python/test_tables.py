"""The core's tables as fronts read them: parameters() is what evaluate validates with and what maps reads,
accuracy_levels() names the levels evaluate accepts."""

from __future__ import annotations

import inspect
import math

import pytest
import spectral_skin

# DJ2006's parameter table (docs/model.md, section Parameters), written out here as the independent reference.
DJ2006 = {"melanin": ("C_m", 0.0, 0.5), "melanin_blend": ("beta_m", 0.0, 1.0), "hemoglobin": ("C_h", 0.0, 0.1),
          "oiliness": ("rho_s", 0.0, 1.0)}


# The values DJ2006 fix that the extended physiology frees (docs/model.md, sections Parameters and Layers).
DJ2006_FIXED = {"epidermis_thickness_mm": 0.25, "baseline_absorption_scale": 1.0, "blood_oxygenation": 0.75}


def test_parameters_are_the_papers_in_evaluates_order() -> None:
    specs = spectral_skin.parameters()
    assert [p["name"] for p in specs] == list(DJ2006) + list(DJ2006_FIXED)
    # The names are evaluate's keywords, in its order: the paper's four positional, the extended keyword-only.
    keywords = list(inspect.signature(spectral_skin.evaluate).parameters)
    assert keywords[: len(specs)] == [p["name"] for p in specs]
    for p in specs[:4]:
        assert (p["symbol"], p["min"], p["max"]) == DJ2006[p["name"]]
        assert p["default"] is None and p["unit"] == "" and p["label"] and p["description"] and p["source"]
    for p in specs[4:]:
        assert p["default"] == DJ2006_FIXED[p["name"]] and p["min"] <= p["default"] <= p["max"]
        assert p["label"] and p["description"] and p["source"]
    assert spectral_skin.parameter_ranges() == {p["name"]: (p["min"], p["max"]) for p in specs}


def test_extended_physiology_at_its_defaults_is_the_paper() -> None:
    paper = spectral_skin.evaluate(preset="asian", outputs=["albedo"])["diffuse_reflectance_rgb"]
    same = spectral_skin.evaluate(preset="asian", outputs=["albedo"], **DJ2006_FIXED)["diffuse_reflectance_rgb"]
    assert (same == paper).all()
    # Each moves the albedo the way its description says.
    thin = spectral_skin.evaluate(preset="asian", outputs=["albedo"], epidermis_thickness_mm=0.08)
    assert thin["diffuse_reflectance_rgb"][0] > paper[0]
    dark = spectral_skin.evaluate(preset="asian", outputs=["albedo"], baseline_absorption_scale=3.0)
    assert all(d < p for d, p in zip(dark["diffuse_reflectance_rgb"], paper, strict=True))
    venous = spectral_skin.evaluate(preset="asian", outputs=["albedo"], blood_oxygenation=0.0)
    assert venous["params"]["blood_oxygenation"] == 0.0 and (venous["diffuse_reflectance_rgb"] != paper).any()


@pytest.mark.parametrize("spec", spectral_skin.parameters(), ids=lambda p: p["name"])
def test_evaluate_accepts_the_range_and_rejects_beyond_it(spec: dict[str, object]) -> None:
    name, high = str(spec["name"]), float(spec["max"])  # type: ignore[arg-type]
    base = {"melanin": 0.1, "melanin_blend": 0.5, "hemoglobin": 0.01, "oiliness": 0.3}
    spectral_skin.evaluate(**{**base, name: high}, outputs=["albedo"], accuracy="draft")  # type: ignore[arg-type]
    low = float(spec["min"])  # type: ignore[arg-type]
    with pytest.raises(spectral_skin.SpectralSkinError, match=rf"{name} must be in \[{low:g}, {high:g}\]"):
        spectral_skin.evaluate(**{**base, name: math.nextafter(high, math.inf)}, outputs=["albedo"])  # type: ignore[arg-type]


def test_accuracy_levels_are_the_ones_evaluate_accepts() -> None:
    levels = spectral_skin.accuracy_levels()
    assert [level["name"] for level in levels] == ["draft", "default", "reference"]
    assert all(level["description"] and "\n" not in level["description"] for level in levels)
    for level in levels:
        assert spectral_skin.evaluate(preset="asian", outputs=["albedo"], accuracy=level["name"])["accuracy"]
    with pytest.raises(spectral_skin.SpectralSkinError, match="accuracy"):
        spectral_skin.evaluate(preset="asian", accuracy="fast")
