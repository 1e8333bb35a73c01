"""scripts/color_difference.py (ΔE00 of the scene-effects report) against published references.

CIEDE2000: the 34 test pairs of Sharma, Wu and Dalal (2005), Table 1 (Color Research and Application 30(1), p. 24),
given to 4 decimals: each pair must match to 1e-4 and be symmetric. CIELAB: white, and the sRGB red primary's
L*a*b* (D65) of 53.24, 80.09, 67.20 (B. Lindbloom's RGB/XYZ and XYZ/Lab equations, also in IEC 61966-2-1 terms).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "color_difference.py"
_spec = importlib.util.spec_from_file_location("_color_difference", SCRIPT)
assert _spec is not None and _spec.loader is not None
color_difference = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(color_difference)

# Sharma et al. (2005), Table 1: L1, a1, b1, L2, a2, b2, ΔE00.
SHARMA_TABLE_1 = np.array([
    [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
    [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
    [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
    [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
    [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
    [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
    [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
    [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
    [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
    [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
    [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
    [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
    [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
    [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
    [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
    [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
    [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
    [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
    [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
    [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
])


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
