"""The panel's settings as a plain object, without bpy.

Validation of the parameters defers to the core: a value out of range fails when the plan is computed, with the
core's own message (``melanin must be in [0, 0.5] ...``).
"""

from __future__ import annotations

import dataclasses
import os
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import spectral_skin

from .colour import DEFAULT_WORKING_SPACE, WORKING_SPACES
from .maps import UDIM_TOKEN, stack_tiles
from .targets import method_name

if TYPE_CHECKING:
    from spectral_skin._core import _ParameterSpec

# The model's parameters, from the core's parameter table (src/skin/params.rs, ``spectral_skin.parameters()``): names,
# ranges, labels and meanings, for the UI (slider limits and tooltips) and for scaling 8/16-bit parameter images onto
# the range (as `spectral-skin maps` does). The core validates every value itself.
# PARAMETERS: the paper's four (no default: every material gives them), one per slider, Live-group input and
# parameter-map channel; EXTENDED_PARAMETERS: the extended physiology (each with the paper's value as its default).
_SPECS = spectral_skin.parameters()
PARAMETERS = tuple(p["name"] for p in _SPECS if p["default"] is None)
EXTENDED_PARAMETERS = tuple(p["name"] for p in _SPECS if p["default"] is not None)
# The extended parameters' defaults: the paper's values (the model of Donner & Jensen 2006 unless one is changed).
EXTENDED_DEFAULTS: dict[str, float] = {p["name"]: float(p["default"]) for p in _SPECS if p["default"] is not None}

# How Apply sets up the material: "BAKED" computes Base Color, Subsurface Radius and Specular IOR Level (values, or
# texture maps from parameter maps) with the core; "LIVE" wires the "Spectral Skin" node group (blender_addon/live.py),
# which computes them in the shader from its four inputs by looking them up in the core's shader table
# (docs/shader-table.md), so painted textures, drivers and keyframes show without another Apply.
MODES = ("BAKED", "LIVE")

# The core's named accuracy levels, cheapest first (``spectral_skin.accuracy_levels()``; docs/accuracy-vs-time.md):
# Blender's enum identifier -> the core's name; ACCURACY_DESCRIPTIONS: the core's one-line description of each.
ACCURACY_LEVELS = {a["name"].upper(): a["name"] for a in spectral_skin.accuracy_levels()}
ACCURACY_DESCRIPTIONS = {a["name"].upper(): a["description"] for a in spectral_skin.accuracy_levels()}

# The core's transports (``spectral_skin.transports()``): how each wavelength's total diffuse reflectance is computed
# (exact adding-doubling, the core's default, or the paper's diffusion). Blender's enum identifier -> the core's name;
# TRANSPORT_DESCRIPTIONS: the core's one line for each; DEFAULT_TRANSPORT: the identifier of the core's default.
TRANSPORTS = {t["name"].upper(): t["name"] for t in spectral_skin.transports()}
TRANSPORT_DESCRIPTIONS = {t["name"].upper(): t["description"] for t in spectral_skin.transports()}
DEFAULT_TRANSPORT = next(t["name"].upper() for t in spectral_skin.transports() if t["default"])

# The core's surface models (``spectral_skin.surface_models()``): which surface reflection the specular inputs stand
# in for (the measured two-lobe skin with a Coat, or the paper's oil layer). Blender's enum identifier -> the core's
# name; SURFACE_DESCRIPTIONS: the core's one line for each; DEFAULT_SURFACE: the identifier of the core's default.
SURFACES = {m["name"].upper(): m["name"] for m in spectral_skin.surface_models()}
SURFACE_DESCRIPTIONS = {m["name"].upper(): m["description"] for m in spectral_skin.surface_models()}
DEFAULT_SURFACE = next(m["name"].upper() for m in spectral_skin.surface_models() if m["default"])

# Greek letters for the core's ASCII-spelled symbols ("beta_m" -> "β_m"), for labels.
_GREEK = {"beta": "β", "rho": "ρ"}


def _symbol(ascii_symbol: str) -> str:
    head, _, tail = ascii_symbol.partition("_")
    return _GREEK.get(head, head) + (f"_{tail}" if tail else "")


class ParameterInfo(NamedTuple):
    """One parameter as the UI shows it: slider limits, label and tooltip."""

    low: float
    high: float
    label: str
    description: str


