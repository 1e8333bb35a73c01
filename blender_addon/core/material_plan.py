"""The material plan: everything Apply sets on a material, decided and computed before anything in Blender changes
(no bpy here).

The plan is built once, by :func:`build_plan`, from typed parts computed before it: the settings
(core/settings.py), the core's answer (:class:`~core.plan.Computed`: ``evaluate``'s values or the core's ``Maps``
result), the scene's decisions (:class:`Decision`, core/scene.py), and in Live mode the live node group's part
(:class:`LivePart`, core/live.py) or for an animated material its values per frame (:class:`Animation`). Nothing
changes it afterwards: its textures are written by the core from it (:meth:`~core.maps.Textures.write`: the core's
``Maps`` writes itself), the material's nodes set from it (``nodes.apply_plan``, ``live.wire``,
``frame_values.store``) and its summary stored on the material (``props.store_result``) and printed by the batch.
Its mappings are read-only views, its sequences tuples, its texels the core's read-only arrays.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from .maps import PLAN_INPUTS, Textures, map_kind, map_kinds
from .plan import Computed, safe_name, subsurface_scale
from .settings import TRANSPORTS, SkinSettings


class Record(Mapping[str, Any]):
    """A frozen dataclass that also reads as a read-only mapping of its fields: its JSON form, as the panel (from
    the material's stored JSON), the batch's sidecar and the tests read it."""

    def __getitem__(self, key: str) -> Any:
        if key not in self._names():
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def _names(self) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(self))  # type: ignore[arg-type]


@dataclass(frozen=True, eq=False)
class Decision(Record):
    """One decision of the scene analysis (core/scene.py): whether ``effect`` is simulated, why, the figures it
    was taken from, and the artist's override ("AUTO", "ON" or "OFF") that won over it, if any."""

    effect: str
    enabled: bool
    reason: str
    figures: Mapping[str, Any]
    override: str = "AUTO"


def decision(effect: str, enabled: bool, reason: str, figures: Mapping[str, Any] | None = None) -> Decision:
    """A decision taken by the analysis (its figures frozen)."""
    return Decision(effect, bool(enabled), reason, frozen(figures or {}))


def enabled(decisions: Sequence[Mapping[str, Any]], effect: str) -> bool:
    """Whether the decision on ``effect`` keeps it."""
    return bool(next(d["enabled"] for d in decisions if d["effect"] == effect))


@dataclass(frozen=True, eq=False)
class Animation(Record):
    """An animated material without maps: the Principled values at each frame (one per frame: computed by the core
    for each distinct parameter set and changed by the plan's decisions, core/scene.py), written as F-curves by
    frame_values.py; ``units`` names each value's unit."""

    frames: tuple[int, ...]
    base_color: tuple[Any, ...]
    radius: tuple[Any, ...]
    specular_ior_level: tuple[Any, ...]
    coat_weight: tuple[Any, ...]
    coat_roughness: tuple[Any, ...]
    units: Mapping[str, str]


@dataclass(frozen=True, eq=False)
class LivePart(Record):
    """Live mode's part of the plan (core/live.py): the node group's name, the core's shader table (None when the
    blend file has it), the parameter maps as the core read them, the panel's constants, the surface's inputs at the
    oiliness nodes the group interpolates, and whether subsurface and specular are kept."""

    group: str
    table: Mapping[str, Any] | None
    maps: Mapping[str, Any]
    constants: Mapping[str, float]
    surface_nodes: Mapping[str, Any]
    subsurface: bool
    specular: bool


@dataclass(frozen=True, eq=False)
class PlanSummary(Record):
    """What the panel shows of an Apply."""

    # The Base Color (mean over the texture with maps), linear RGB in the plan's working space.
    albedo: tuple[float, ...]
    # The Subsurface Radius, mm (mean over the texture with maps; zeros when no radius was computed).
    radius_mm: tuple[float, ...]
    # What was computed, one sentence.
    computed: str
    seconds: float
    warnings: tuple[str, ...]


@dataclass(frozen=True)
class PrincipledValues:
    """The Principled inputs a plan sets from the core's values, after the decisions: each None where a texture
    supplies it (its field of :data:`~core.maps.PLAN_INPUTS`)."""

    base_color: tuple[float, ...] | None
    radius: tuple[float, ...] | None
    specular_ior_level: float | None
    coat_weight: float | None
    coat_roughness: float | None


@dataclass(frozen=True)
class MaterialPlan:
    """What Apply sets on one material, and why."""

    # Blender's subsurface method id ("BURLEY", "RANDOM_WALK", ...: those the target's Blender offers).
    method: str
    # What the core computed for: {"blender": "5.0", "engine": "cycles" | "eevee", "tested": bool, ...}.
    target: Mapping[str, Any]
    # The scene-linear working space of base_color and of the albedo texture.
    working_space: str
    # The core's transport name the totals were computed with ("adding_doubling" or "diffusion").
    transport: str
    # The extended physiology the core computed with (one value per material; the paper's by default).
    extended: Mapping[str, float]
    # Whether the core was asked for the radius and the specular inputs ({"radius": bool, "specular": bool}): the
    # scene analysis asks for neither when it has dropped the effect before computing.
    computed: Mapping[str, bool]
    # The scene analysis's decisions, one per effect (core/scene.py).
    effects: tuple[Decision, ...]
    # Principled Base Color (linear RGB in working_space), or None when the albedo texture supplies it.
    base_color: tuple[float, ...] | None
    # Principled Subsurface Radius (the core's radius, mm), or None when the radius texture supplies it.
    radius: tuple[float, ...] | None
    # Principled Subsurface Scale, scene units per mm, so that Radius x Scale is the core's radius in scene units.
    scale: float
    ior: float
    subsurface_ior: float
    # Principled Specular IOR Level, or None when the specular texture supplies it.
    specular_ior_level: float | None
    roughness: float
    # The core's surface model the specular inputs stand in for ("measured" or "paper").
    surface: str
    # Principled Coat Weight and Coat Roughness (None when a texture supplies it: the measured surface's varying
    # oiliness), and Coat IOR. The paper's surface has no Coat (weight 0).
    coat_weight: float | None
    coat_roughness: float | None
    coat_ior: float
    # 0 where the scene analysis dropped subsurface scattering (plain diffuse with the same albedo), else 1.
    subsurface_weight: float
    # The textures this plan writes: {map name: the core's read-only texels}, with their folder, file prefix and
    # UDIM tiles (empty without maps); written by the core (core/maps.py Textures.write), which names the files.
    textures: Textures
    # What the core computed, as it reports it (evaluate(...)["work"] or maps(...).report["work"], added up).
    work: Mapping[str, Any]
    summary: PlanSummary
    # The skin's total diffuse reflectance (constants only) and the Burley radius the scene analysis compares.
    albedo: tuple[float, ...] | None = None
    extent_radius_mm: tuple[float, ...] | None = None
    # An animated material without maps: its values per frame (core/scene.py, frame_values.py); None otherwise.
    animation: Animation | None = None
    # Live mode: the live node group's part (core/live.py); None in Baked mode.
    live: LivePart | None = None

    def as_json(self) -> dict[str, Any]:
        """The plan's values as plain JSON types (no texels, no shader table): for the batch's report and tests;
        ``textures`` lists the maps written (the core names their files when it writes them)."""
        skip = {"textures", "live"}
        plain = {f.name: thawed(getattr(self, f.name)) for f in dataclasses.fields(self) if f.name not in skip}
        return {**plain, "textures": list(self.textures)}


def frozen(value: Any) -> Any:
    """A read-only copy: mappings as read-only views of copies, lists and tuples as tuples, anything else (a record,
    an array of the core's, a ParameterMap) as it is."""
    if isinstance(value, Mapping) and not isinstance(value, Record):
        return MappingProxyType({k: frozen(v) for k, v in value.items()})
    if type(value) in (list, tuple):  # not a NamedTuple
        return tuple(frozen(v) for v in value)
    return value


def thawed(value: Any) -> Any:
    """The plain-JSON form of a frozen value: dicts and lists."""
    if isinstance(value, Mapping):
        return {k: thawed(v) for k, v in value.items()}
    if type(value) in (list, tuple):
        return [thawed(v) for v in value]
    return value


def sum_work(works: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The core's work counts of several computations added up, key by key (nested dicts too)."""
    total: dict[str, Any] = {}
    for work in works:
        for key, value in work.items():
            if isinstance(value, Mapping):
                total[key] = sum_work([total.get(key, {}), value])
            else:
                total[key] = total.get(key, 0) + value
    return total


def _first_texel(image: Any) -> tuple[float, ...]:
    """An output image's first texel (all its channels)."""
    import numpy as np

    array = np.asarray(image, dtype=np.float64)
    return tuple(float(v) for v in array.reshape(-1, array.shape[-1] if array.ndim == 3 else 1)[0])


def decided_values(computed: Computed, decisions: Sequence[Decision],
                   albedo: Computed | None = None) -> tuple[PrincipledValues, dict[str, Any]]:
    """The Principled values and the kept textures ({map name: texels}) of ``computed`` as the decisions say.

    Subsurface off: the radius texture is dropped (the radius, unused at weight 0, is the mean) and, for a method
    other than Burley (whose Base Color is not the albedo), Base Color is the skin's total diffuse reflectance:
    ``computed.albedo`` for constants, else the albedo maps of ``albedo`` (the core's Burley maps without radius or
    specular). Specular off: Specular IOR Level 0, no Coat, no surface texture. Constant maps: an output texture of
    one value becomes that value."""
    images = computed.images()
    values: dict[str, Any] = {"base_color": computed.base_color, "radius": computed.radius}
    surface = computed.surface
    if not enabled(decisions, "subsurface"):
        images.pop("radius", None)
        if computed.radius_computed:
            values["radius"] = computed.mean_radius_mm
        if computed.method != "BURLEY" and computed.albedo is not None:
            values["base_color"] = computed.albedo
        elif computed.method != "BURLEY":
            if albedo is None or albedo.maps is None or albedo.maps.albedo is None:
                raise ValueError("subsurface dropped from maps of another method than Burley needs the albedo maps")
            images["albedo"] = albedo.maps.albedo
    if enabled(decisions, "specular"):
        values.update(specular_ior_level=surface.specular_ior_level, coat_weight=surface.coat_weight,
                      coat_roughness=surface.coat_roughness)
    else:
        values.update(specular_ior_level=0.0, coat_weight=0.0,
                      coat_roughness=surface.roughness if surface.coat_roughness is None else surface.coat_roughness)
        for kind in map_kinds():
            if kind.scalar:
                images.pop(kind.name, None)
    for name in constant_maps(decisions):
        if name in images:
            kind, texel = map_kind(name), _first_texel(images.pop(name))
            values[kind.field] = texel[0] if kind.scalar else texel
    ordered = {kind.name: images[kind.name] for kind in map_kinds() if kind.name in images}
    return PrincipledValues(**values), ordered


def constant_maps(decisions: Sequence[Decision]) -> tuple[str, ...]:
    """The output maps the "constant maps" decision sets as values (none when it is off)."""
    entry = next(d for d in decisions if d.effect == "constant maps")
    return tuple(entry.figures.get("constant", ())) if entry.enabled else ()


def build_plan(settings: SkinSettings, computed: Computed, decisions: Sequence[Decision], *,
               albedo: Computed | None = None, work: Mapping[str, Any] | None = None,
               animation: Animation | None = None, live: LivePart | None = None,
               seconds: float = 0.0) -> MaterialPlan:
    """The material plan, built once from its parts: ``settings``, the core's answer ``computed``, the scene's
    ``decisions`` (:func:`decided_values`, with ``albedo``, the core's Burley albedo maps where a map-based random
    walk drops subsurface), the core's ``work`` for everything the plan took (default: ``computed``'s and
    ``albedo``'s added up), an animated material's ``animation``, Live mode's ``live`` part, and the ``seconds``
    the computing took."""
    values, images = decided_values(computed, decisions, albedo)
    held = computed.images()
    whole = bool(images) and images.keys() == held.keys() and all(images[k] is held[k] for k in held)
    textures = Textures(images=MappingProxyType(images), tiles=computed.tiles, source=computed.maps if whole else None,
                        folder=_folder(settings) if computed.maps is not None else "",
                        prefix=safe_name(settings.file_prefix) if computed.maps is not None else "")
    # Base Color as the summary shows it: the albedo where subsurface was dropped from another method than Burley.
    mean = computed.mean_albedo
    if not enabled(decisions, "subsurface") and computed.method != "BURLEY":
        mean = computed.albedo if computed.albedo is not None else albedo.mean_albedo if albedo else mean
    surface = computed.surface
    return MaterialPlan(
        method=settings.method, target=computed.target, working_space=settings.working_space,
        transport=TRANSPORTS[settings.transport], extended=MappingProxyType(settings.extended()),
        computed=MappingProxyType({"radius": computed.radius_computed, "specular": computed.specular_computed}),
        effects=tuple(decisions), **{field: getattr(values, field) for field in PLAN_INPUTS},
        scale=subsurface_scale(settings.scale_length), ior=surface.ior, subsurface_ior=surface.ior,
        roughness=surface.roughness, surface=surface.surface, coat_ior=surface.coat_ior,
        subsurface_weight=1.0 if enabled(decisions, "subsurface") else 0.0, textures=textures,
        work=frozen(work if work is not None else sum_work([c.work for c in (computed, albedo) if c is not None])),
        summary=_summary(settings, computed, mean, live, seconds),
        albedo=computed.albedo, extent_radius_mm=computed.extent_radius_mm, animation=animation, live=live)


def _folder(settings: SkinSettings) -> str:
    import os

    return os.path.abspath(settings.output_dir)


def _summary(settings: SkinSettings, computed: Computed, albedo: tuple[float, ...], live: LivePart | None,
             seconds: float) -> PlanSummary:
    """What the panel shows: the Base Color ``albedo``, the radius, what was computed for which target, and every
    warning (what the core clamped, what the settings and the map files' reader noted, an untested target)."""
    target = computed.target
    text = f"{computed.description} for Blender {target['blender']} {target['engine'].upper()}"
    if live is not None:
        text += "; live node group, shader table " + ("computed" if live.table is not None else
                                                      "reused from the blend file")
    # What the core's reader ignored in the map files (an alpha channel, a misspelt channel), once per note.
    notes = dict.fromkeys((*settings.notes, *(n for m in settings.maps.values() for n in m.notes)))
    untested = () if target["tested"] else (str(target["untested_reason"]),)
    return PlanSummary(albedo=albedo, radius_mm=computed.mean_radius_mm, computed=text, seconds=seconds,
                       warnings=(*computed.warnings, *notes, *untested))


def write_textures(plan: MaterialPlan) -> dict[str, str]:
    """Write the plan's textures with the core's writer (:meth:`~core.maps.Textures.write`); returns {map name: the
    file the core wrote}. Raises spectral_skin.SpectralSkinIOError (an OSError naming the file) when a file cannot
    be written; the final paths are then untouched."""
    return plan.textures.write()
