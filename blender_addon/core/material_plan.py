"""The material plan: everything Apply sets on a material, decided and computed before anything in Blender changes
(no bpy here).

:func:`~core.scene.scene_plan` (Baked mode) and :func:`~core.live.live_plan` (Live mode) build it, by one path:
the scene analysis decides which effects the scene calls for, the core computes only those
(:func:`~core.plan.make_plan`, whose dict is the plan's draft), the decisions change the draft, and :func:`freeze`
turns it into a :class:`MaterialPlan`. From there on nothing changes it: the textures are written from it
(:func:`~core.plan.write_textures`), the material's nodes set from it (``nodes.apply_plan``, ``live.wire``,
``frame_values.store``) and its summary stored on the material (``props.store_result``) and printed by the batch.
Its mappings are read-only views and its sequences tuples; its texture arrays are read-only.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

# The plan field (a Principled input's one value) of each texture, named by its map as the core names it
# (``spectral_skin.maps``: albedo.exr feeds Base Color): the field is None while the texture supplies the input, and
# takes the texture's value when the scene analysis sets a constant texture as a value.
FIELD_OF_TEXTURE = {"albedo": "base_color", "radius": "radius", "specular": "specular_ior_level",
                    "coat_weight": "coat_weight", "coat_roughness": "coat_roughness"}
# The single-channel surface textures: the specular output's maps when the oiliness varies (the Coat's two only under
# the measured surface).
SURFACE_TEXTURES = ("specular", "coat_weight", "coat_roughness")


@dataclass(frozen=True)
class PlanSummary:
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
    # The scene analysis's decisions, one per effect: {"effect", "enabled", "reason", "figures", "override"}
    # (core/scene.py).
    effects: tuple[Mapping[str, Any], ...]
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
    # {"albedo" | "radius" | "specular": final absolute path} of the textures this plan writes (<folder>/<prefix>_
    # <kind>.exr, or .<UDIM>.exr for a tile set); empty without maps.
    textures: Mapping[str, str]
    # {same keys: (H, W, 3) or (H, W) float32 array, row 0 at the top, read-only}: the textures' texels.
    images: Mapping[str, Any]
    # The texture folder and file prefix (None without maps), and a tile set's (tile, rows) stacked top to bottom.
    folder: str | None
    prefix: str | None
    tiles: tuple[tuple[int, int], ...]
    # What the core computed, as it reports it (evaluate(...)["work"] or maps(...)["report"]["work"], added up).
    work: Mapping[str, Any]
    summary: PlanSummary
    # The skin's total diffuse reflectance (constants only) and the Burley radius the scene analysis compares.
    albedo: tuple[float, ...] | None = None
    extent_radius_mm: tuple[float, ...] | None = None
    # An animated material without maps: {"frames", "base_color", "radius", "specular_ior_level", "units"}, one value
    # per frame (core/scene.py, frame_values.py); None otherwise.
    animation: Mapping[str, Any] | None = None
    # Live mode: {"group", "table", "maps", "constants", "subsurface", "specular"} (core/live.py); None in Baked mode.
    live: Mapping[str, Any] | None = None

    def as_json(self) -> dict[str, Any]:
        """The plan's values as plain JSON types (no texels, no shader table): for the batch's report and tests."""
        skip = {"images", "live"}
        return {f.name: thawed(getattr(self, f.name)) for f in dataclasses.fields(self) if f.name not in skip}


def _frozen(value: Any) -> Any:
    """A read-only copy: mappings as read-only views of copies, lists and tuples as tuples, numpy arrays read-only
    (a view: the texels are not copied), anything else as it is."""
    if isinstance(value, Mapping):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    if type(value) in (list, tuple):  # not a NamedTuple (a ParameterMap keeps its fields)
        return tuple(_frozen(v) for v in value)
    if hasattr(value, "setflags") and hasattr(value, "view"):  # a numpy array
        view = value.view()
        view.setflags(write=False)
        return view
    return value


def thawed(value: Any) -> Any:
    """The plain-JSON form of a frozen value: dicts and lists."""
    if isinstance(value, PlanSummary):
        return {f.name: thawed(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {k: thawed(v) for k, v in value.items()}
    if type(value) in (list, tuple):
        return [thawed(v) for v in value]
    return value


def _floats(values: Sequence[Any] | None) -> tuple[float, ...] | None:
    return None if values is None else tuple(float(v) for v in values)


def freeze(draft: Mapping[str, Any]) -> MaterialPlan:
    """The plan of a draft (:func:`~core.plan.make_plan`'s dict, changed by the scene analysis's decisions)."""
    summary = draft["summary"]
    specular = draft["specular_ior_level"]

    def optional(key: str) -> float | None:
        return None if draft[key] is None else float(draft[key])
    return MaterialPlan(
        method=draft["method"],
        target=_frozen(draft["target"]),
        working_space=draft["working_space"],
        transport=draft["transport"],
        extended=_frozen(draft["extended"]),
        computed=_frozen(draft["computed"]),
        effects=_frozen(draft.get("effects", [])),
        base_color=_floats(draft["base_color"]),
        radius=_floats(draft["radius"]),
        scale=float(draft["scale"]),
        ior=float(draft["ior"]),
        subsurface_ior=float(draft["subsurface_ior"]),
        specular_ior_level=None if specular is None else float(specular),
        roughness=float(draft["roughness"]),
        surface=str(draft["surface"]),
        coat_weight=optional("coat_weight"),
        coat_roughness=optional("coat_roughness"),
        coat_ior=float(draft["coat_ior"]),
        subsurface_weight=float(draft.get("subsurface_weight", 1.0)),
        textures=_frozen(draft["textures"]),
        images=_frozen(draft["images"]),
        folder=draft.get("folder"),
        prefix=draft.get("prefix"),
        tiles=_frozen(draft.get("tiles") or ()),
        work=_frozen(draft["work"]),
        summary=PlanSummary(albedo=tuple(float(v) for v in summary["albedo"]),
                            radius_mm=tuple(float(v) for v in summary["radius_mm"]),
                            computed=str(summary["computed"]), seconds=float(summary.get("seconds", 0.0)),
                            warnings=tuple(str(w) for w in summary["warnings"])),
        albedo=_floats(draft.get("albedo")),
        extent_radius_mm=_floats(draft.get("extent_radius_mm")),
        animation=_frozen(draft["animation"]) if draft.get("animation") is not None else None,
        live=_frozen(draft["live"]) if draft.get("live") is not None else None,
    )
