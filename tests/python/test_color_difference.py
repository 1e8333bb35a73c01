"""tests/python/color_difference.py (the tests' independent CIEDE2000) against published references.

CIEDE2000: the 34 test pairs of Sharma, Wu and Dalal (2005), Table 1 (Color Research and Application 30(1), p. 24),
given to 4 decimals: each pair must match to 1e-4 and be symmetric. CIELAB: white, and the sRGB red primary's
L*a*b* (D65) of 53.24, 80.09, 67.20 (B. Lindbloom's RGB/XYZ and XYZ/Lab equations, also in IEC 61966-2-1 terms).
"""

from __future__ import annotations

from pathlib import Path

import color_difference
import numpy as np

# Sharma et al. (2005), Table 1: L1, a1, b1, L2, a2, b2, ΔE00 (the file's first line names the source).
SHARMA_TABLE_1 = np.loadtxt(Path(__file__).resolve().parents[2] / "data" / "sharma2005_ciede2000_pairs.csv",
                            delimiter=",", comments="#", skiprows=2)


def test_ciede2000_matches_sharmas_table_1() -> None:
    lab1, lab2, expected = SHARMA_TABLE_1[:, :3], SHARMA_TABLE_1[:, 3:6], SHARMA_TABLE_1[:, 6]
    np.testing.assert_allclose(color_difference.ciede2000(lab1, lab2), expected, atol=5e-5)
    np.testing.assert_allclose(color_difference.ciede2000(lab2, lab1), expected, atol=5e-5)
    assert np.all(color_difference.ciede2000(lab1, lab1) == 0.0)


def test_lab_of_white_and_the_srgb_red_primary() -> None:
    lab = color_difference.lab_from_linear_rgb(np.array([[1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [1.0, 0.0, 0.0]]))
    np.testing.assert_allclose(lab[0], [100.0, 0.0, 0.0], atol=1e-9)
    assert abs(lab[1, 1]) < 1e-9 and abs(lab[1, 2]) < 1e-9 and 76.0 < lab[1, 0] < 76.1  # 116 * 0.5^(1/3) - 16
    np.testing.assert_allclose(lab[2], [53.24, 80.09, 67.20], atol=0.05)
    # The white's luminance scales out: twice the light and a white twice as bright are the same colour.
    np.testing.assert_allclose(color_difference.lab_from_linear_rgb(np.array([0.4, 0.2, 0.1]) * 2, white_y=2.0),
                               color_difference.lab_from_linear_rgb(np.array([0.4, 0.2, 0.1])), atol=1e-12)