def _info(spec: _ParameterSpec) -> ParameterInfo:
    low, high, symbol, meaning = spec["min"], spec["max"], _symbol(spec["symbol"]), spec["description"]
    unit = f", {spec['unit']}" if spec.get("unit") else ""
    return ParameterInfo(low, high, f"{spec['label']} ({symbol}{unit})",
                         f"{meaning[:1].upper()}{meaning[1:]}, {symbol} ({low:g} to {high:g}): {spec['effect']}")


PARAMETER_INFO = {p["name"]: _info(p) for p in _SPECS}

# The core's presets (``spectral_skin.presets()``) as plain dicts, name -> {parameter: value}, an extended parameter a
# preset leaves out at its default; the default preset (a new material's values, the batch script's default) is
# the core's first.
PRESETS: dict[str, dict[str, Any]] = {name: {**EXTENDED_DEFAULTS, **dict(p)}
                                      for name, p in spectral_skin.presets().items()}
DEFAULT_PRESET = next(iter(PRESETS))


@dataclass
class ParameterMap:
    """One parameter's map: pixel values as an (H, W) float32 array, row 0 at the top.

    ``normalized`` is True for 8/16-bit images, whose 0..1 values map linearly onto the parameter's range; False for
    float images, whose values are the parameter itself. ``notes``: what the core's reader accepted but ignored (an
    alpha channel, a channel of no parameter's name), one sentence each naming the file: Apply reports them.
    """

    pixels: object  # numpy.ndarray, (H, W)
    normalized: bool
    name: str = ""
    notes: tuple[str, ...] = ()
    # A UDIM tile set stacked top to bottom: (tile number, rows) of each tile; () for a single image.
    tiles: tuple[tuple[int, int], ...] = ()


def read_tile_set(pattern: str, tiles: list[int], name: str | None = None) -> dict[str, ParameterMap]:
    """A UDIM tile set's parameter maps (``pattern`` holds ``<UDIM>``; ``tiles`` its tile numbers, as Blender lists a
    tiled image's), each tile read by :func:`read_map_file`, stacked top to bottom in tile order into one map per
    parameter (the core computes a tile set as one texture, :func:`~core.maps.stack_tiles`) with ``tiles`` recording
    each tile's rows. ValueError when a tile lacks a map or the tiles' widths differ (naming them)."""
    if UDIM_TOKEN not in os.path.basename(pattern):
        raise ValueError(f"{pattern}: a tile set's file name holds {UDIM_TOKEN}")
    read = [(tile, read_map_file(pattern.replace(UDIM_TOKEN, str(tile)), name)) for tile in sorted(tiles)]
    if not read:
        raise ValueError(f"{pattern}: the tile set has no tiles")
    stacked: dict[str, ParameterMap] = {}
    for parameter in read[0][1]:
        planes = [(tile, maps[parameter]) for tile, maps in read if parameter in maps]
        if len(planes) != len(read):
            raise ValueError(f"{pattern}: every tile must have the {parameter} map to be computed as one texture; found "
                             f"it in {len(planes)} of {len(read)} tiles")
        pixels, rows = stack_tiles([(tile, m.pixels) for tile, m in planes], f"{pattern} ({parameter})")
        stacked[parameter] = ParameterMap(pixels=pixels, normalized=planes[0][1].normalized, name=pattern,
                                          notes=tuple(dict.fromkeys(n for _, m in planes for n in m.notes)), tiles=rows)
    return stacked


