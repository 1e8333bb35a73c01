"""The core's answer for one material, computed before anything in Blender changes (no bpy here).

:func:`compute` asks the core once (``spectral_skin.evaluate`` for constants, ``spectral_skin.maps`` for parameter
maps) for only the outputs asked for, and gathers the answer into a :class:`Computed`: frozen, typed, the core's
``Maps`` result held as it came (its texels are never copied into Python's own arrays). The scene analysis
(core/scene.py) decides from it, and :func:`~core.material_plan.build_plan` builds the material plan from it and the
decisions. Nothing changes it.
"""

from __future__ import annotations

import inspect
import os
import re
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import spectral_skin

from .maps import map_kinds
from .settings import (
    ACCURACY_LEVELS,
    DEFAULT_TRANSPORT,
    EXTENDED_PARAMETERS,
    PARAMETER_INFO,
    PARAMETERS,
    TRANSPORTS,
    SkinSettings,
    check,
)
from .targets import method_name

METRES_PER_MM = 1e-3

# Per core function: whether it takes the extended physiology as keywords (inspected once).
_TAKES_EXTENDED: dict[Any, bool] = {}


def _takes_extended(function: Callable[..., Any]) -> bool:
    if function not in _TAKES_EXTENDED:
        try:
            params = inspect.signature(function).parameters
        except (TypeError, ValueError):  # a builtin without a text signature: try the keywords
            _TAKES_EXTENDED[function] = True
        else:
            _TAKES_EXTENDED[function] = all(name in params for name in EXTENDED_PARAMETERS) or any(
                p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    return _TAKES_EXTENDED[function]


def extended_keywords(function: Callable[..., Any], settings: SkinSettings, what: str) -> dict[str, Any]:
    """The keywords that give ``function`` (a core function: ``spectral_skin.maps``, ``shader_table``) the
    settings' extended physiology: only the values that differ from the paper's, so that the defaults call the core
    exactly as before. Raises ``spectral_skin.SpectralSkinError`` when a value differs and this ``spectral_skin``'s
    ``function`` does not take the extended keywords (``what``: what needs them, for the message)."""
    changed = settings.changed_extended()
    if changed and not _takes_extended(function):
        name = getattr(function, "__name__", "the core")
        raise spectral_skin.SpectralSkinError(
            f"{what} needs a spectral_skin whose {name}() takes "
            f"{', '.join(EXTENDED_PARAMETERS)} (this is spectral_skin "
            f"{getattr(spectral_skin, '__version__', '?')}); set {', '.join(sorted(changed))} back to the default or "
            "install a newer Spectral Skin")
    return changed


def swatch_albedo(values: dict[str, float], working_space: str, transport: str = DEFAULT_TRANSPORT) -> list[float]:
    """The panel's albedo swatch: the skin's total diffuse reflectance (``evaluate(outputs=["albedo"])``, linear RGB
    in ``working_space``, with ``transport``, a key of TRANSPORTS) of constant values (the four parameters and the
    extended physiology; an extended one left out takes its default)."""
    keywords: dict[str, Any] = {p: values[p] for p in EXTENDED_PARAMETERS if p in values}
    if transport != DEFAULT_TRANSPORT:
        keywords["transport"] = TRANSPORTS[transport]
    ev = spectral_skin.evaluate(*(values[p] for p in PARAMETERS), outputs=["albedo"], working_space=working_space,
                                **keywords)
    return list(_rgb(ev["diffuse_reflectance_rgb"]))


def subsurface_scale(scale_length: float) -> float:
    """Principled Subsurface Scale for radii in mm: scene units per mm (scale_length is metres per scene unit)."""
    return METRES_PER_MM / scale_length


def _rgb(values: Any) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def texture_prefix(blend_path: str, material_name: str) -> str:
    """The texture files' prefix: ``<blend name>_<material name>``, so that .blend files sharing a texture folder,
    each with a material of the same name, keep their own maps (just the material's name for an unsaved .blend)."""
    stem = os.path.splitext(os.path.basename(blend_path))[0]
    return f"{stem}_{material_name}" if stem else material_name


def describe_error(error: BaseException) -> str:
    """An error's message for an artist: bad texels in a parameter map (the core's ``bad_texels``) are described
    with the panel's words; any other error keeps the core's message (it names the input and its range)."""
    bad = getattr(error, "bad_texels", None)
    if not isinstance(bad, dict) or bad.get("parameter") not in PARAMETER_INFO:
        return str(error)
    kinds = [f"{bad[key]} {label}" for key, label in (("nan", "NaN"), ("infinite", "infinite"),
                                                      ("out_of_range", "out of range")) if bad.get(key)]
    count = sum(int(bad.get(key, 0)) for key in ("nan", "infinite", "out_of_range"))
    first = ", ".join(f"({x}, {y})" for x, y in bad.get("first", [])[:3])
    return (f"{PARAMETER_INFO[bad['parameter']][2]} map: {count} texel{'s' if count != 1 else ''} outside "
            f"{bad['min']:g} to {bad['max']:g} ({', '.join(kinds)}), first at x, y = {first} counted from the top "
            "left. Tick 'Clamp Out-of-Range Texels' to clamp them into range, or correct the map.")


@dataclass(frozen=True)
class SurfaceInputs:
    """The Principled surface inputs the core gives: the surface model ("measured" or "paper"), IOR, Roughness and
    Coat IOR (constants: no parameter changes them), and the oiliness-dependent Specular IOR Level, Coat Weight and
    Coat Roughness, each None where one of the core's maps supplies it (a varying oiliness)."""

    surface: str
    ior: float
    roughness: float
    coat_ior: float
    specular_ior_level: float | None
    coat_weight: float | None
    coat_roughness: float | None


@dataclass(frozen=True)
class Computed:
    """What the core computed for one parameter set, as it answered.

    Constants (one ``evaluate``): ``base_color`` (the method's; the albedo without the radius), ``radius`` (the
    method's, mm; None without the radius), ``albedo`` (the skin's total diffuse reflectance) and
    ``extent_radius_mm`` (the same skin's Burley radius, which the scene analysis compares whatever the method; None
    without the radius). Maps (one ``maps``): ``maps``, the core's ``Maps`` result, and the UDIM ``tiles`` it was
    stacked from. ``mean_albedo`` and ``mean_radius_mm``: Base Color and radius, averaged over the maps (zeros
    without the radius). ``work``: the core's own count of what it computed."""

    target: Mapping[str, Any]
    work: Mapping[str, Any]
    # The Principled subsurface method id the core computed for: the material's, or BURLEY without the radius.
    method: str
    radius_computed: bool
    specular_computed: bool
    surface: SurfaceInputs
    mean_albedo: tuple[float, ...]
    mean_radius_mm: tuple[float, ...]
    # What was computed, one sentence (the panel's "computed" line before the target), and what the core clamped.
    description: str
    warnings: tuple[str, ...] = ()
    base_color: tuple[float, ...] | None = None
    radius: tuple[float, ...] | None = None
    albedo: tuple[float, ...] | None = None
    extent_radius_mm: tuple[float, ...] | None = None
    maps: spectral_skin.Maps | None = None
    tiles: tuple[tuple[int, int], ...] = ()

    def images(self) -> dict[str, Any]:
        """The core's maps this answer holds: {map name: read-only float32 texels}, in the core's map order."""
        held = self.maps
        if held is None:
            return {}
        return {kind.name: held[kind.name] for kind in map_kinds() if kind.name in held}

    def largest_radius_mm(self) -> float:
        """The largest radius, mm, of any channel and texel (the method's); ValueError without the radius."""
        import numpy as np

        radius = self.radius if self.maps is None else self.maps.radius
        if radius is None:
            raise ValueError("no radius was computed")
        return float(np.max(np.asarray(radius, dtype=np.float64)))


def compute(settings: SkinSettings, progress: Any = None, *, radius: bool = True, specular: bool = True) -> Computed:
    """What the core computes for ``settings``; raises ``spectral_skin.SpectralSkinError`` (a ValueError) on bad
    input.

    ``progress``: None, or ``progress(done, total)`` told the texels done by the core (see ``spectral_skin.maps``);
    returning False cancels (InterruptedError). ``radius=False``: subsurface is off, so the core is not asked for the
    radius: Base Color is the skin's total diffuse reflectance (the albedo, whatever the method). ``specular=False``:
    the specular lobe is off: the core is not asked for it (Specular IOR Level 0 and no Coat: IOR and Roughness are
    the surface's constants, which no parameter changes). With maps the core (``spectral_skin.maps(outputs=...)``)
    likewise computes only those outputs: no radius fit without the radius, no specular input without specular
    (``work`` counts it).
    """
    check(settings)
    if settings.maps:
        return _from_maps(settings, progress, radius, specular)
    return _from_constants(settings, radius, specular)


def _outputs(radius: bool, specular: bool) -> list[str]:
    return ["albedo", *(["radius"] if radius else []), *(["specular"] if specular else [])]


def _surface(constants: Mapping[str, Any], specular: Mapping[str, Any] | None,
             mapped: Collection[str] = ()) -> SurfaceInputs:
    """The surface inputs from the core's surface constants and its specular inputs (None: not computed, so no lobe
    and no Coat, the Coat Roughness unused at weight 0); ``mapped``: the fields one of the core's maps supplies."""
    def value(key: str) -> float | None:
        if specular is None:
            return float(constants["roughness"]) if key == "coat_roughness" else 0.0
        return None if key in mapped else float(specular[key])

    return SurfaceInputs(surface=str(constants["surface"]), ior=float(constants["ior"]),
                         roughness=float(constants["roughness"]), coat_ior=float(constants["coat_ior"]),
                         specular_ior_level=value("specular_ior_level"), coat_weight=value("coat_weight"),
                         coat_roughness=value("coat_roughness"))


def _from_constants(settings: SkinSettings, radius: bool, specular: bool) -> Computed:
    c = settings.constants()
    ev = spectral_skin.evaluate(c["melanin"], c["melanin_blend"], c["hemoglobin"], c["oiliness"],
                                outputs=_outputs(radius, specular), accuracy=ACCURACY_LEVELS[settings.accuracy],
                                working_space=settings.working_space, blender=settings.blender,
                                engine=settings.engine, **settings.transport_keywords(),
                                surface=settings.surface_name(), **settings.extended())
    albedo = _rgb(ev["diffuse_reflectance_rgb"])
    base_color, radius_mm, extent = albedo, None, None
    if radius:
        name = method_name(settings.method)
        if name not in ev["methods"]:
            raise spectral_skin.SpectralSkinError(
                f"Blender {ev['target']['blender']} has no subsurface method {settings.method}; it offers "
                f"{', '.join(ev['methods'])}")
        base_color = _rgb(ev["methods"][name]["base_color"])
        radius_mm = _rgb(ev["methods"][name]["subsurface_radius_mm"])
        extent = _rgb(ev["methods"]["burley"]["subsurface_radius_mm"])
    skipped = f"{'' if radius else ', no radius'}{'' if specular else ', no specular'}"
    return Computed(target=_frozen(ev["target"]), work=_frozen(ev["work"]),
                    method=settings.method if radius else "BURLEY", radius_computed=radius,
                    specular_computed=specular, surface=_surface(ev["surface"], ev["specular"] if specular else None),
                    mean_albedo=base_color, mean_radius_mm=radius_mm or (0.0, 0.0, 0.0),
                    description=f"one evaluation ({ev['work']['wavelengths']} wavelengths{skipped})",
                    base_color=base_color, radius=radius_mm, albedo=albedo, extent_radius_mm=extent)


def _map_input(settings: SkinSettings, name: str) -> Any:
    import numpy as np

    pmap = settings.maps.get(name)
    if pmap is None:
        return float(getattr(settings, name))
    pixels = np.asarray(pmap.pixels, dtype=np.float32)
    if pmap.normalized:
        low, high = PARAMETER_INFO[name][:2]
        pixels = (low + pixels * (high - low)).astype(np.float32)
    return np.ascontiguousarray(pixels)


def _from_maps(settings: SkinSettings, progress: Any, radius: bool, specular: bool) -> Computed:
    import numpy as np

    inputs = {name: _map_input(settings, name) for name in PARAMETERS}
    extended = extended_keywords(spectral_skin.maps, settings, "extended physiology with parameter maps")
    # A varying extended map (SkinSettings.with_maps kept it) beats the material's value.
    extended.update({name: _map_input(settings, name) for name in EXTENDED_PARAMETERS if name in settings.maps})
    # Without subsurface the core fits no radius and Base Color is the albedo (Burley's Base Color), whatever the
    # material's method.
    result = spectral_skin.maps(**inputs, method=method_name(settings.method if radius else "BURLEY"),
                                outputs=_outputs(radius, specular), accuracy=ACCURACY_LEVELS[settings.accuracy],
                                working_space=settings.working_space, clamp=settings.clamp, progress=progress,
                                blender=settings.blender, engine=settings.engine, **settings.transport_keywords(),
                                surface=settings.surface_name(), **extended)
    report = result.report
    # The surface's constants: the result's, or without specular an evaluation of no output (IOR and Roughness).
    held = result.specular_constants
    if held is None:
        surface = _surface(_surface_constants(settings), None)
    else:
        surface = _surface(held, held, {kind.field for kind in map_kinds() if kind.name in result})
    # A UDIM tile set (every map has the same tiles: check) is computed as one texture and written tile by tile.
    tiles = next(iter(settings.maps.values())).tiles

    def mean(image: Any) -> tuple[float, ...]:
        return _rgb(np.asarray(image, dtype=np.float64).reshape(-1, 3).mean(axis=0))

    return Computed(target=_frozen(report["target"]), work=_frozen(report["work"]),
                    method=settings.method if radius else "BURLEY", radius_computed=radius,
                    specular_computed=specular,
                    surface=surface,
                    mean_albedo=mean(result.albedo), mean_radius_mm=mean(result.radius) if radius else (0.0, 0.0, 0.0),
                    description=_maps_description(report, tiles),
                    warnings=tuple(f"{c['parameter']}: {c['nan']} NaN, {c['infinite']} infinite, "
                                   f"{c['out_of_range']} out-of-range texels clamped" for c in report.get("clamped", [])),
                    maps=result, tiles=tiles)


def _surface_constants(settings: SkinSettings) -> Mapping[str, Any]:
    """The surface's constants (IOR, Roughness, Coat IOR: no parameter changes them) where the core computed no
    specular input: an evaluation of no output."""
    c = settings.constants()
    return spectral_skin.evaluate(c["melanin"], c["melanin_blend"], c["hemoglobin"], c["oiliness"], outputs=(),
                                  surface=settings.surface_name())["surface"]


def _maps_description(report: Mapping[str, Any], tiles: tuple[tuple[int, int], ...]) -> str:
    strategy = report["strategy"]
    computed = f"{report['width']}×{report['height']} maps, strategy {strategy['name']}"
    if tiles:
        computed += f" (UDIM tiles {', '.join(str(t) for t, _ in tiles)})"
    if "tuples" in strategy:
        computed += f" ({strategy['tuples']} distinct parameter sets)"
    return computed


def _frozen(value: Any) -> Any:
    """A read-only copy of the core's plain answer: mappings as read-only views, lists as tuples."""
    if isinstance(value, Mapping):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if type(value) in (list, tuple):
        return tuple(_frozen(v) for v in value)
    return value


def safe_name(name: str) -> str:
    """A file-name part the core accepts as a prefix (no path separator, not empty)."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "skin"
