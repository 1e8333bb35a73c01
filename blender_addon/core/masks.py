"""Live mode's masks, without bpy: what a blush/flush or tan/vitiligo mask does to a parameter, its strength's range,
its image size and names (the bpy glue, the mask node group and the operator, is blender_addon/masks.py).

A mask is a painted image or colour attribute (its first channel, 0 = no change, 1 = the full strength) with a
Strength in the parameter's own units; it feeds the "Spectral Skin" group's input through a small node group that
computes ``clamp(value + mask * strength, low, high)``, the parameter's range from the core's parameter table
(``spectral_skin.parameters()``). A negative strength removes (a pale patch, vitiligo). Several masks on one
parameter are a chain, each clamping: :func:`apply_masks` is that chain, the reference the tests render against.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import spectral_skin

from .settings import PARAMETER_INFO


@dataclass(frozen=True)
class MaskKind:
    """One kind of mask: the parameter it changes, its label, and its default strength as a fraction of the
    parameter's range (a design choice: a visible change, far from the range's ends)."""

    parameter: str
    label: str
    description: str
    default_fraction: float


MASK_KINDS = {
    "BLUSH": MaskKind("hemoglobin", "Blush/Flush",
                      "adds haemoglobin where painted (a blush, a flush; a negative strength: pallor)", 0.2),
    "TAN": MaskKind("melanin", "Tan/Vitiligo",
                    "adds melanin where painted (a tan; a negative strength removes it: vitiligo)", 0.1),
}
MASK_SOURCES = ("IMAGE", "ATTRIBUTE")
# The side of a new mask image when the material has no parameter map to take its size from.
DEFAULT_MASK_SIZE = (1024, 1024)


def parameter_range(parameter: str) -> tuple[float, float]:
    """(low, high) of a parameter, from the core's parameter table."""
    info = PARAMETER_INFO[parameter]
    return float(info.low), float(info.high)


def strength_range(kind: str) -> tuple[float, float]:
    """The strengths a mask of ``kind`` accepts: +-(the parameter's span), which takes any value anywhere in range."""
    low, high = parameter_range(MASK_KINDS[kind].parameter)
    return -(high - low), high - low


def default_strength(kind: str) -> float:
    low, high = parameter_range(MASK_KINDS[kind].parameter)
    return MASK_KINDS[kind].default_fraction * (high - low)


def check_mask(kind: str, source: str, strength: float) -> None:
    """Raise SpectralSkinError naming the input and its allowed values."""
    if kind not in MASK_KINDS:
        raise spectral_skin.SpectralSkinError(f"mask kind must be one of {', '.join(MASK_KINDS)}; got {kind!r}")
    if source not in MASK_SOURCES:
        raise spectral_skin.SpectralSkinError(f"mask source must be one of {', '.join(MASK_SOURCES)}; got {source!r}")
    low, high = strength_range(kind)
    if not (np.isfinite(strength) and low <= strength <= high):
        raise spectral_skin.SpectralSkinError(
            f"mask strength ({MASK_KINDS[kind].label}, {MASK_KINDS[kind].parameter}) must be in [{low:g}, {high:g}]; "
            f"got {strength!r}")


def apply_mask(value: np.ndarray | float, mask: np.ndarray | float, strength: float,
               parameter: str) -> np.ndarray:
    """What one mask node gives the parameter: clamp(value + mask * strength) into the parameter's range."""
    low, high = parameter_range(parameter)
    return np.clip(np.asarray(value, dtype=np.float64) + np.asarray(mask, dtype=np.float64) * strength, low, high)


def apply_masks(value: np.ndarray | float, masks: Iterable[tuple[np.ndarray | float, float]],
                parameter: str) -> np.ndarray:
    """A chain of masks (mask, strength), first applied first, each clamping, as the node chain computes it."""
    out = np.asarray(value, dtype=np.float64)
    for mask, strength in masks:
        out = apply_mask(out, mask, strength, parameter)
    return out


def mask_size(map_sizes: Sequence[tuple[int, int]]) -> tuple[int, int]:
    """The size of a new mask image: the largest of the material's parameter maps (so a painted texel matches a
    parameter texel), else DEFAULT_MASK_SIZE."""
    sizes = [(int(w), int(h)) for w, h in map_sizes if w > 0 and h > 0]
    return max(sizes, key=lambda s: s[0] * s[1]) if sizes else DEFAULT_MASK_SIZE


def mask_name(material: str, kind: str, taken: Iterable[str]) -> str:
    """A name for the new mask's image or colour attribute, not among ``taken``: "<material> Blush/Flush Mask",
    then ".001" etc. Kept under Blender 4.x's 63-byte ID names."""
    base = f"{material} {MASK_KINDS[kind].label} Mask"
    if len(base.encode()) > 58:
        base = base.encode()[:58].decode(errors="ignore")
    taken = set(taken)
    name, n = base, 0
    while name in taken:
        n += 1
        name = f"{base}.{n:03d}"
    return name


def group_name(parameter: str) -> str:
    """The mask node group of a parameter (one per parameter: its clamp range is the parameter's)."""
    return f"Spectral Skin Mask {parameter}"
