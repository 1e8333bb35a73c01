"""Type stubs of spectral-skin's compiled core (src/python/): types only.

Each function's documentation (arguments, units, returns, raises) lives once, in the Rust doc comment of its
``#[pyfunction]``, which pyo3 makes the function's ``__doc__``: read it with ``help(spectral_skin.evaluate)``.
Units: lengths in mm, coefficients in mm^-1, radial profiles in mm^-2, wavelengths in nm. Arrays are numpy float64,
except the images of :func:`maps` (float32). Every function releases the GIL while the core computes.
"""

import os
import pathlib
from collections.abc import Callable, ItemsView, Iterable, Iterator, KeysView, Mapping, Sequence, ValuesView
from typing import Any, Literal, NotRequired, TypedDict, final, overload

import numpy as np
import numpy.typing as npt

__all__ = [
    "MODEL_VERSION",
    "AlbedoMapFit",
    "Maps",
    "SpectralSkinError",
    "SpectralSkinIOError",
    "SpectralSkinWarning",
    "__version__",
    "_cli_main",
    "_markdown_stamp",
    "_png_stamp_version",
    "_stamp_png",
    "_write_markdown_blocks",
    "accuracy_levels",
    "blender_targets",
    "cielab",
    "delta_e00",
    "evaluate",
    "fit_albedo",
    "fit_albedo_map",
    "fit_spectra",
    "fit_spectrum",
    "layered_reflectance",
    "map_kinds",
    "maps",
    "parameter_ranges",
    "parameters",
    "presets",
    "profile",
    "read_parameter_map",
    "shader_table",
    "surface_albedo",
    "surface_brdf",
    "surface_input_nodes",
    "surface_models",
    "transports",
    "write_maps",
    "write_shader_table",
]

__version__: str
MODEL_VERSION: int

def _markdown_stamp(command: str) -> str: ...
def _write_markdown_blocks(path: str | os.PathLike[str], command: str, blocks: Sequence[tuple[str, str]]) -> None: ...
def _stamp_png(path: str | os.PathLike[str], command: str) -> None: ...
def _png_stamp_version(path: str | os.PathLike[str]) -> int | None: ...

_FloatArray = npt.NDArray[np.float64]
_Float32Array = npt.NDArray[np.float32]
_MapArray = npt.NDArray[np.float32] | npt.NDArray[np.float64]

_Combination = Literal["directional", "symmetric"]
_WorkingSpace = Literal["Linear Rec.709", "Linear Rec.2020", "ACEScg"]
_Method = Literal["burley", "random_walk", "random_walk_legacy", "random_walk_skin"]
_Engine = Literal["cycles", "eevee"]
_Precision = Literal["half", "float"]
_Compression = Literal["auto", "piz", "zip", "zips", "rle", "none"]
_BlenderVersion = str | tuple[int, int] | tuple[int, int, int]
_AccuracyLevel = Literal["draft", "default", "reference"]
_WavelengthPlacement = Literal["uniform", "cmf_adapted", "rgb_shortcut"]
_Parameter = Literal["melanin", "melanin_blend", "hemoglobin", "oiliness"]
_ExtendedParameter = Literal["epidermis_thickness_mm", "baseline_absorption_scale", "blood_oxygenation"]
_RgbMapping = Literal["linear", "non_negative"]
_Boundaries = Literal["paper", "capped"]
_Transport = Literal["adding_doubling", "diffusion"]
_SurfaceModel = Literal["measured", "paper"]
_OutputName = Literal["albedo", "radius", "profile_rgb", "profile_spectral", "spectrum", "specular"]
_MapOutputName = Literal["albedo", "radius", "specular"]
_MapName = Literal["albedo", "radius", "specular", "coat_weight", "coat_roughness"]

class SpectralSkinError(ValueError):
    """Invalid input to spectral-skin.

    The message names the input, its allowed range and the value received, e.g.
    ``melanin must be in [0, 0.5] (melanin volume fraction of the epidermis); got 0.7``.
    """