def read_map_file(path: str, name: str | None = None) -> dict[str, ParameterMap]:
    """Parameter maps from a file, read by the core with the CLI's rules (``spectral_skin.read_parameter_map``):
    ``name`` None for the four-channel parameter EXR (channels melanin, melanin_blend, hemoglobin, oiliness), else
    that parameter's own map (any form the core accepts: a one-channel EXR of any channel name, a grey RGB(A) EXR as
    Blender saves one, an 8/16-bit greyscale or grey RGB PNG/TIFF/JPEG mapped onto the parameter's range). Values
    come back in the parameter's own unit; the core's warnings (``SpectralSkinWarning``) become the maps' ``notes``.
    Raises ``spectral_skin.SpectralSkinError`` naming the file, what it found and what is accepted."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", spectral_skin.SpectralSkinWarning)
        planes = spectral_skin.read_parameter_map(path, name)
    notes = tuple(str(w.message) for w in caught if issubclass(w.category, spectral_skin.SpectralSkinWarning))
    for w in caught:  # anything else goes on as it came
        if not issubclass(w.category, spectral_skin.SpectralSkinWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return {p: ParameterMap(pixels=pixels, normalized=False, name=path, notes=notes) for p, pixels in planes.items()}


@dataclass
class SkinSettings:
    """Everything the Apply operator needs, read from the material's properties or given by a batch script."""

    # The default preset's values (PRESETS[DEFAULT_PRESET], from the core).
    melanin: float = float(PRESETS[DEFAULT_PRESET]["melanin"])
    melanin_blend: float = float(PRESETS[DEFAULT_PRESET]["melanin_blend"])
    hemoglobin: float = float(PRESETS[DEFAULT_PRESET]["hemoglobin"])
    oiliness: float = float(PRESETS[DEFAULT_PRESET]["oiliness"])
    # Principled subsurface_method id (the methods the Blender version offers: core/targets.py).
    method: str = "BURLEY"
    # The target: Blender version "MAJOR.MINOR" (None: the core's current release) and engine ("cycles", "eevee").
    # In Blender both come from the running Blender and the scene (bpy glue).
    blender: str | None = None
    engine: str = "cycles"
    # Accuracy level of the spectral computation (a key of ACCURACY_LEVELS).
    accuracy: str = "DEFAULT"
    # How the totals are computed (a key of TRANSPORTS; the Advanced settings).
    transport: str = DEFAULT_TRANSPORT
    # The surface reflection the specular inputs stand in for (a key of SURFACES).
    surface: str = DEFAULT_SURFACE
    # parameter name -> ParameterMap; a parameter with a map ignores its constant.
    maps: dict[str, ParameterMap] = field(default_factory=dict)
    # Clamp NaN, infinite and out-of-range texels of the maps into range instead of refusing them.
    clamp: bool = False
    # Absolute folder for the texture maps (needed only when maps are given).
    output_dir: str = ""
    # Name used for the texture files: <prefix>_albedo.exr etc. (see plan.texture_prefix).
    file_prefix: str = "skin"
    # Blender's scene.unit_settings.scale_length: metres per scene unit.
    scale_length: float = 1.0
    # The blend file's scene-linear working space (bpy.data.colorspace.working_space in Blender 5.0): the space of
    # Base Color and of the albedo texture.
    working_space: str = DEFAULT_WORKING_SPACE
    # "BAKED" or "LIVE" (MODES).
    mode: str = "BAKED"
    # The extended physiology (EXTENDED_PARAMETERS: one value per material, unless a parameter EXR holds a varying
    # channel of it: with_maps), the paper's values by default (the core's table).
    epidermis_thickness_mm: float = EXTENDED_DEFAULTS["epidermis_thickness_mm"]
    baseline_absorption_scale: float = EXTENDED_DEFAULTS["baseline_absorption_scale"]
    blood_oxygenation: float = EXTENDED_DEFAULTS["blood_oxygenation"]

    @classmethod
    def from_preset(cls, name: str, **overrides: object) -> SkinSettings:
        """Settings with a preset's parameters (:data:`PRESETS`: the four and the extended ones, the default where a
        preset leaves one out), then ``overrides``."""
        key = name.lower()
        if key not in PRESETS:
            raise spectral_skin.SpectralSkinError(
                f"unknown preset {name!r}; expected one of {', '.join(sorted(PRESETS))}")
        values: dict[str, object] = {p: PRESETS[key][p] for p in (*PARAMETERS, *EXTENDED_PARAMETERS)}
        values.update(overrides)
        return cls(**values)  # type: ignore[arg-type]

    # What with_maps decided that an artist should read (an extended value taken from a map), one sentence each.
    notes: tuple[str, ...] = ()

    def replace(self, **changes: object) -> SkinSettings:
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]

    def with_maps(self, maps: dict[str, ParameterMap]) -> SkinSettings:
        """The settings with parameter maps. An extended-physiology map (a channel of a parameter EXR, as the albedo
        fit writes one) of one value everywhere is that parameter's value: it replaces the material's, with a note
        where they differ, so a constant map costs one evaluation and Live mode can use it. A varying one stays a map:
        Baked mode computes it per texel; Live mode refuses it (:func:`check`)."""
        import numpy as np

        kept: dict[str, ParameterMap] = {}
        values: dict[str, float] = {}
        notes = list(self.notes)
        for name, pmap in maps.items():
            pixels = np.asarray(pmap.pixels, dtype=np.float32)
            if name in EXTENDED_PARAMETERS and pixels.size and bool(np.all(pixels == pixels.flat[0])):
                value = float(pixels.flat[0])
                if pmap.normalized:
                    low, high = PARAMETER_INFO[name][:2]
                    value = low + value * (high - low)
                if value != float(getattr(self, name)):
                    notes.append(f"{name} = {value:g} from the map {pmap.name} (not the material's "
                                 f"{float(getattr(self, name)):g})")
                values[name] = value
                continue
            kept[name] = pmap
        return self.replace(maps=kept, notes=tuple(notes), **values)

    def constants(self) -> dict[str, float]:
        """The paper's four parameters' constants (a parameter with a map ignores its constant)."""
        return {p: float(getattr(self, p)) for p in PARAMETERS}

    def extended(self) -> dict[str, Any]:
        """The extended physiology's values (EXTENDED_PARAMETERS), one per material."""
        return {p: float(getattr(self, p)) for p in EXTENDED_PARAMETERS}

    def changed_extended(self) -> dict[str, Any]:
        """The extended values that differ from the paper's (the defaults): what a core call must be given."""
        return {p: v for p, v in self.extended().items() if v != EXTENDED_DEFAULTS[p]}

    def transport_keywords(self) -> dict[str, Any]:
        """The core's ``transport=`` keyword for the settings' transport: given whenever it is not the core's
        default (the default calls the core as before, as the extended physiology's keywords do)."""
        return {} if self.transport == DEFAULT_TRANSPORT else {"transport": TRANSPORTS[self.transport]}

    def surface_name(self) -> str:
        """The core's ``surface=`` name of the settings' surface model."""
        return SURFACES[self.surface]

    def surface_reflects_dry(self) -> bool:
        """Whether the surface reflects where the oiliness is zero (every model but the paper's oil layer)."""
        return self.surface_name() != "paper"


