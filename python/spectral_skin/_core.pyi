"""Type stubs of spectral-skin's compiled core (src/python.rs).

Units: lengths in mm, coefficients in mm^-1, radial profiles in mm^-2, wavelengths in nm. Arrays are numpy float64,
except the images of :func:`maps` (float32). Every function releases the GIL while the core computes.
"""

import os
import pathlib
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, Literal, TypedDict

import numpy as np
import numpy.typing as npt

__all__ = [
    "SpectralSkinError",
    "SpectralSkinWarning",
    "__version__",
    "blender_targets",
    "evaluate",
    "layered_reflectance",
    "maps",
    "parameter_ranges",
    "presets",
    "profile",
    "read_parameter_map",
    "write_maps",
]

__version__: str

_FloatArray = npt.NDArray[np.float64]
_Float32Array = npt.NDArray[np.float32]
_MapArray = npt.NDArray[np.float32] | npt.NDArray[np.float64]

_Combination = Literal["directional", "symmetric"]
_WorkingSpace = Literal["Linear Rec.709", "Linear Rec.2020", "ACEScg"]
_Method = Literal["burley", "random_walk", "random_walk_legacy", "random_walk_skin"]
_Engine = Literal["cycles", "eevee"]
_BlenderVersion = str | tuple[int, int] | tuple[int, int, int]
_AccuracyLevel = Literal["draft", "default", "reference"]
_WavelengthPlacement = Literal["uniform", "cmf_adapted", "rgb_shortcut"]
_Parameter = Literal["melanin", "melanin_blend", "hemoglobin", "oiliness"]
_RgbMapping = Literal["linear", "non_negative"]
_Boundaries = Literal["paper", "capped"]
_OutputName = Literal["albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular"]

class SpectralSkinError(ValueError):
    """Invalid input to spectral-skin.

    The message names the input, its allowed range and the value received, e.g.
    ``melanin must be in [0, 0.5] (melanin fraction C_m); got 0.7``.
    """