class SpectralSkinIOError(OSError):
    """A file spectral-skin could not read or write; the message names it and says what went wrong.

    ``errno`` is the operating system's error code where it gave one (e.g. ``errno.ENOENT``), else None.
    """

class SpectralSkinWarning(UserWarning):
    """A result computed but changed on its way out: a negative lobe of a radial profile set to 0.

    With the paper's boundaries (``boundaries="paper"``, the default) a layer thinner than its extrapolation
    distances, over layers that do not fill it, gives a profile that is negative at some radii: the diffusion model's
    own lobe, not round-off (docs/robustness.md, "Negative profile lobes"). The profile returned is clamped to 0 and
    this warning says where and how deep; ``boundaries="capped"`` gives a profile that is non-negative by
    construction. No preset has such a lobe.

    Also raised by :func:`read_parameter_map` for what it read but ignored: an alpha channel, or a channel of the
    four-channel file named like no parameter (a misspelt ``hemoglobn``), the message naming the file and the known
    channel names.
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
    epidermis_thickness_mm: float | None = None,
    baseline_absorption_scale: float | None = None,
    blood_oxygenation: float | None = None,
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
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    surface: _SurfaceModel | str | None = None,
    model: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Documented once, in the compiled module: ``help(spectral_skin.evaluate)``."""

def profile(
    melanin: float | None = None,
    melanin_blend: float | None = None,
    hemoglobin: float | None = None,
    oiliness: float | None = None,
    *,
    epidermis_thickness_mm: float | None = None,
    baseline_absorption_scale: float | None = None,
    blood_oxygenation: float | None = None,
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
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    model: Mapping[str, Any] | None = None,
) -> dict[str, _FloatArray]:
    """Documented once, in the compiled module: ``help(spectral_skin.profile)``."""

class _ParameterSpec(TypedDict):
    """One parameter of the core's parameter table (see :func:`parameters`)."""

    name: str
    symbol: str
    label: str
    description: str
    effect: str
    unit: str
    min: float
    max: float
    default: float | None
    source: str

class _AccuracyLevelSpec(TypedDict):
    """A named accuracy level (see :func:`accuracy_levels`)."""

    name: str
    description: str

def parameters() -> list[_ParameterSpec]:
    """Documented once, in the compiled module: ``help(spectral_skin.parameters)``."""

def parameter_ranges() -> dict[str, tuple[float, float]]:
    """Documented once, in the compiled module: ``help(spectral_skin.parameter_ranges)``."""

def accuracy_levels() -> list[_AccuracyLevelSpec]:
    """Documented once, in the compiled module: ``help(spectral_skin.accuracy_levels)``."""

class _TransportSpec(TypedDict):
    """A transport (see :func:`transports`)."""

    name: str
    description: str
    default: bool

def transports() -> list[_TransportSpec]:
    """Documented once, in the compiled module: ``help(spectral_skin.transports)``."""

class _SurfaceModelSpec(TypedDict):
    name: _SurfaceModel
    description: str
    default: bool

def surface_models() -> list[_SurfaceModelSpec]:
    """Documented once, in the compiled module: ``help(spectral_skin.surface_models)``."""

def presets() -> dict[str, _Preset]:
    """Documented once, in the compiled module: ``help(spectral_skin.presets)``."""

def layered_reflectance(
    layers: Iterable[Sequence[float]],
    radii_mm: npt.ArrayLike,
    *,
    boundaries: _Boundaries | str = "paper",
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
) -> tuple[float, _FloatArray]:
    """Documented once, in the compiled module: ``help(spectral_skin.layered_reflectance)``."""

class _SpecularConstants(TypedDict):
    """The specular inputs of Principled BSDF for a constant oiliness (as ``evaluate(...)["specular"]``)."""

    surface: _SurfaceModel
    oiliness: float
    specular_ior_level: float
    roughness: float
    ior: float
    coat_weight: float
    coat_roughness: float
    coat_ior: float
    beckmann_m: float
    directional_albedo_normal: float
    hemispherical_albedo: float