def check(settings: SkinSettings) -> None:
    """Raise ``spectral_skin.SpectralSkinError`` (a ValueError) for settings Blender would reject."""
    import spectral_skin

    method_name(settings.method)  # raises for an unknown method; the core checks the version offers it
    if settings.accuracy not in ACCURACY_LEVELS:
        raise spectral_skin.SpectralSkinError(
            f"accuracy must be one of {', '.join(ACCURACY_LEVELS)}; got {settings.accuracy!r}")
    if settings.transport not in TRANSPORTS:
        raise spectral_skin.SpectralSkinError(
            f"transport must be one of {', '.join(TRANSPORTS)}; got {settings.transport!r}")
    if settings.surface not in SURFACES:
        raise spectral_skin.SpectralSkinError(
            f"surface must be one of {', '.join(SURFACES)}; got {settings.surface!r}")
    if not settings.scale_length > 0.0:
        raise spectral_skin.SpectralSkinError(
            f"scene unit scale must be > 0 (metres per scene unit); got {settings.scale_length}")
    if settings.working_space not in WORKING_SPACES:
        raise spectral_skin.SpectralSkinError(
            f"working space must be one of {', '.join(WORKING_SPACES)}; got {settings.working_space!r}")
    if settings.mode not in MODES:
        raise spectral_skin.SpectralSkinError(f"mode must be one of {', '.join(MODES)}; got {settings.mode!r}")
    unknown = set(settings.maps) - set(PARAMETERS) - set(EXTENDED_PARAMETERS)
    if unknown:
        raise spectral_skin.SpectralSkinError(
            f"parameter maps must be among {', '.join((*PARAMETERS, *EXTENDED_PARAMETERS))}; got "
            f"{', '.join(sorted(unknown))}")
    tile_sets = {m.tiles for m in settings.maps.values()}
    if len(tile_sets) > 1:
        raise spectral_skin.SpectralSkinError(
            "the parameter maps must all be one UDIM tile set (the same tiles) or all single images; got "
            + "; ".join(f"{name}: {[t for t, _ in m.tiles] or 'one image'}" for name, m in settings.maps.items()))
    varying = [name for name in EXTENDED_PARAMETERS if name in settings.maps]
    if varying and settings.mode == "LIVE":
        raise spectral_skin.SpectralSkinError(
            f"Live mode takes one value of {', '.join(varying)} per material, but the map "
            f"{settings.maps[varying[0]].name} varies over the texture: use Baked mode, or a map of one value")
    if settings.maps and not settings.output_dir and settings.mode == "BAKED":
        raise spectral_skin.SpectralSkinError("an output folder for the texture maps is required with parameter maps")
    # The parameter values themselves are validated by the core when the plan is computed.