class SpectralSkinWarning(UserWarning):
    """A result computed but changed on its way out: a negative lobe of a radial profile set to 0.

    With the paper's boundaries (``boundaries="paper"``, the default) a layer thinner than its extrapolation
    distances, over layers that do not fill it, gives a profile that is negative at some radii: the diffusion model's
    own lobe, not round-off (docs/robustness.md, "Negative profile lobes"). The profile returned is clamped to 0 and
    this warning says where and how deep; ``boundaries="capped"`` gives a profile that is non-negative by
    construction. No preset has such a lobe.
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
    accuracy: _AccuracyLevel | str = "default",
    wavelength_step_nm: float | None = None,
    wavelength_placement: _WavelengthPlacement | str | None = None,
    multipole_pairs: int | None = None,
    profile_r_min_mm: float | None = None,
    profile_r_max_mm: float | None = None,
    profile_count: int | None = None,
    combination: _Combination | str = "directional",
    working_space: _WorkingSpace | str = "Linear Rec.709",
    blender: _BlenderVersion | None = None,
    engine: _Engine | str = "cycles",
    rgb_mapping: _RgbMapping | str = "linear",
    boundaries: _Boundaries | str = "paper",
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
        accuracy: a named accuracy level, "draft", "default" or "reference" (docs/accuracy-vs-time.md); the
            knobs below override its settings where given.
        wavelength_step_nm: wavelength sampling step in nm (380-780 nm), 0.5..100; with "cmf_adapted" placement it
            sets the count (the uniform step's); None: the level's (10 nm at "default").
        wavelength_placement: "uniform" (every step nm), "cmf_adapted" (denser where the colour-matching functions
            weigh most; the default level's) or "rgb_shortcut" (reflectance at 435.8, 546.1 and 700 nm taken as B, G,
            R: the shortcut DJ2006 argues against, for comparison); None: the level's.
        multipole_pairs: image-source pairs per side of the multipole; None: the whole series (closed form).
        profile_r_min_mm: smallest radius of the log-spaced profile grid, mm; None: 0.001 mm.
        profile_r_max_mm: largest radius of the profile grid, mm; None: 20 mm.
        profile_count: number of profile radii; None: 64.
        combination: transport through the epidermis from below: "directional" (the layer seen from below) or
            "symmetric" (DJ2005's published form).
        working_space: linear RGB space of every RGB output, named as Blender 5.0's working spaces:
            "Linear Rec.709", "Linear Rec.2020" (both D65) or "ACEScg" (AP1 primaries, ACES white; the D65 XYZ is
            Bradford-adapted to it, as Blender's OCIO config does). A perfect white reflector is (1, 1, 1) in each.
        blender: the Blender version the Principled inputs are for: "MAJOR.MINOR" (e.g. "5.2"; a patch level is
            ignored) or a tuple such as ``bpy.app.version``; 4.2 or newer. A version newer than the tested ones uses
            the newest known behaviour (``result["target"]["tested"]`` is False). None: the current release (5.3,
            ``blender_targets()["current_release"]``).
        engine: the render engine, "cycles" or "eevee" (EEVEE renders every subsurface method as Burley, with a
            radius compensated for its albedo-dependent profile).
        rgb_mapping: how the RGB profile's colour at each radius is formed (only "profile_rgb" uses it), as for
            :func:`profile`: "linear" (exact; negative in a channel where the light is outside the gamut) or
            "non_negative".
        boundaries: the layers' boundary conditions: "paper" (DJ2005's extrapolated boundaries, the default) or
            "capped" (each layer's extrapolation distances capped so that every radial profile is non-negative and
            the total reflectance never rises with absorption, by construction; it moves a thin or red-lit epidermis
            away from Monte Carlo: docs/robustness.md, "Negative profile lobes").

    Returns:
        The CLI's JSON as a dict. Always: "params", "color_space", "accuracy", "model" (model["dermis_thickness_mm"]
        is float("inf") for a semi-infinite dermis), "combination", "target" ({"blender": "5.3", "engine":
        "cycles", "tested": True}), "default_method", "work" ({"wavelengths",
        "transform_samples", "radial_profiles"}), "seconds". Per requested output, numpy arrays where array-valued:
        albedo or radius: "diffuse_reflectance_rgb" (3,);
        radius: "methods", one entry per subsurface method the target's Blender offers ("burley", "random_walk",
        "random_walk_skin", and "random_walk_legacy" from 5.2) -> {"base_color" (3,), "subsurface_radius_mm" (3,),
        mm, "expected_albedo" (3,)} and "radius_fit" (a list of 3 dicts {"d_mm", "radius_mm", "edge_residual"}:
        the Cycles Burley fit);
        specular: "specular" {"oiliness", "specular_ior_level", "roughness", "ior", "beckmann_m",
        "directional_albedo_normal", "hemispherical_albedo"};
        spectrum: "wavelengths_nm" (K,), "spectral_reflectance" (K,);
        profile_rgb / profile_spectral: "profile" {"radii_mm" (N,), "rgb_per_mm2" (N, 3) and/or
        "spectral_per_mm2" (K, N), mm^-2, and "negative_lobe" {"wavelength_nm", "radius_mm", "relative_to_peak"}
        when a spectral profile was negative beyond round-off before its clamp to 0, also reported by a
        SpectralSkinWarning} (and "wavelengths_nm" (K,) with profile_spectral).

    Raises:
        SpectralSkinError: a parameter or knob out of range or not finite, an unknown preset, output, combination or
            working space, or neither a preset nor all four parameters; a Blender version older than 4.2 or not
            MAJOR.MINOR; an unknown engine.
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
    accuracy: _AccuracyLevel | str = "default",
    wavelength_step_nm: float | None = None,
    wavelength_placement: _WavelengthPlacement | str | None = None,
    multipole_pairs: int | None = None,
    profile_r_min_mm: float | None = None,
    profile_r_max_mm: float | None = None,
    profile_count: int | None = None,
    combination: _Combination | str = "directional",
    working_space: _WorkingSpace | str = "Linear Rec.709",
    rgb_mapping: _RgbMapping | str = "linear",
    boundaries: _Boundaries | str = "paper",
) -> dict[str, _FloatArray]:
    """The radial reflectance profile R(r) of the skin on a log-spaced radius grid.

    The RGB profile is the spectral profile mapped into ``working_space``. With ``rgb_mapping="linear"`` (the
    default) that map is linear: the exact colour at each radius, additive, and it integrates (2 pi r dr) to the RGB
    albedo; but where the light is outside the space's gamut a channel is **negative**. Every preset has such radii:
    in the far tail only red light is left, more saturated than the red primary (README.md, "Radial profiles", lists
    the radii and sizes). ``rgb_mapping="non_negative"`` moves each such colour along the line towards the grey of the same
    luminance (R = G = B = Y) until its most negative channel is 0: no value is negative, luminance and hue are kept,
    radii inside the gamut are unchanged, but the profile no longer integrates exactly to the albedo. The spectral
    profiles (``spectral=True``) are never negative: a negative lobe of the model itself (only with
    ``boundaries="paper"``, none for the presets) is set to 0 and reported by a :class:`SpectralSkinWarning`.

    Arguments:
        melanin, melanin_blend, hemoglobin, oiliness, preset: as for :func:`evaluate`.
        spectral: False: RGB profiles; True: one profile per wavelength.
        accuracy, wavelength_step_nm, wavelength_placement, multipole_pairs, profile_r_min_mm, profile_r_max_mm,
            profile_count, combination, working_space: as for :func:`evaluate`.
        rgb_mapping: "linear" or "non_negative", see above.
        boundaries: "paper" or "capped", as for :func:`evaluate`.

    Returns:
        {"radii_mm": (N,), "rgb_per_mm2": (N, 3)} in mm^-2, or with spectral=True
        {"radii_mm": (N,), "spectral_per_mm2": (K, N), "wavelengths_nm": (K,)}.

    Raises:
        SpectralSkinError: as for :func:`evaluate`.
        TypeError: an argument of the wrong type.
    """

def parameter_ranges() -> dict[str, tuple[float, float]]:
    """The allowed range of each parameter.

    Returns:
        {"melanin": (0.0, 0.5), "melanin_blend": (0.0, 1.0), "hemoglobin": (0.0, 0.1), "oiliness": (0.0, 1.0)}:
        volume fractions (melanin of the epidermis, whole blood of the dermis), the eumelanin share, the oiliness.
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
    *,
    boundaries: _Boundaries | str = "paper",
) -> tuple[float, _FloatArray]:
    """Total diffuse reflectance and radial profile of a stack of layers under air (the diffusion solver alone).

    Uses the directional combination, the whole multipole series and the default inverse-Hankel quadrature. With the
    paper's boundaries a thin layer over layers that do not fill it can give a profile that is negative at some
    radii (the model's own lobe); it is returned clamped to 0 and reported by a :class:`SpectralSkinWarning` naming
    the radius and the depth relative to the peak. ``boundaries="capped"`` gives a profile that is non-negative and
    a total that is monotone in absorption by construction (docs/robustness.md, "Negative profile lobes").

    Arguments:
        layers: top to bottom, each (thickness_mm, sigma_a_per_mm, sigma_s_reduced_per_mm, ior): thickness in mm
            (float("inf") for a semi-infinite last layer), absorption and reduced scattering coefficients in mm^-1,
            index of refraction 1..2.
        radii_mm: 1-D radii in mm, finite and >= 0.
        boundaries: "paper" (the default) or "capped".

    Returns:
        (total diffuse reflectance, R(r) at radii_mm in mm^-2 as a float64 array of the same length).

    Raises:
        SpectralSkinError: no layers, a layer that is not 4 values, a thickness outside 1e-11..1e6 mm (inf only for
            the last layer), a coefficient other than 0 or 1e-12..1e6 per mm, an ior outside 1..2 (where the diffuse
            Fresnel fits hold), or a radius outside 0..1e6 mm.
        TypeError: layers or radii_mm not sequences of numbers.
    """