class _SpecularMapConstants(TypedDict):
    """The specular inputs of Principled BSDF that do not depend on the oiliness (when the oiliness varies); the
    ``paper`` surface's Coat too (weight 0)."""

    surface: _SurfaceModel
    roughness: float
    ior: float
    coat_ior: float
    beckmann_m: float
    coat_weight: NotRequired[float]
    coat_roughness: NotRequired[float]

@final
class Maps(Mapping[str, Any]):
    """Documented once, in the compiled module: ``help(spectral_skin.Maps)``."""

    @property
    def albedo(self) -> _Float32Array | None: ...
    @property
    def radius(self) -> _Float32Array | None: ...
    @property
    def specular(self) -> _Float32Array | None: ...
    @property
    def coat_weight(self) -> _Float32Array | None: ...
    @property
    def coat_roughness(self) -> _Float32Array | None: ...
    @property
    def specular_constants(self) -> _SpecularConstants | _SpecularMapConstants | None: ...
    @property
    def report(self) -> dict[str, Any]: ...
    @property
    def shape(self) -> tuple[int, int]: ...
    @overload
    def __getitem__(self, key: _MapName, /) -> _Float32Array: ...
    @overload
    def __getitem__(self, key: Literal["specular_constants"], /) -> _SpecularConstants | _SpecularMapConstants: ...
    @overload
    def __getitem__(self, key: Literal["report"], /) -> dict[str, Any]: ...
    @overload
    def __getitem__(self, key: str, /) -> Any: ...
    def __contains__(self, key: object, /) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def keys(self) -> KeysView[str]: ...
    def values(self) -> ValuesView[Any]: ...
    def items(self) -> ItemsView[str, Any]: ...
    @overload
    def get(self, key: str, default: None = None) -> Any | None: ...
    @overload
    def get(self, key: str, default: Any) -> Any: ...
    def write(
        self,
        folder: str | os.PathLike[str],
        prefix: str | None = None,
        precision: _Precision | str = "half",
        compression: _Compression | str = "auto",
        tiles: Sequence[tuple[int, int]] | None = None,
    ) -> dict[str, pathlib.Path]: ...

def maps(
    params: _MapArray | None = None,
    *,
    melanin: _MapArray | float | None = None,
    melanin_blend: _MapArray | float | None = None,
    hemoglobin: _MapArray | float | None = None,
    oiliness: _MapArray | float | None = None,
    epidermis_thickness_mm: _MapArray | float | None = None,
    baseline_absorption_scale: _MapArray | float | None = None,
    blood_oxygenation: _MapArray | float | None = None,
    method: _Method | str = "burley",
    outputs: Iterable[_MapOutputName | str] | None = None,
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
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    surface: _SurfaceModel | str | None = None,
    model: Mapping[str, Any] | None = None,
) -> Maps:
    """Documented once, in the compiled module: ``help(spectral_skin.maps)``."""

def write_maps(
    result: Maps | Mapping[str, Any],
    folder: str | os.PathLike[str],
    prefix: str | None = None,
    precision: _Precision | str = "half",
    compression: _Compression | str = "auto",
    tile: int | None = None,
    tiles: Sequence[tuple[int, int]] | None = None,
) -> dict[str, pathlib.Path]:
    """Documented once, in the compiled module: ``help(spectral_skin.write_maps)``."""

class _ShaderAxis(TypedDict):
    nodes: int
    min: float
    max: float
    warp: Literal["cube_root", "linear"]

class _ShaderTableMetadata(TypedDict):
    format: str
    crate_version: str
    model_version: int
    method: str
    blender: str
    engine: str
    color_space: str
    width: int
    height: int
    slice_width: int
    gutter: int
    melanin: _ShaderAxis
    melanin_blend: _ShaderAxis
    hemoglobin: _ShaderAxis
    stored: Literal["ln"]
    request: dict[str, Any]
    extended: dict[_ExtendedParameter, float]

