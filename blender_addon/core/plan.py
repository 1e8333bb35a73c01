"""What the skin material needs, computed by the core before anything in Blender changes (no bpy here).

:func:`make_plan` computes a material's values with the core and returns them as a plain dict, the draft of the
material plan (:class:`~core.material_plan.MaterialPlan`: its keys are the plan's fields, documented there). The scene
analysis (core/scene.py) and Live mode (core/live.py) change the draft as their decisions say and freeze it; nothing
changes a plan after that.

Maps are written only by :func:`write_textures`, from a frozen plan, by the core's writer
(``spectral_skin.write_maps``): first to temporary files in the output folder, then renamed into place together, so a
failure leaves existing files as they were.
"""

from __future__ import annotations

import inspect
import os
import re
import time
from collections.abc import Callable
from typing import Any

from .material_plan import FIELD_OF_TEXTURE, SURFACE_TEXTURES, MaterialPlan
from .settings import (
    ACCURACY_LEVELS,
    DEFAULT_TRANSPORT,
    EXTENDED_PARAMETERS,
    PARAMETER_INFO,
    PARAMETERS,
    TRANSPORTS,
    UDIM_TOKEN,
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
        import spectral_skin

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
    import spectral_skin

    keywords: dict[str, Any] = {p: values[p] for p in EXTENDED_PARAMETERS if p in values}
    if transport != DEFAULT_TRANSPORT:
        keywords["transport"] = TRANSPORTS[transport]
    ev = spectral_skin.evaluate(*(values[p] for p in PARAMETERS), outputs=["albedo"], working_space=working_space,
                                **keywords)
    return _rgb(ev["diffuse_reflectance_rgb"])

def subsurface_scale(scale_length: float) -> float:
    """Principled Subsurface Scale for radii in mm: scene units per mm (scale_length is metres per scene unit)."""
    return METRES_PER_MM / scale_length


def _rgb(values: Any) -> list[float]:
    return [float(v) for v in values]


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


def make_plan(settings: SkinSettings, progress: Any = None, *, radius: bool = True,
              specular: bool = True) -> dict[str, Any]:
    """Compute what the material needs; raises ``spectral_skin.SpectralSkinError`` (a ValueError) on bad input.

    ``progress``: None, or ``progress(done, total)`` told the texels done by the core (see ``spectral_skin.maps``);
    returning False cancels (InterruptedError). ``radius=False``: subsurface is off, so the core is not asked for the
    radius: Base Color is the skin's total diffuse reflectance (the albedo, whatever the method) and ``radius`` is
    None. ``specular=False``: the specular lobe is off: Specular IOR Level 0, no specular texture, and the core is
    not asked for it (IOR and Roughness are the surface's constants, which no parameter changes). With maps the core
    (``spectral_skin.maps(outputs=...)``) likewise computes only those outputs: no radius fit without the radius, no
    specular input without specular (``plan["work"]`` counts it).
    """
    check(settings)
    start = time.perf_counter()
    if settings.maps:
        plan = _plan_from_maps(settings, progress, radius, specular)
    else:
        plan = _plan_from_constants(settings, radius, specular)
    plan["computed"] = {"radius": radius, "specular": specular}
    plan["extended"] = settings.extended()
    plan["method"] = settings.method
    plan["transport"] = TRANSPORTS[settings.transport]
    plan["working_space"] = settings.working_space
    plan["scale"] = subsurface_scale(settings.scale_length)
    target = plan["target"]
    plan["summary"]["computed"] += f" for Blender {target['blender']} {target['engine'].upper()}"
    # What the core's reader ignored in the map files (an alpha channel, a misspelt channel), once per note.
    for note in dict.fromkeys((*settings.notes, *(n for m in settings.maps.values() for n in m.notes))):
        plan["summary"]["warnings"].append(note)
    if not target["tested"]:
        plan["summary"]["warnings"].append(target["untested_reason"])
    plan["summary"]["seconds"] = time.perf_counter() - start
    return plan


def _plan_from_constants(settings: SkinSettings, radius: bool, specular: bool) -> dict[str, Any]:
    import spectral_skin

    c = settings.constants()
    outputs = ["albedo", *(["radius"] if radius else []), *(["specular"] if specular else [])]
    ev = spectral_skin.evaluate(c["melanin"], c["melanin_blend"], c["hemoglobin"], c["oiliness"], outputs=outputs,
                                accuracy=ACCURACY_LEVELS[settings.accuracy], working_space=settings.working_space,
                                blender=settings.blender, engine=settings.engine, **settings.transport_keywords(),
                                surface=settings.surface_name(), **settings.extended())
    albedo = _rgb(ev["diffuse_reflectance_rgb"])
    radius_mm: list[float] | None = None
    base_color = albedo
    if radius:
        name = method_name(settings.method)
        if name not in ev["methods"]:
            raise spectral_skin.SpectralSkinError(
                f"Blender {ev['target']['blender']} has no subsurface method {settings.method}; it offers "
                f"{', '.join(ev['methods'])}")
        method = ev["methods"][name]
        base_color = _rgb(method["base_color"])
        radius_mm = _rgb(method["subsurface_radius_mm"])
    surface = ev["surface"]
    # Without specular: no lobe and no Coat (the surface's constants for the rest).
    spec = ev["specular"] if specular else {"specular_ior_level": 0.0, "coat_weight": 0.0,
                                            "coat_roughness": surface["roughness"]}
    return {
        "base_color": base_color,
        "radius": radius_mm,
        # The same skin's Burley radius: the physical extent the scene analysis compares for every method
        # (core/scene.py, extent_mm).
        "extent_radius_mm": _rgb(ev["methods"]["burley"]["subsurface_radius_mm"]) if radius else None,
        "albedo": albedo,
        "ior": float(surface["ior"]),
        "subsurface_ior": float(surface["ior"]),
        "specular_ior_level": float(spec["specular_ior_level"]),
        "roughness": float(surface["roughness"]),
        "coat_weight": float(spec["coat_weight"]),
        "coat_roughness": float(spec["coat_roughness"]),
        "coat_ior": float(surface["coat_ior"]),
        "surface": str(surface["surface"]),
        "target": dict(ev["target"]),
        "textures": {},
        "images": {},
        "work": dict(ev["work"]),
        "summary": {
            "albedo": base_color,
            "radius_mm": radius_mm if radius_mm is not None else [0.0, 0.0, 0.0],
            "computed": f"one evaluation ({ev['work']['wavelengths']} wavelengths"
                        f"{'' if radius else ', no radius'}{'' if specular else ', no specular'})",
            "warnings": [],
        },
    }


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


def _safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "skin"


def _plan_from_maps(settings: SkinSettings, progress: Any, radius: bool, specular: bool) -> dict[str, Any]:
    import numpy as np
    import spectral_skin

    inputs = {name: _map_input(settings, name) for name in PARAMETERS}
    extended = extended_keywords(spectral_skin.maps, settings, "extended physiology with parameter maps")
    # A varying extended map (SkinSettings.with_maps kept it) beats the material's value.
    extended.update({name: _map_input(settings, name) for name in EXTENDED_PARAMETERS if name in settings.maps})
    # Without subsurface the core fits no radius and Base Color is the albedo (Burley's Base Color), whatever the
    # material's method.
    outputs = ["albedo", *(["radius"] if radius else []), *(["specular"] if specular else [])]
    result = spectral_skin.maps(**inputs, method=method_name(settings.method if radius else "BURLEY"),
                                outputs=outputs, accuracy=ACCURACY_LEVELS[settings.accuracy],
                                working_space=settings.working_space, clamp=settings.clamp, progress=progress,
                                blender=settings.blender, engine=settings.engine, **settings.transport_keywords(),
                                surface=settings.surface_name(), **extended)
    report = result["report"]
    prefix = _safe_name(settings.file_prefix)
    folder = os.path.abspath(settings.output_dir)
    # The maps by their one name: the output asked for, the result's key, the texture's file (<prefix>_<name>.exr).
    images: dict[str, Any] = {"albedo": result["albedo"]}
    if radius:
        images["radius"] = result["radius"]
    # Roughness and IOR always (without specular: the surface's constants, which an evaluation of no output gives);
    # each oiliness-dependent input (the level, and the Coat's weight and roughness) is a map of its own when the
    # oiliness varies (None here), else a value.
    surface_inputs: dict[str, float | None] = {"specular_ior_level": 0.0, "coat_weight": 0.0}
    if not specular:
        c = settings.constants()
        constants: dict[str, Any] = dict(spectral_skin.evaluate(c["melanin"], c["melanin_blend"], c["hemoglobin"],
                                                                c["oiliness"], outputs=(),
                                                                surface=settings.surface_name())["surface"])
        surface_inputs["coat_roughness"] = float(constants["roughness"])
    else:
        constants = dict(result["specular_constants"])
        for name in SURFACE_TEXTURES:
            field = FIELD_OF_TEXTURE[name]
            if name in result:
                images[name] = result[name]
                surface_inputs[field] = None
            else:
                surface_inputs[field] = float(constants[field])
    roughness = float(constants["roughness"])
    ior = float(constants["ior"])
    # A UDIM tile set (every map has the same tiles: check) is computed as one texture and written tile by tile.
    tiles = next(iter(settings.maps.values())).tiles
    udim = f".{UDIM_TOKEN}" if tiles else ""
    strategy = report["strategy"]
    computed = f"{report['width']}×{report['height']} maps, strategy {strategy['name']}"
    if tiles:
        computed += f" (UDIM tiles {', '.join(str(t) for t, _ in tiles)})"
    if "tuples" in strategy:
        computed += f" ({strategy['tuples']} distinct parameter sets)"
    warnings = [
        f"{c['parameter']}: {c['nan']} NaN, {c['infinite']} infinite, {c['out_of_range']} out-of-range texels clamped"
        for c in report.get("clamped", [])
    ]
    return {
        "base_color": None,
        "radius": None,
        "ior": ior,
        "subsurface_ior": ior,
        **surface_inputs,
        "roughness": roughness,
        "coat_ior": float(constants["coat_ior"]),
        "surface": str(constants["surface"]),
        "target": dict(report["target"]),
        "folder": folder,
        "prefix": prefix,
        "textures": {kind: os.path.join(folder, f"{prefix}_{kind}{udim}.exr") for kind in images},
        "tiles": tiles,
        "images": images,
        "work": dict(report["work"]),
        "summary": {
            "albedo": _rgb(np.asarray(result["albedo"], dtype=np.float64).reshape(-1, 3).mean(axis=0)),
            "radius_mm": _rgb(np.asarray(result["radius"], dtype=np.float64).reshape(-1, 3).mean(axis=0))
            if radius else [0.0, 0.0, 0.0],
            "computed": computed,
            "warnings": warnings,
        },
    }


def write_textures(plan: MaterialPlan) -> None:
    """Write the plan's maps with ``spectral_skin.write_maps`` (the core's writer: half-float EXRs, compression chosen
    per file, staged as temporary files and renamed into place together), as ``<prefix>_albedo.exr`` etc. in the
    plan's folder (a UDIM tile set: ``<prefix>_albedo.1001.exr`` etc., every tile's files staged and then all renamed
    together); an earlier texture of this prefix (and tiles) that the plan no longer has is removed.

    One call for the plan's images, which need not be one ``maps()`` result's (the scene analysis may take the albedo
    of another computation and drop textures): the core reads the plan's read-only arrays in place.

    Raises spectral_skin.SpectralSkinIOError (an OSError naming the file) when a file cannot be written; the final paths are then
    untouched.
    """
    if not plan.textures:
        return
    import spectral_skin

    if plan.folder is None:
        raise ValueError("a plan with textures has a folder (core/plan.py _plan_from_maps)")

    result = {kind: plan.images[kind] for kind in plan.textures}
    written = {kind: str(path) for kind, path in spectral_skin.write_maps(
        result, plan.folder, plan.prefix, tiles=list(plan.tiles) or None).items()}
    if written != dict(plan.textures):
        raise RuntimeError(f"spectral_skin.write_maps wrote {written}, expected {dict(plan.textures)}")
