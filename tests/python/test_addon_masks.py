"""Live mode's masks without bpy (blender_addon/core/masks.py): the value a mask chain gives a parameter, clamped to
the core's parameter table's range; strengths checked against that range; the new mask's size and names."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import spectral_skin
from addon_helpers import load_core

load_core()
masks = importlib.import_module("addon_core.masks")

RANGES = {p["name"]: (p["min"], p["max"]) for p in spectral_skin.parameters()}


def test_mask_adds_strength_where_painted_and_clamps_to_the_cores_range():
    low, high = RANGES["hemoglobin"]
    mask = np.array([0.0, 0.5, 1.0, 1.0])
    got = masks.apply_mask(0.02, mask, 0.03, "hemoglobin")
    np.testing.assert_allclose(got, [0.02, 0.035, 0.05, 0.05])
    np.testing.assert_allclose(masks.apply_mask(0.02, mask, high - low, "hemoglobin")[2:], high)
    low_m = RANGES["melanin"][0]
    np.testing.assert_allclose(masks.apply_mask(0.05, 1.0, -0.08, "melanin"), low_m)
    # A chain clamps at each mask: +0.2 then -0.05 from 0.02 gives high - 0.05, not 0.17.
    np.testing.assert_allclose(masks.apply_masks(0.02, [(1.0, 0.2), (1.0, -0.05)], "hemoglobin"), high - 0.05)


def test_strength_range_is_the_parameters_span():
    for kind, kind_info in masks.MASK_KINDS.items():
        low, high = RANGES[kind_info.parameter]
        assert masks.strength_range(kind) == pytest.approx((low - high, high - low))
        assert 0 < masks.default_strength(kind) < high - low
    masks.check_mask("BLUSH", "IMAGE", -(RANGES["hemoglobin"][1]))
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"strength .*hemoglobin.* must be in \[-0\.1, 0\.1\]"):
        masks.check_mask("BLUSH", "IMAGE", 0.2)
    with pytest.raises(spectral_skin.SpectralSkinError, match="mask strength"):
        masks.check_mask("TAN", "IMAGE", float("nan"))
    with pytest.raises(spectral_skin.SpectralSkinError, match="mask kind must be one of BLUSH, TAN"):
        masks.check_mask("FRECKLE", "IMAGE", 0.0)
    with pytest.raises(spectral_skin.SpectralSkinError, match="mask source must be one of IMAGE, ATTRIBUTE"):
        masks.check_mask("TAN", "VERTEX", 0.0)


def test_mask_size_and_names():
    assert masks.mask_size([]) == (1024, 1024)
    assert masks.mask_size([(512, 256), (2048, 1024), (0, 0)]) == (2048, 1024)
    assert masks.mask_name("Face", "BLUSH", []) == "Face Blush/Flush Mask"
    assert masks.mask_name("Face", "TAN", ["Face Tan/Vitiligo Mask"]) == "Face Tan/Vitiligo Mask.001"
    long = masks.mask_name("x" * 80, "BLUSH", [])
    assert len(long.encode()) <= 58
    assert masks.group_name("melanin") != masks.group_name("hemoglobin")