class _ShaderTable(TypedDict):
    """The result of :func:`shader_table`."""

    base_color_log: _Float32Array
    radius_log: _Float32Array
    metadata: _ShaderTableMetadata

def shader_table(
    *,
    method: _Method | str = "burley",
    blender: _BlenderVersion | None = None,
    engine: _Engine | str = "cycles",
    resolution: tuple[int, int, int] | None = None,
    accuracy: _AccuracyLevel | str = "default",
    working_space: _WorkingSpace | str = "Linear Rec.709",
    boundaries: _Boundaries | str = "paper",
    table_cache: bool = True,
    epidermis_thickness_mm: float | None = None,
    baseline_absorption_scale: float | None = None,
    blood_oxygenation: float | None = None,
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
) -> _ShaderTable:
    """Documented once, in the compiled module: ``help(spectral_skin.shader_table)``."""

def write_shader_table(
    result: Mapping[str, Any], folder: str | os.PathLike[str], prefix: str | None = None
) -> dict[str, pathlib.Path]:
    """Documented once, in the compiled module: ``help(spectral_skin.write_shader_table)``."""

class _MapKindSpec(TypedDict):
    name: _MapName
    file: str
    channels: list[str]
    unit: str
    principled_input: str
    color_space: Literal["Non-Color"] | None
    output: _MapOutputName

def map_kinds() -> list[_MapKindSpec]:
    """Documented once, in the compiled module: ``help(spectral_skin.map_kinds)``."""

def read_parameter_map(
    path: str | os.PathLike[str], name: _Parameter | _ExtendedParameter | str | None = None
) -> dict[str, _Float32Array]:
    """Documented once, in the compiled module: ``help(spectral_skin.read_parameter_map)``."""

def blender_targets() -> dict[str, Any]:
    """Documented once, in the compiled module: ``help(spectral_skin.blender_targets)``."""

def fit_albedo(
    rgb: Sequence[float] | _FloatArray,
    *,
    working_space: _WorkingSpace | str = "Linear Rec.709",
    epidermis_thickness_mm: float | None = None,
    baseline_absorption_scale: float | None = None,
    blood_oxygenation: float | None = None,
    oiliness: float | None = None,
    melanin_blend_prior: float | None = None,
    prior_weight: float | None = None,
    ambiguity_delta_e: float | None = None,
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    rgb_gains: npt.ArrayLike | None = None,
) -> dict[str, Any]:
    """Documented once, in the compiled module: ``help(spectral_skin.fit_albedo)``."""

def fit_albedo_map(
    albedo: _MapArray,
    *,
    working_space: _WorkingSpace | str = "Linear Rec.709",
    epidermis_thickness_mm: float | None = None,
    baseline_absorption_scale: float | None = None,
    blood_oxygenation: float | None = None,
    oiliness: float | None = None,
    melanin_blend_prior: float | None = None,
    prior_weight: float | None = None,
    ambiguity_delta_e: float | None = None,
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    rgb_gains: npt.ArrayLike | Literal["auto"] | None = None,
    mask: npt.NDArray[np.bool_] | _MapArray | None = None,
    progress: Callable[[int, int], bool | None] | None = None,
) -> AlbedoMapFit:
    """Documented once, in the compiled module: ``help(spectral_skin.fit_albedo_map)``."""

class _ThicknessChoice(TypedDict):
    screened: list[list[float]]
    sampled_texels: int | None
    whole_texture: list[list[float]]
    chosen_mm: float