class _SpecularConstants(TypedDict):
    """The specular inputs of Principled BSDF for a constant oiliness (as ``evaluate(...)["specular"]``)."""

    oiliness: float
    specular_ior_level: float
    roughness: float
    ior: float
    beckmann_m: float
    directional_albedo_normal: float
    hemispherical_albedo: float

class _SpecularMapConstants(TypedDict):
    """The specular inputs of Principled BSDF that do not depend on the oiliness (when the oiliness varies)."""

    roughness: float
    ior: float
    beckmann_m: float

class _Maps(TypedDict, total=False):
    """The result of :func:`maps` (``specular_ior_level`` only when the oiliness varies)."""

    base_color: _Float32Array
    radius_mm: _Float32Array
    specular: _SpecularConstants | _SpecularMapConstants
    specular_ior_level: _Float32Array
    report: dict[str, Any]

def maps(
    params: _MapArray | None = None,
    *,
    melanin: _MapArray | float | None = None,
    melanin_blend: _MapArray | float | None = None,
    hemoglobin: _MapArray | float | None = None,
    oiliness: _MapArray | float | None = None,
    method: _Method | str = "burley",
    exact: bool = False,
    clamp: bool = False,
    accuracy: _AccuracyLevel | str = "default",
    wavelength_step_nm: float | None = None,
    wavelength_placement: _WavelengthPlacement | str | None = None,
    working_space: _WorkingSpace | str = "Linear Rec.709",
    table_resolution: tuple[int, int, int] | None = None,
    table_cache: bool = True,
    blender: _BlenderVersion | None = None,
    engine: _Engine | str = "cycles",
    progress: Callable[[int, int], bool | None] | None = None,
    boundaries: _Boundaries | str = "paper",
) -> _Maps:
    """Principled BSDF texture maps (Base Color, Subsurface Radius, specular) from per-texel parameter maps.

    The Python side of ``spectral-skin maps``, on numpy arrays instead of files. Row 0 is the top row, as numpy and
    EXR store images. Each texel is evaluated as :func:`evaluate` would, by the cheapest strategy that is exact enough:
    "constant" (one evaluation) when melanin, melanin_blend and hemoglobin each hold one value everywhere (floats, or
    arrays of one value); "distinct_tuples" (one evaluation per distinct (melanin, melanin_blend, hemoglobin)) when
    there are at most 2048 of them; otherwise "table": a lookup table built for the call and interpolated per texel,
    worst error below 0.5 % in albedo and 1 % in radius (its measured figures are in ``report["strategy"]``).
    ``exact=True`` evaluates every texel (or distinct tuple) directly instead of using the table: a few milliseconds
    of CPU per texel.

    The inputs are copied once into float32 planes (the core's type) before the GIL is released. float32 arrays are
    copied as they are; float64 arrays are converted to float32 in that same pass (no extra copy, but the values are
    rounded to float32 before the range check and the evaluation); non-contiguous arrays (slices, transposes, Fortran
    order) are gathered in that pass too. No other dtype is accepted: convert with ``a.astype(np.float32)``.

    Arguments:
        params: (H, W, 4) array, channels melanin, melanin_blend, hemoglobin, oiliness (in that order); None when
            each parameter is given by its keyword.
        melanin: C_m, melanin volume fraction of the epidermis, 0..0.5: an (H, W) array, a float (the same value
            everywhere), or None (take channel 0 of params). Given together with params, it replaces that channel.
        melanin_blend: beta_m, eumelanin share of the melanin, 0..1; as melanin (channel 1).
        hemoglobin: C_h, whole-blood volume fraction of the dermis, 0..0.1; as melanin (channel 2).
        oiliness: rho_s, scale of the surface's specular lobe, 0..1; as melanin (channel 3).
        method: the subsurface method the maps are for: "burley" (Christensen-Burley), "random_walk",
            "random_walk_legacy" (Blender 5.2 and later only) or "random_walk_skin".
        blender, engine: the target, as for :func:`evaluate`; the radius (and for the random walks Base Color) is
            computed for it per texel (for EEVEE from each texel's own albedo).
        exact: evaluate every texel (or distinct tuple) directly, never the table.
        clamp: clamp NaN (to the minimum), infinite and out-of-range values into range and count them in
            ``report["clamped"]``, instead of raising. The input arrays are not modified.
        accuracy: a named accuracy level, "draft", "default" or "reference", as for :func:`evaluate`.
        wavelength_step_nm, wavelength_placement: as for :func:`evaluate`.
        working_space: linear RGB space of Base Color, as for :func:`evaluate`: "Linear Rec.709" (Blender's
            default scene linear), "Linear Rec.2020" or "ACEScg"; use the scene's working space.
        table_cache: keep a built lookup table in the per-user cache folder ($SPECTRAL_SKIN_CACHE_DIR, else
            $XDG_CACHE_HOME/spectral-skin, else ~/.cache/spectral-skin) and reuse it (as the CLI does); False
            always builds it afresh.
        table_resolution: nodes per axis of the lookup table, (melanin, melanin_blend, hemoglobin), each >= 2;
            None: the core's default (chosen for the error bound above; the report names it). Used only by "table".
        progress: None, or a callable ``progress(done, total)`` told how many texels of ``total`` are done: once
            with 0 before the computation, with the same ``done`` about once per percent of a lookup table's nodes
            while one is built, then about once per percent as rows are filled (from the core's worker threads,
            taking the GIL for each call; a "constant" map has no rows to report). Returning False cancels: the
            rows (or table nodes) being computed are finished, the others skipped, nothing is returned and
            InterruptedError is raised. An exception raised by the callback cancels the same way and is re-raised.
        boundaries: the layers' boundary conditions, "paper" or "capped", as for :func:`evaluate` (a cached table
            is kept per choice).

    Ctrl-C (KeyboardInterrupt, or any exception a Python signal handler raises) stops the call the same way: the
    calling thread checks for signals every 0.1 s while the work runs, the rows or table nodes being computed are
    finished (a node is about a millisecond) and the exception is raised; a table stopped part-way is not cached.

    Returns:
        A dict:
        "base_color": float32 (H, W, 3), Principled Base Color for ``method``, linear RGB in ``working_space``;
        "radius_mm": float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale for ``method``, mm (with
        Radius set to these values, Scale is 0.001 in a scene whose unit is the metre);
        "specular": the specular constants, always: when the oiliness is one value everywhere (a float, or an
        array of one value), {"oiliness", "specular_ior_level", "roughness", "ior", "beckmann_m",
        "directional_albedo_normal", "hemispherical_albedo"} (as ``evaluate(...)["specular"]``); when it varies, the
        ones that do not depend on it: {"roughness", "ior", "beckmann_m"} (Principled IOR is 1.4 everywhere);
        "specular_ior_level": only when the oiliness varies, float32 (H, W): Principled Specular IOR Level per texel;
        "report": what was done: {"crate_version", "width", "height", "method", "target" ({"blender", "engine",
        "tested"}), "color_space", "strategy" ({"name":
        "constant" | "distinct_tuples" | "table" | "exact", with its figures: "tuples"; "evaluations"; or
        "resolution", "nodes", "from_cache", "build_seconds", "measured_error"}), "clamped" (one dict per parameter
        with bad values: {"parameter", "nan", "infinite", "out_of_range", "first": [[x, y], ...]}),
        "constant_parameters", "request" (accuracy and model), "seconds" ({"read", "compute", "write", "total"})}.
        The arrays are new, writeable and C-contiguous (handed to numpy without a copy).

    Raises:
        SpectralSkinError: a NaN, infinite or out-of-range value without clamp=True (the message names the parameter,
            its range, the counts and the first (x, y) coordinates); inputs whose (H, W) differ (the message lists
            each input's shape); params not (H, W, 4) or a keyword array not (H, W); an empty map or one over 2^28
            texels; only constants and no array; a parameter given neither by params nor by its keyword; an unknown
            method, a method the target's Blender lacks, an unknown working space or engine, a Blender version older
            than 4.2; a wavelength step out of range; a table resolution below 2 nodes per axis or over the core's node bound
            (checked before anything is allocated).
        TypeError: an input that is not a numpy array of float32 or float64 (or, for the keywords, a number): e.g. a
            list, an integer array, a string, a bool (Python's or numpy's); a non-integer in table_resolution; a
            progress that is not callable. The message names the argument. Non-contiguous and read-only arrays are
            read as they are.
        InterruptedError: the progress callback returned False.

    A SpectralSkinError for NaN, infinite or out-of-range texels (clamp=False) also has an attribute
    ``bad_texels``: {"parameter", "min", "max", "nan", "infinite", "out_of_range", "first": [(x, y), ...]}.
    """

