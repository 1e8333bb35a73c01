"""The tests' independent colour difference: linear Rec.709 RGB -> CIELAB (D65) and the CIEDE2000 difference ΔE00,
written apart from the core's (src/color/difference.rs, spectral_skin.delta_e00) so that tests can check it.

No dependencies beyond numpy (colour-science is not installed in the Blender venvs). Used by test_inverse_albedo.py,
test_delta_e00.py and tests/blender/test_addon_udim.py; checked against the published test pairs in
test_color_difference.py.

References:
- CIEDE2000: G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference formula: implementation notes,
  supplementary test data, and mathematical observations", Color Research and Application 30(1), 21-30 (2005),
  equations (1)-(22), with k_L = k_C = k_H = 1.
- Linear Rec.709 / sRGB primaries with a D65 white to CIE XYZ: IEC 61966-2-1:1999, the matrix of section 5.2 (its
  inverse's rounded form); the white is the matrix's row sums, so RGB (1, 1, 1) is L* = 100, a* = b* = 0.
- CIELAB: CIE 15:2004, section 8.2.1 (f(t) = t^(1/3) above (6/29)^3, linear below).
"""

from __future__ import annotations

import numpy as np

# IEC 61966-2-1: linear RGB (Rec.709 primaries, D65) -> XYZ.
RGB_TO_XYZ = np.array([[0.4124, 0.3576, 0.1805],
                       [0.2126, 0.7152, 0.0722],
                       [0.0193, 0.1192, 0.9505]])
WHITE_XYZ = RGB_TO_XYZ.sum(axis=1)
_DELTA = 6.0 / 29.0  # CIE 15:2004, 8.2.1
_HUE_EPS_DEG = 1e-9  # rounding of hue angles (degrees) at the 180° branch of Sharma et al.'s eqs. (10) and (14)


def lab_from_linear_rgb(rgb: np.ndarray, white_y: float = 1.0) -> np.ndarray:
    """CIELAB of linear Rec.709 RGB (last axis), relative to a white of luminance ``white_y`` (RGB = white_y each)."""
    xyz = np.asarray(rgb, dtype=np.float64) @ RGB_TO_XYZ.T / (WHITE_XYZ * white_y)
    f = np.where(xyz > _DELTA**3, np.cbrt(np.maximum(xyz, 0.0)), xyz / (3 * _DELTA**2) + 4.0 / 29.0)
    return np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])],
                    axis=-1)


def ciede2000(lab1: np.ndarray, lab2: np.ndarray) -> np.ndarray:
    """ΔE00 between CIELAB colours (last axis L*, a*, b*; broadcast), Sharma et al. (2005) eqs. (1)-(22)."""
    lab1, lab2 = np.asarray(lab1, dtype=np.float64), np.asarray(lab2, dtype=np.float64)
    l1, a1, b1 = lab1[..., 0], lab1[..., 1], lab1[..., 2]
    l2, a2, b2 = lab2[..., 0], lab2[..., 1], lab2[..., 2]
    # (2)-(7): a' with the chroma-dependent factor G, C' and h' (degrees in [0, 360); 0 where a' = b = 0).
    c_mean = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    g = 0.5 * (1.0 - np.sqrt(c_mean**7 / (c_mean**7 + 25.0**7)))
    a1p, a2p = (1.0 + g) * a1, (1.0 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.where((a1p == 0) & (b1 == 0), 0.0, np.degrees(np.arctan2(b1, a1p)) % 360.0)
    h2p = np.where((a2p == 0) & (b2 == 0), 0.0, np.degrees(np.arctan2(b2, a2p)) % 360.0)
    # (8)-(11): the differences.
    dl = l2 - l1
    dc = c2p - c1p
    product = c1p * c2p
    dh = h2p - h1p
    # A hue difference of exactly 180° (Table 1, pairs 13-14) falls on the "<= 180" side of eqs. (10) and (14); the
    # degrees from arctan2 land a rounding error either side of it: compared with _HUE_EPS_DEG.
    dh = np.where(product == 0, 0.0, np.where(dh > 180.0 + _HUE_EPS_DEG, dh - 360.0,
                                              np.where(dh < -180.0 - _HUE_EPS_DEG, dh + 360.0, dh)))
    dhh = 2.0 * np.sqrt(product) * np.sin(np.radians(dh / 2.0))
    # (12)-(22): means, weights, rotation.
    lp = 0.5 * (l1 + l2)
    cp = 0.5 * (c1p + c2p)
    hsum = h1p + h2p
    hp = np.where(product == 0, hsum,
                  np.where(np.abs(h1p - h2p) <= 180.0 + _HUE_EPS_DEG, hsum / 2.0,
                           np.where(hsum < 360.0, (hsum + 360.0) / 2.0, (hsum - 360.0) / 2.0)))
    t = (1.0 - 0.17 * np.cos(np.radians(hp - 30.0)) + 0.24 * np.cos(np.radians(2.0 * hp))
         + 0.32 * np.cos(np.radians(3.0 * hp + 6.0)) - 0.20 * np.cos(np.radians(4.0 * hp - 63.0)))
    d_theta = 30.0 * np.exp(-(((hp - 275.0) / 25.0) ** 2))
    rc = 2.0 * np.sqrt(cp**7 / (cp**7 + 25.0**7))
    sl = 1.0 + 0.015 * (lp - 50.0) ** 2 / np.sqrt(20.0 + (lp - 50.0) ** 2)
    sc = 1.0 + 0.045 * cp
    sh = 1.0 + 0.015 * cp * t
    rt = -np.sin(np.radians(2.0 * d_theta)) * rc
    return np.sqrt((dl / sl) ** 2 + (dc / sc) ** 2 + (dhh / sh) ** 2 + rt * (dc / sc) * (dhh / sh))


def delta_e00_linear_rgb(rgb1: np.ndarray, rgb2: np.ndarray, white_y: float = 1.0) -> np.ndarray:
    """ΔE00 between linear Rec.709 RGB colours (last axis), both relative to the same white."""
    return ciede2000(lab_from_linear_rgb(rgb1, white_y), lab_from_linear_rgb(rgb2, white_y))
