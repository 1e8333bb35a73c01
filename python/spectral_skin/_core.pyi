"""Type stubs of spectral-skin's compiled core (src/python.rs).

Units: lengths in mm, coefficients in mm^-1, radial profiles in mm^-2, wavelengths in nm. Arrays are numpy float64.
Every function releases the GIL while the core computes.
"""

from collections.abc import Iterable, Sequence
from typing import Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

__all__ = ["SpectralSkinError", "__version__", "evaluate", "layered_reflectance", "presets", "profile"]

__version__: str

_FloatArray = npt.NDArray[np.float64]

_Combination = Literal["directional", "symmetric"]
_WorkingSpace = Literal["Linear Rec.709", "Linear Rec.2020"]
_OutputName = Literal["albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular"]

class SpectralSkinError(ValueError):
    """Invalid input to spectral-skin.

    The message names the input, its allowed range and the value received, e.g.
    ``melanin must be in [0, 0.5] (melanin fraction C_m); got 0.7``.
    """

class _Preset(TypedDict):
    """A named parameter set (see :func:`presets`)."""

    melanin: float
    melanin_blend: float
    hemoglobin: float
    oiliness: float
    description: str

def evaluate(
    melanin: float | None = None,
    melanin_blend: float | None = None,
    hemoglobin: float | None = None,
    oiliness: float | None = None,
    *,
    preset: str | None = None,
    outputs: Iterable[_OutputName | str] | None = None,
    wavelength_step_nm: float = 5.0,
    multipole_pairs: int | None = None,
    profile_r_min_mm: float | None = None,
    profile_r_max_mm: float | None = None,
    profile_count: int | None = None,
    combination: _Combination | str = "directional",
    working_space: _WorkingSpace | str = "Linear Rec.709",
) -> dict[str, Any]:
    """Evaluate the skin model; compute only the requested outputs.

    Give a preset, or all four parameters; a preset with explicit parameters uses the explicit ones instead of the
    preset's.

    Arguments:
        melanin: C_m, melanin volume fraction of the epidermis, 0..0.5.
        melanin_blend: beta_m, eumelanin share of the melanin, 0..1 (the rest is pheomelanin).
        hemoglobin: C_h, whole-blood volume fraction of the dermis, 0..0.1.
        oiliness: rho_s, scale of the surface's specular lobe, 0..1.
        preset: a preset name from :func:`presets` (case-insensitive).
        outputs: names among "albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular".
            None: ("albedo", "radius", "specular"), what a material needs.
        wavelength_step_nm: wavelength sampling step in nm (380-780 nm), 0.5..100.
        multipole_pairs: image-source pairs per side of the multipole; None: the whole series (closed form).
        profile_r_min_mm: smallest radius of the log-spaced profile grid, mm; None: 0.001 mm.
        profile_r_max_mm: largest radius of the profile grid, mm; None: 20 mm.
        profile_count: number of profile radii; None: 64.
        combination: transport through the epidermis from below: "directional" (the layer seen from below) or
            "symmetric" (DJ2005's published form).
        working_space: linear RGB space of every RGB output: "Linear Rec.709" or "Linear Rec.2020".

    Returns:
        The CLI's JSON as a dict. Always: "params", "color_space", "accuracy", "model" (model["dermis_thickness_mm"]
        is float("inf") for a semi-infinite dermis), "combination", "default_method", "work" ({"wavelengths",
        "transform_samples", "radial_profiles"}), "seconds". Per requested output, numpy arrays where array-valued:
        albedo or radius: "diffuse_reflectance_rgb" (3,);
        radius: "methods" {"burley", "random_walk"} -> {"base_color" (3,), "subsurface_radius_mm" (3,), mm,
        "expected_albedo" (3,)} and "radius_fit" (a list of 3 dicts {"d_mm", "radius_mm", "edge_residual"});
        specular: "specular" {"oiliness", "specular_ior_level", "roughness", "ior", "beckmann_m",
        "directional_albedo_normal", "hemispherical_albedo"};
        spectrum: "wavelengths_nm" (K,), "spectral_reflectance" (K,);
        profile_rgb / profile_spectral: "profile" {"radii_mm" (N,), "rgb_per_mm2" (N, 3) and/or
        "spectral_per_mm2" (K, N), mm^-2} (and "wavelengths_nm" (K,) with profile_spectral).

    Raises:
        SpectralSkinError: a parameter or knob out of range or not finite, an unknown preset, output, combination or
            working space, or neither a preset nor all four parameters.
        TypeError: an argument of the wrong type (e.g. outputs given as a single string).
    """

def profile(
    melanin: float | None = None,
    melanin_blend: float | None = None,
    hemoglobin: float | None = None,
    oiliness: float | None = None,
    *,
    preset: str | None = None,
    spectral: bool = False,
    wavelength_step_nm: float = 5.0,
    multipole_pairs: int | None = None,
    profile_r_min_mm: float | None = None,
    profile_r_max_mm: float | None = None,
    profile_count: int | None = None,
    combination: _Combination | str = "directional",
    working_space: _WorkingSpace | str = "Linear Rec.709",
) -> dict[str, _FloatArray]:
    """The radial reflectance profile R(r) of the skin on a log-spaced radius grid.

    Arguments:
        melanin, melanin_blend, hemoglobin, oiliness, preset: as for :func:`evaluate`.
        spectral: False: RGB profiles; True: one profile per wavelength.
        wavelength_step_nm, multipole_pairs, profile_r_min_mm, profile_r_max_mm, profile_count, combination,
            working_space: as for :func:`evaluate`.

    Returns:
        {"radii_mm": (N,), "rgb_per_mm2": (N, 3)} in mm^-2, or with spectral=True
        {"radii_mm": (N,), "spectral_per_mm2": (K, N), "wavelengths_nm": (K,)}.

    Raises:
        SpectralSkinError: as for :func:`evaluate`.
        TypeError: an argument of the wrong type.
    """

def presets() -> dict[str, _Preset]:
    """The named presets.

    Returns:
        {name: {"melanin", "melanin_blend", "hemoglobin", "oiliness", "description"}}; the names are accepted by
        ``preset=`` of :func:`evaluate` and :func:`profile`.
    """

def layered_reflectance(
    layers: Iterable[Sequence[float]],
    radii_mm: npt.ArrayLike,
) -> tuple[float, _FloatArray]:
    """Total diffuse reflectance and radial profile of a stack of layers under air (the diffusion solver alone).

    Uses the directional combination, the whole multipole series and the default inverse-Hankel quadrature.

    Arguments:
        layers: top to bottom, each (thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior): thickness in mm
            (float("inf") for a semi-infinite last layer), absorption and reduced scattering coefficients in mm^-1,
            index of refraction 1..4.
        radii_mm: 1-D radii in mm, finite and >= 0.

    Returns:
        (total diffuse reflectance, R(r) at radii_mm in mm^-2 as a float64 array of the same length).

    Raises:
        SpectralSkinError: no layers, a layer that is not 4 values, a thickness <= 0 or infinite before the last
            layer, a negative or non-finite coefficient, an ior outside 1..4, or a negative or non-finite radius.
        TypeError: layers or radii_mm not sequences of numbers.
    """
