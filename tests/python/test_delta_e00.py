"""spectral_skin.cielab / delta_e00 (the core's CIELAB and CIEDE2000, as the fits use them) against independent
references: the sRGB red primary's published L*a*b* (53.24, 80.09, 67.20, D65; B. Lindbloom's RGB/XYZ and XYZ/Lab
equations in IEC 61966-2-1 terms), and the independent numpy CIEDE2000 (checked against Sharma, Wu & Dalal's 34
published pairs in test_color_difference.py) on random colours. The core's white is the D65 of the CIE tables
integrated, the numpy one IEC 61966-2-1's rounded matrix: they agree to about 1e-3 ΔE00.
"""

from __future__ import annotations

import color_difference
import numpy as np
import pytest
import spectral_skin


def test_cielab_of_white_grey_and_the_srgb_red_primary() -> None:
    lab = spectral_skin.cielab([[1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [1.0, 0.0, 0.0]])
    assert lab.shape == (3, 3), lab.shape
    np.testing.assert_allclose(lab[0], [100.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(lab[1], [116.0 * 0.5 ** (1 / 3) - 16.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(lab[2], [53.24, 80.09, 67.20], atol=0.1)
    doubled = spectral_skin.cielab(np.array([0.4, 0.2, 0.1]) * 2, white_luminance=2.0)
    np.testing.assert_allclose(doubled, spectral_skin.cielab([0.4, 0.2, 0.1]), atol=1e-12)


def test_delta_e00_agrees_with_the_independent_implementation() -> None:
    rng = np.random.default_rng(7)
    reference = rng.uniform(0.0, 1.0, (4, 500, 3))
    test = np.clip(reference * rng.uniform(0.8, 1.2, reference.shape), 0.0, None)
    core = spectral_skin.delta_e00(reference, test)
    independent = color_difference.ciede2000(color_difference.lab_from_linear_rgb(reference),
                                             color_difference.lab_from_linear_rgb(test))
    assert core.shape == (4, 500), core.shape
    worst = float(np.max(np.abs(core - independent)))
    assert worst < 5e-3, f"largest |core - numpy| ΔE00 {worst:.2e} (mean ΔE00 {float(np.mean(core)):.3f})"
    assert np.all(spectral_skin.delta_e00(reference, reference) == 0.0)
    np.testing.assert_allclose(spectral_skin.delta_e00(test, reference), core, atol=1e-12)


def test_bad_colours_are_refused_by_name() -> None:
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"invalid test: must have the shape of reference \(2, 3\); got \(3, 3\)"):
        spectral_skin.delta_e00(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(spectral_skin.SpectralSkinError, match=r"invalid rgb: must be .*\(\.\.\., 3\); got shape \(2, 4\)"):
        spectral_skin.cielab(np.zeros((2, 4)))
    with pytest.raises(spectral_skin.SpectralSkinError, match="invalid reference: must hold finite values; colour 1"):
        spectral_skin.delta_e00([[0.1, 0.2, 0.3], [np.nan, 0.0, 0.0]], np.zeros((2, 3)))
    with pytest.raises(spectral_skin.SpectralSkinError, match="invalid white_luminance: must be finite and > 0"):
        spectral_skin.cielab([0.1, 0.2, 0.3], white_luminance=0.0)
    with pytest.raises(spectral_skin.SpectralSkinError, match="working_space"):
        spectral_skin.cielab([0.1, 0.2, 0.3], working_space="sRGB-ish")