@final
class AlbedoMapFit:
    """Documented once, in the compiled module: ``help(spectral_skin.AlbedoMapFit)``."""

    @property
    def params(self) -> _Float32Array: ...
    @property
    def residual_delta_e00(self) -> _Float32Array: ...
    @property
    def extended(self) -> dict[str, float]: ...
    @property
    def stats(self) -> dict[str, Any]: ...
    @property
    def thickness(self) -> _ThicknessChoice | None: ...
    @property
    def gains(self) -> dict[str, Any] | None: ...
    @property
    def diagnosis(self) -> str | None: ...
    @property
    def shape(self) -> tuple[int, int]: ...
    def write(
        self,
        path: str | os.PathLike[str],
        residual_path: str | os.PathLike[str] | None = None,
        tiles: Sequence[tuple[int, int]] | None = None,
    ) -> None: ...
def _cli_main(argv: list[str]) -> int:
    """The console script's entry (spectral_skin._cli), not an API: help(spectral_skin._core._cli_main)."""
    ...

def cielab(
    rgb: npt.ArrayLike,
    *,
    working_space: _WorkingSpace | str = "Linear Rec.709",
    white_luminance: float = 1.0,
) -> npt.NDArray[np.float64]:
    """Documented once, in the compiled module: ``help(spectral_skin.cielab)``."""
    ...

def delta_e00(
    reference: npt.ArrayLike,
    test: npt.ArrayLike,
    *,
    working_space: _WorkingSpace | str = "Linear Rec.709",
    white_luminance: float = 1.0,
) -> npt.NDArray[np.float64]:
    """Documented once, in the compiled module: ``help(spectral_skin.delta_e00)``."""
    ...

def surface_brdf(
    theta_in_deg: npt.ArrayLike,
    theta_out_deg: npt.ArrayLike,
    phi_deg: npt.ArrayLike = 180.0,
    *,
    oiliness: float = 0.3,
    surface: _SurfaceModel | str = "measured",
) -> npt.NDArray[np.float64]:
    """Documented once, in the compiled module: ``help(spectral_skin.surface_brdf)``."""
    ...

class _SurfaceInputNodes(TypedDict):
    surface: _SurfaceModel
    oiliness: list[float]
    specular_ior_level: list[float]
    coat_weight: list[float]
    coat_roughness: list[float]

def surface_input_nodes(
    surface: _SurfaceModel | str | None = None,
    *,
    blender: _BlenderVersion | None = None,
    engine: _Engine | str = "cycles",
) -> _SurfaceInputNodes:
    """Documented once, in the compiled module: ``help(spectral_skin.surface_input_nodes)``."""

def surface_albedo(
    theta_in_deg: npt.ArrayLike,
    *,
    oiliness: float = 0.3,
    surface: _SurfaceModel | str = "measured",
) -> npt.NDArray[np.float64]:
    """Documented once, in the compiled module: ``help(spectral_skin.surface_albedo)``."""
    ...

def fit_spectrum(
    wavelengths_nm: npt.ArrayLike,
    reflectance: npt.ArrayLike,
    *,
    free: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
    specular: Literal["free", "fresnel"] | float | None = None,
    objective: Literal["reflectance", "cielab"] = "reflectance",
    starts: int | None = None,
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    bandpass: Literal["spacing"] | float | None = None,
    aperture: Literal["cm2600d-mav", "cm2600d-sav"] | str | None = None,
    model: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Documented once, in the compiled module: ``help(spectral_skin.fit_spectrum)``."""

def fit_spectra(
    wavelengths_nm: npt.ArrayLike,
    reflectances: npt.ArrayLike,
    *,
    free: Sequence[str] | None = None,
    fixed: Mapping[str, float] | None = None,
    specular: Literal["free", "fresnel"] | float | None = None,
    objective: Literal["reflectance", "cielab"] = "reflectance",
    starts: int | None = None,
    transport: _Transport | str = "adding_doubling",
    streams: int | None = None,
    bandpass: Literal["spacing"] | float | None = None,
    aperture: Literal["cm2600d-mav", "cm2600d-sav"] | str | None = None,
    model: Mapping[str, Any] | None = None,
    progress: Callable[[int, int], bool | None] | None = None,
) -> list[dict[str, Any]]:
    """Documented once, in the compiled module: ``help(spectral_skin.fit_spectra)``."""