def write_maps(
    result: Mapping[str, Any], folder: str | os.PathLike[str], prefix: str | None = None
) -> dict[str, pathlib.Path]:
    """Write the images of a :func:`maps` result as float EXRs, with the core's writer (that of ``spectral-skin maps``).

    Each image present (and not None) becomes one file in ``folder`` (created if missing): "base_color" ->
    ``albedo.exr`` (channels R, G, B), "radius_mm" -> ``radius.exr`` (R, G, B), "specular_ior_level" ->
    ``specular.exr`` (Y); with ``prefix``, ``<prefix>_albedo.exr`` etc. 32-bit float, PIZ compression, row 0 at the
    top. The files are written as temporary files in ``folder`` and renamed into place together once all are written,
    so a failure leaves the existing files as they were. Then the files of an earlier write with the same prefix that
    this one did not write (``albedo.exr``, ``radius.exr``, ``specular.exr``, ``skin_maps.json``) are removed, so the
    folder holds exactly this result's maps. No sidecar is written: the report is in the result.

    Arguments:
        result: a mapping with any of "base_color" (H, W, 3), "radius_mm" (H, W, 3) and "specular_ior_level" (H, W),
            float32 or float64 numpy arrays (float64 is rounded to float32); other keys are ignored. A result of
            :func:`maps`, or a part of one.
        folder: the output folder.
        prefix: None, or a file-name part prepended with "_" to each file name (no path separator).

    Returns:
        {"albedo" | "radius" | "specular": path of the file written}, for the images written.

    Raises:
        SpectralSkinError: no image in ``result``, images whose (H, W) differ, an image of the wrong shape, a prefix
            that is empty or holds a path separator; a file that cannot be written (the message names it).
        TypeError: an image that is not a float32 or float64 numpy array.
    """

def read_parameter_map(path: str | os.PathLike[str], name: _Parameter | str | None = None) -> dict[str, _Float32Array]:
    """Parameter maps read from a file with the core's reader: the formats and rules of ``spectral-skin maps``.

    Arguments:
        path: the file.
        name: None for the four-channel parameter EXR (as ``spectral-skin maps --params``; ``spectral-skin
            example`` writes one): channels named melanin, melanin_blend, hemoglobin and oiliness, all required.
            A parameter name ("melanin", "melanin_blend", "hemoglobin" or "oiliness") for that parameter's own map
            (as ``--melanin`` etc.): an EXR with exactly one channel (any name) or with a channel named like the
            parameter, whose values are the parameter itself; or an 8/16-bit greyscale PNG or TIFF, whose 0..1
            values map linearly onto the parameter's range (:func:`parameter_ranges`).

    Returns:
        {parameter name: float32 (H, W) array, row 0 at the top}: the four parameters, or the one named. Values are
        not range-checked (:func:`maps` does that).

    Raises:
        SpectralSkinError: a missing or unreadable file, an unsupported format, a missing channel or a multi-channel
            file without the parameter's channel (the message names the file and the channels found), an unknown
            name.
    """

def blender_targets() -> dict[str, Any]:
    """The Blender target table of the core, for fronts that derive their choices from it (the add-on).

    Returns:
        {"oldest_supported": "4.2", "current_release": "5.3", "default": {"blender", "engine", "tested"},
        "tested_versions": ["4.2", ...], "engines": [{"name": "cycles"}, {"name": "eevee"}],
        "methods": [{"name": "burley", "blender_id": "BURLEY"}, ...] (every method of any version),
        "versions": one entry per table row, oldest first: {"version": "4.2", "tested": bool (Cycles), "eevee_tested": bool,
        "engine_ids": {"cycles": "CYCLES", "eevee": "BLENDER_EEVEE_NEXT"}, "methods": [{"name", "blender_id",
        "tested", "model"}, ...] in Blender's menu order}. A version resolves to the newest row at or below it.
    """
