"""What the scene calls for: which effects of the skin material any camera can see, decided from plain facts (no bpy).

The bpy glue (``blender_addon/scene_facts.py``) gathers :class:`~core.facts.SceneFacts` from the scene.
:func:`scene_plan`, the one path of the operator and of the headless batch, runs one way: :func:`before_computing`
decides what it can before the core is asked (:func:`subsurface_before`, the oiliness: a dropped effect is not
computed, and the plan's ``work``, the core's count, shows no radius fit or no specular evaluation), the core is
asked once per parameter set (:func:`~core.plan.compute`), :func:`decide` takes the decisions
(:class:`~core.material_plan.Decision`, frozen) from the core's answer, and
:func:`~core.material_plan.build_plan` builds the frozen plan from the parts. Nothing is changed after it is made.

Effects:

- ``subsurface``: the smallest pixel footprint on the skin (mm per pixel) over every view (object, camera, frame),
  compared with the material's largest extent (mm): the skin's Burley Subsurface Radius × Scale, whatever the
  method (:func:`extent_mm`; the threshold was measured with Burley's radius, and a random walk's radius is a mean
  free path, several times shorter for the same skin in Blender 5.2+). When the largest extent is below
  :data:`SUBSURFACE_MIN_RADIUS_PX` pixels everywhere, subsurface scattering is dropped: Subsurface Weight 0 with the
  skin's total diffuse reflectance (the albedo) as Base Color, which keeps the total reflectance exact and only
  loses the blur no pixel can show (Subsurface Weight 0 is a diffuse closure of weight Base Color:
  docs/blender-principled.md, Subsurface Weight). Not where an object using the material has thin parts (as the
  ``subsurface method`` advice below measures them): light carried through an ear is no blur a pixel hides, and a
  far Suzanne rendered plain diffuse differs by about 1.3 % in mean colour (docs/scene-effects.md).
- ``specular``: the model's only surface term is the oil layer on the skin (Donner & Jensen 2006, ρ_s scales the
  Torrance-Sparrow lobe); oiliness zero everywhere means no oil film, hence no specular lobe at all: Specular IOR
  Level 0 and no specular texture.
- ``constant maps``: an output map whose texels all hold one value is set as a value, not written as a texture
  (exact; the override Off writes the texture all the same).
- ``engine/version``: the target the core computed for (core/targets.py), recorded as the plan's first entry.
- ``subsurface method``: a recommendation, never applied by itself (the method is the artist's choice on the
  material, and the Auto/On/Off overrides switch effects, not methods): per object using the material, its thickness
  part by part (ray-cast through the mesh from sampled faces: thin when at least :data:`THIN_AREA_FRACTION` of its
  area is under :data:`THIN_RADII` times the largest radius; without samples, the smallest dimension of its
  evaluated bounds, mm, against :data:`THIN_RADII` times the largest radius), and
  whether its mesh is closed (every edge shared by exactly two faces). Thinner than that and closed: a random walk
  (Burley's disk projection assumes a half-space, wrong on ears, nostrils, fingers); open: Burley, or close the mesh
  (a random walk leaks out through the holes). ``enabled``: the material's method suits every object.
- ``animation``: a parameter keyframed or driven on the material's Spectral Skin settings. A constant-parameter
  material gets its values per frame (``plan.animation``: computed by the core for each distinct parameter set,
  with the same decisions), written as F-curves by blender_addon/frame_values.py; a material with parameter
  maps renders the current frame's values (``enabled`` False): its animation needs per-frame maps or the live
  shader.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from .facts import (
    MM_PER_METRE,
    THIN_AREA_FRACTION,
    THIN_RADII,
    AnimationFacts,
    CameraFacts,
    SceneFacts,
    ShapeFacts,
    View,
    active_camera,
    footprint_mm,
    is_thin,
    nearest_depth,
    pixels_across,
    sample_frames,
    smallest_footprint,
    thin_objects,
    thin_parts,
)
from .maps import PLAN_INPUTS
from .material_plan import (
    Animation,
    Decision,
    LivePart,
    MaterialPlan,
    build_plan,
    decided_values,
    decision,
    enabled,
    sum_work,
)
from .plan import Computed, compute
from .settings import SkinSettings

# The facts and their geometry (core/facts.py) and the decisions' record (core/material_plan.py), as the analysis
# names them.
__all__ = [
    "MM_PER_METRE", "THIN_AREA_FRACTION", "THIN_RADII", "AnimationFacts", "CameraFacts", "Decision", "SceneFacts",
    "ShapeFacts", "View", "active_camera", "before_computing", "decide", "describe", "enabled", "extent_mm",
    "footprint_mm", "is_thin", "nearest_depth", "pixels_across", "radius_bound_mm", "sample_frames", "scene_plan",
    "smallest_footprint", "specular_needed", "subsurface_before", "sum_work", "thin_objects", "thin_parts",
]

# Largest subsurface radius, in pixels of the smallest footprint, below which subsurface scattering is dropped.
# Chosen from the measurement in docs/scene-effects.md (scripts/reports/scene_effects_report.py): at and below this
# radius the Burley slab and the plain-diffuse slab of the same albedo differ by a mean under 0.5 % of the albedo.
SUBSURFACE_MIN_RADIUS_PX = 0.25


OVERRIDES = ("AUTO", "ON", "OFF")
# Effects an artist can force on or off (engine/version is required by the target). "constant maps" on: an output
# map of one value is set as a value; off: written as a texture all the same.
OVERRIDABLE = ("subsurface", "specular", "constant maps")

def _largest(values: Any) -> float:
    import numpy as np

    return float(np.max(np.asarray(values, dtype=np.float64)))


def extent_mm(computed: Computed, settings: SkinSettings) -> float:
    """The largest physical extent of the computed profile, mm, as the Burley radius of the same skin: what
    :data:`SUBSURFACE_MIN_RADIUS_PX` was measured with, whatever the material's method (a random walk's radius is
    a mean free path, several times shorter than Burley's for the same skin in Blender 5.2+, longer before).
    Constants have it from their one evaluation (``extent_radius_mm``); maps' method radius is scaled by the
    largest Burley-to-method ratio over the bound grid (:func:`radius_bound_mm`), an upper bound."""
    if computed.extent_radius_mm is not None:
        return _largest(computed.extent_radius_mm)
    return computed.largest_radius_mm() * extent_ratio(settings)


def _subsurface(computed: Computed, facts: SceneFacts | None, threshold_px: float,
                settings: SkinSettings) -> Decision:
    largest_mm = computed.largest_radius_mm()
    extent = extent_mm(computed, settings)
    figures: dict[str, Any] = {"largest_radius_mm": largest_mm, "extent_mm": extent, "threshold_px": threshold_px}
    if facts is None:
        return decision("subsurface", True, "no scene facts: kept", figures)
    try:
        best = smallest_footprint(facts)
    except ValueError as error:
        return decision("subsurface", True, f"kept: {error}", figures)
    if best is None:
        return decision("subsurface", True, f"kept: {facts.note or 'no camera sees an object using the material'}",
                      figures)
    radius_px = extent / best["footprint_mm"]
    figures.update(best, largest_radius_px=radius_px)
    where = f"at frame {best['frame']}, camera {best['camera']}, object {best['object']}"
    thin = thin_objects(facts, largest_mm) if radius_px < threshold_px else []
    if thin:
        figures["thin_objects"] = thin
        return decision("subsurface", True, f"kept: {', '.join(thin)} {'has' if len(thin) == 1 else 'have'} parts "
                      f"thinner than {THIN_RADII:g} radii, through which subsurface scattering carries light (plain "
                      f"diffuse would lose it at any distance), although the largest radius is {radius_px:.3g} px "
                      f"{where}", figures)
    if radius_px < threshold_px:
        return decision("subsurface", False, f"largest extent (Burley radius) {radius_px:.3g} px {where} (under "
                      f"{threshold_px:g} px): plain diffuse with the same albedo", figures)
    return decision("subsurface", True, f"largest extent (Burley radius) {radius_px:.3g} px {where} (at least "
                  f"{threshold_px:g} px)", figures)


# Where the largest radius of any skin is sought: a grid over melanin (dense at small fractions, as fractions of its
# range), both melanin types and their mix, without blood (blood absorbs the deep, long paths: it only narrows the
# profile). The radius is not monotone in melanin: for the random-walk methods and a thin epidermis a little melanin
# (a filter on top, absorbing the short paths first) widens the fitted radius before more narrows it, so the least
# absorbing skin alone is no bound. Checked on a denser, offset grid over all three fractions for every method and
# engine, with the paper's and a widening extended physiology, by
# tests/python/test_addon_scene.py::test_bound_grid_bounds_the_radius.
BOUND_MELANIN_FRACTIONS = (0.0, 0.005, 0.01, 0.02, 0.04, 0.06, 0.09, 0.125, 0.17, 0.25, 0.35, 0.5, 0.7, 1.0)
BOUND_MELANIN_BLENDS = (0.0, 0.5, 1.0)

_BOUNDS: dict[tuple[Any, ...], tuple[float, float, dict[str, int]]] = {}


def _bound_key(settings: Any) -> tuple[Any, ...]:
    return (settings.method, settings.blender, settings.engine, settings.accuracy, settings.transport,
            settings.working_space, tuple(sorted(settings.changed_extended().items())))


def radius_bound_mm(settings: Any) -> tuple[float, dict[str, int]]:
    """The largest extent (mm: Burley's Subsurface Radius × Scale, :func:`extent_mm`) any skin parameters give for
    the settings' target, accuracy, transport, working space and extended physiology (one value per material: a thinner
    epidermis or less baseline absorption widens the radius): the largest over the grid of :data:`BOUND_MELANIN_FRACTIONS` ×
    :data:`BOUND_MELANIN_BLENDS`, no blood; and the core's work for it (summed over the grid; computed once per
    process and key)."""
    import spectral_skin

    from .settings import ACCURACY_LEVELS, PARAMETER_INFO
    from .targets import method_name

    key = _bound_key(settings)
    extended = settings.changed_extended()
    if key not in _BOUNDS:
        melanin_max = PARAMETER_INFO["melanin"].high
        largest, ratio, work = 0.0, 0.0, dict[str, int]()
        for fraction in BOUND_MELANIN_FRACTIONS:
            for blend in BOUND_MELANIN_BLENDS if fraction > 0 else (0.0,):
                ev = spectral_skin.evaluate(fraction * melanin_max, blend, 0.0, 0.0,
                                            outputs=["radius"], accuracy=ACCURACY_LEVELS[settings.accuracy],
                                            working_space=settings.working_space, blender=settings.blender,
                                            engine=settings.engine, **settings.transport_keywords(), **extended)
                burley = ev["methods"]["burley"]["subsurface_radius_mm"]
                own = ev["methods"][method_name(settings.method)]["subsurface_radius_mm"]
                largest = max(largest, _largest(burley))
                ratio = max(ratio, *(b / o for b, o in zip(burley, own, strict=True) if o > 0))
                work = {k: work.get(k, 0) + v for k, v in ev["work"].items()}
        _BOUNDS[key] = (largest, ratio, work)
    return _BOUNDS[key][0], _BOUNDS[key][2]


def extent_ratio(settings: Any) -> float:
    """The largest ratio of Burley's radius to the settings' method's over the bound grid (1 for Burley): what
    turns a map plan's method radius into an upper bound on its extent (:func:`extent_mm`)."""
    radius_bound_mm(settings)
    return _BOUNDS[_bound_key(settings)][1]


def subsurface_before(settings: Any, facts: SceneFacts | None,
                      threshold_px: float = SUBSURFACE_MIN_RADIUS_PX) -> Decision | None:
    """The subsurface decision taken before the material is computed, so that its radius is not computed at all:
    off when even the largest radius of any skin (:func:`radius_bound_mm`) is under ``threshold_px`` pixels of the
    smallest footprint; None when that does not settle it (the radius is then computed and :func:`decide` compares
    the material's own)."""
    if facts is None:
        return None
    try:
        best = smallest_footprint(facts)
    except ValueError:
        return None
    if best is None:
        return None
    bound_mm, work = radius_bound_mm(settings)
    bound_px = bound_mm / best["footprint_mm"]
    if bound_px >= threshold_px or thin_objects(facts, bound_mm):
        return None
    figures: dict[str, Any] = {"largest_radius_bound_mm": bound_mm, "threshold_px": threshold_px, **best,
                               "largest_radius_bound_px": bound_px, "bound_work": work}
    where = f"at frame {best['frame']}, camera {best['camera']}, object {best['object']}"
    return decision("subsurface", False, f"the largest radius of any skin is {bound_px:.3g} px {where} (under "
                  f"{threshold_px:g} px): plain diffuse with the same albedo; the radius was not computed", figures)


def oiliness_zero_everywhere(settings: Any) -> bool:
    """True when the settings' oiliness is zero at every texel (a map of zeros, or the constant 0 without a map)."""
    import numpy as np

    pmap = settings.maps.get("oiliness")
    if pmap is None:
        return float(settings.oiliness) == 0.0
    return not bool(np.any(np.asarray(pmap.pixels) != 0.0))


def specular_needed(settings: Any) -> bool:
    """Whether the surface reflects anywhere: always for a surface that reflects dry skin (the measured one, a
    dielectric's Fresnel reflection at every oiliness); for the paper's oil layer, unless the oiliness is zero at
    every texel."""
    return bool(settings.surface_reflects_dry()) or not oiliness_zero_everywhere(settings)


def _specular(computed: Computed, settings: SkinSettings) -> Decision:
    if settings.surface_reflects_dry():
        return decision("specular", True, f"the {settings.surface_name()} surface reflects at every oiliness (skin is a "
                      "dielectric: Fresnel reflection even where it is dry)",
                      {"specular_ior_level": computed.surface.specular_ior_level,
                         "coat_weight": computed.surface.coat_weight})
    if oiliness_zero_everywhere(settings):
        return decision("specular", False, "oiliness is zero everywhere: no oil film, and the oil layer is the model's "
                      "only surface term, so there is no specular lobe (Specular IOR Level 0, no texture)",
                      {"oiliness_max": 0.0})
    return decision("specular", True, "oiliness above zero: the oil layer's specular lobe",
                  {"specular_ior_level": computed.surface.specular_ior_level})


def _texels(image: Any) -> Any:
    """An output image as (texels, channels) float64."""
    import numpy as np

    array = np.asarray(image, dtype=np.float64)
    return array.reshape(-1, array.shape[-1] if array.ndim == 3 else 1)


def _constant_maps(computed: Computed, settings: SkinSettings) -> Decision:
    import numpy as np

    if not settings.maps:
        return decision("constant maps", True, "no parameter maps: values, no textures", {"constant": []})
    constant = sorted(kind for kind, image in computed.images().items()
                      if float(np.ptp(_texels(image), axis=0).max()) == 0.0)
    figures = {"constant": constant}
    if constant:
        return decision("constant maps", True, f"{', '.join(sorted(constant))} of one value: set as values, not "
                      "textures", figures)
    return decision("constant maps", True, "every output map varies: textures", figures)


def _engine(computed: Computed) -> Decision:
    target = computed.target
    tested = "" if target["tested"] else f" ({target['untested_reason']})"
    return decision("engine/version", True, f"mapping for Blender {target['blender']} {target['engine'].upper()}"
                  f"{tested}", target)


def _shape_advice(shape: ShapeFacts, largest_mm: float, parts: dict[str, Any] | None) -> tuple[str | None, str]:
    """The method recommended for one object (None: any) and why (thin: :func:`is_thin`; ``parts`` its
    :func:`thin_parts` against :data:`THIN_RADII` × ``largest_mm``)."""
    radii = shape.thickness_mm / largest_mm if largest_mm > 0.0 else float("inf")
    size = f"{shape.object_name}: {shape.thickness_mm:.3g} mm thick ({radii:.3g} × the largest radius)"
    thin = is_thin(shape, largest_mm, parts)
    if parts is not None:
        fraction = parts["thin_area_fraction"]
        if thin:
            centre = ", ".join(f"{v:.3g}" for v in parts["thin_centre"])
            size = (f"{shape.object_name}: {100 * fraction:.3g} % of its surface thinner than {THIN_RADII:g} radii "
                    f"({THIN_RADII * largest_mm:.3g} mm): parts {parts['thin_median_mm']:.3g} mm thick (thinnest "
                    f"{parts['thinnest_mm']:.3g} mm) around ({centre}) in object space")
        else:
            size = (f"{shape.object_name}: thinnest part {parts['thinnest_mm']:.3g} mm "
                    f"({parts['thinnest_mm'] / largest_mm:.3g} × the largest radius; "
                    f"{100 * fraction:.3g} % of its surface under {THIN_RADII:g} radii)")
    if shape.closed is False:
        also = " (thin too: close the mesh, then a random walk)" if thin else ""
        return "BURLEY", (f"{size}, open mesh ({shape.open_edges} edges not shared by two faces): a random walk leaks "
                          f"out through the holes: Burley, or close the mesh{also}")
    unknown = ", no faces to tell closed or open" if shape.closed is None else ", closed"
    if thin:
        return "RANDOM_WALK", (f"{size}{unknown}: under {THIN_RADII:g} radii, where Burley's disk projection is "
                               "wrong: a random walk")
    return None, f"{size}{unknown}: any method (Burley the fastest)"


def _method(computed: Computed, settings: SkinSettings, facts: SceneFacts | None, subsurface: bool) -> Decision:
    """The recommended subsurface method per object (a recommendation: nothing is changed)."""
    method = settings.method
    figures: dict[str, Any] = {"method": method, "thin_radii": THIN_RADII, "objects": {}}
    if not subsurface:
        return decision("subsurface method", True, "subsurface is off: the method does not matter", figures)
    largest_mm = computed.largest_radius_mm()
    figures["largest_radius_mm"] = largest_mm
    if computed.target["engine"] == "eevee":
        return decision("subsurface method", True, "EEVEE renders every method with its screen-space Burley-like "
                      "blur: no method to recommend", figures)
    if facts is None or not facts.shapes:
        return decision("subsurface method", True, f"{method} as chosen: no object using the material to look at",
                      figures)
    wrong = []
    for shape in facts.shapes:
        parts = thin_parts(shape, THIN_RADII * largest_mm)
        recommended, reason = _shape_advice(shape, largest_mm, parts)
        figures["objects"][shape.object_name] = {
            "thickness_mm": shape.thickness_mm, "thickness_radii": shape.thickness_mm / largest_mm,
            "closed": shape.closed, "open_edges": shape.open_edges, "recommended": recommended, "reason": reason,
            "parts": parts}
        if recommended is not None and (recommended == "BURLEY") != (method == "BURLEY"):
            wrong.append(f"{reason} (the material uses {method})")
    if wrong:
        return decision("subsurface method", False, "; ".join(wrong), figures)
    return decision("subsurface method", True, f"{method} suits every object: "
                  + "; ".join(o["reason"] for o in figures["objects"].values()), figures)


def _animation(settings: SkinSettings, facts: SceneFacts | None, evaluations: int | None) -> Decision:
    """Whether per-frame values are part of the plan; ``evaluations``: the distinct parameter sets the core
    evaluated for them."""
    animation = facts.animation if facts is not None else None
    if animation is None or not animation.parameters:
        return decision("animation", False, "no keyframed or driven parameter: one value each", {"parameters": {}})
    names = ", ".join(f"{name} {how}" for name, how in sorted(animation.parameters.items()))
    figures: dict[str, Any] = {"parameters": dict(animation.parameters), "first_frame": animation.frames[0],
                               "last_frame": animation.frames[-1]}
    if settings.maps:
        return decision("animation", False, f"{names}, but the material uses parameter maps, computed once with the "
                        f"values of frame {animation.current_frame}: animation needs per-frame maps or the live "
                        "shader", figures)
    counted = ""
    if evaluations is not None:
        figures["evaluations"] = evaluations
        counted = f" ({evaluations} distinct parameter sets evaluated)"
    return decision("animation", True, f"{names}: values per frame for frames {animation.frames[0]}-"
                    f"{animation.frames[-1]}, keyed on the material's nodes{counted}", figures)


def _overridden(entry: Decision, overrides: Mapping[str, str] | None) -> Decision:
    """The decision with the artist's override applied: one other than AUTO wins, and is recorded in the decision
    (``override``) and its reason."""
    choice = (overrides or {}).get(entry.effect, "AUTO")
    if choice not in OVERRIDES:
        raise ValueError(f"override of {entry.effect} must be one of {', '.join(OVERRIDES)}; got {choice!r}")
    if choice == "AUTO" or entry.effect not in OVERRIDABLE:
        return entry
    return dataclasses.replace(entry, override=choice, enabled=choice == "ON",
                               reason=f"forced {choice.lower()} by the override (automatic: {entry.reason})")


def decide(computed: Computed, settings: SkinSettings, facts: SceneFacts | None,
           overrides: Mapping[str, str] | None = None, threshold_px: float = SUBSURFACE_MIN_RADIUS_PX,
           subsurface: Decision | None = None, evaluations: int | None = None) -> tuple[Decision, ...]:
    """The decisions for what the core computed (before any texture is written), with the overrides applied:
    {"subsurface": "AUTO" | "ON" | "OFF", "specular": ...}; an override other than AUTO wins over the decision and
    is recorded in it ("override") and its reason. ``subsurface``: the subsurface decision when it was taken before
    computing (:func:`subsurface_before`; ``computed`` then has no radius). ``evaluations``: the distinct parameter
    sets evaluated for an animated material."""
    sub = subsurface if subsurface is not None else _subsurface(computed, facts, threshold_px, settings)
    engine, sub, specular, constant = (_overridden(entry, overrides) for entry in (
        _engine(computed), sub, _specular(computed, settings), _constant_maps(computed, settings)))
    # After the overrides: the method matters only where subsurface scattering stays.
    method = _method(computed, settings, facts, sub.enabled)
    return engine, sub, method, specular, constant, _animation(settings, facts, evaluations)


def describe(effects: Sequence[Mapping[str, Any]]) -> list[str]:
    """One line per decision, for the batch log and the operator's report."""
    return [f"{e['effect']}: {'on' if e['enabled'] else 'off'} ({e['reason']})" for e in effects]


@dataclass(frozen=True)
class Prior:
    """What is decided before the core is asked: whether it computes the radius and the specular inputs, and the
    subsurface decision when it was taken then (None: it is taken from the computed radius)."""

    radius: bool
    specular: bool
    subsurface: Decision | None


def before_computing(settings: SkinSettings, facts: SceneFacts | None,
                     overrides: Mapping[str, str] | None) -> Prior:
    """The effects decided before anything is computed, which are then not computed: subsurface dropped by the
    bound on every skin's radius (or forced off), specular off (oiliness zero at every texel and frame, or forced
    off). ``settings``: an animated material's with the largest oiliness of its frames."""
    choice = {effect: (overrides or {}).get(effect, "AUTO") for effect in OVERRIDABLE}
    before = None if choice["subsurface"] == "ON" else subsurface_before(settings, facts)
    if before is None and choice["subsurface"] == "OFF":
        before = decision("subsurface", True, "not compared: the radius is not computed when forced off",
                          {"threshold_px": SUBSURFACE_MIN_RADIUS_PX})
    specular = choice["specular"] == "ON" or (choice["specular"] == "AUTO" and specular_needed(settings))
    return Prior(radius=before is None, specular=specular, subsurface=before)


def _key(settings: SkinSettings) -> tuple[tuple[str, float], ...]:
    return tuple(settings.constants().items())


@dataclass(frozen=True)
class Frames:
    """An animated constant material's computations: its settings at each frame, and the core's answer for each
    distinct parameter set (computed once each), by :func:`_key`."""

    frames: tuple[int, ...]
    settings: tuple[SkinSettings, ...]
    computed: Mapping[tuple[tuple[str, float], ...], Computed]

    def at_each_frame(self) -> list[Computed]:
        return [self.computed[_key(s)] for s in self.settings]

    def widest(self, current: Computed) -> Computed:
        """``current`` with the largest radius and extent over the frames: what the subsurface decision compares
        (taken over every frame)."""
        import numpy as np

        def largest(values: list[Any]) -> tuple[float, ...]:
            return tuple(float(v) for v in np.max(values, axis=0))

        answers = list(self.computed.values())
        return dataclasses.replace(current, radius=largest([c.radius for c in answers]),
                                   extent_radius_mm=largest([c.extent_radius_mm for c in answers]))

    def animation(self, decisions: Sequence[Decision], working_space: str) -> Animation:
        """The values at each frame, changed by the plan's decisions (taken over every frame)."""
        values = [decided_values(c, decisions)[0] for c in self.at_each_frame()]
        return Animation(frames=self.frames, **{name: tuple(getattr(v, name) for v in values)
                                                for name in ANIMATED_VALUES},
                         units={"base_color": f"linear RGB, {working_space}", **ANIMATION_UNITS})


# The plan's values that the animation sets per frame (fields of the material plan), and their units.
ANIMATED_VALUES = tuple(PLAN_INPUTS)
ANIMATION_UNITS = {"radius": "mm (Principled Subsurface Radius; Subsurface Scale makes it scene units)",
                   "specular_ior_level": "Principled Specular IOR Level", "coat_weight": "Principled Coat Weight",
                   "coat_roughness": "Principled Coat Roughness"}


def _frames(frames: tuple[int, ...], at_frames: tuple[SkinSettings, ...], prior: Prior, progress: Any) -> Frames:
    """The core's answer for each distinct parameter set of the animation's frames (no set computed twice)."""
    distinct = {_key(s): s for s in at_frames}
    return Frames(frames=frames, settings=at_frames,
                  computed={key: compute(s, progress, radius=prior.radius, specular=prior.specular)
                            for key, s in distinct.items()})


def _albedo_maps(settings: SkinSettings, computed: Computed, decisions: Sequence[Decision],
                 progress: Any) -> Computed | None:
    """The core's albedo maps where subsurface is dropped after computing maps for another method than Burley (whose
    Base Color is not the albedo): Burley's Base Color, computed without radius or specular; None elsewhere (a
    constant material's albedo came with its one evaluation)."""
    if enabled(decisions, "subsurface") or computed.method == "BURLEY" or computed.albedo is not None:
        return None
    return compute(settings.replace(method="BURLEY"), progress, radius=False, specular=False)


def scene_plan(settings: SkinSettings, facts: SceneFacts | None, overrides: Mapping[str, str] | None = None,
               progress: Any = None, live: Callable[[], LivePart] | None = None) -> MaterialPlan:
    """The material plan for a scene, the one path of the operator and of the batch apply (its textures still to be
    written: :func:`~core.material_plan.write_textures`): what is decided before computing
    (:func:`before_computing`), the core's answer (:func:`~core.plan.compute`), :func:`decide`, then
    :func:`~core.material_plan.build_plan` (with Live mode's part, ``live()``, made once the core has answered:
    core/live.py).

    Animated parameters (``facts.animation``) take their values at the current frame. For a material without maps
    the plan also gets ``plan.animation``: one value per frame, each computed by the core (once per distinct
    parameter set) and changed by the same decisions, which are taken over every frame: the largest radius over the
    frames, and oiliness zero only if it is zero at every frame.
    """
    start = time.perf_counter()
    animation = facts.animation if facts is not None and facts.animation and facts.animation.parameters else None
    if animation is not None:
        settings = settings.replace(**animation.at(animation.current_frame))
    at_frames = tuple(settings.replace(**animation.at(frame)) for frame in animation.frames) \
        if animation is not None and not settings.maps else ()
    deciding = settings.replace(oiliness=max(s.oiliness for s in at_frames)) if at_frames else settings
    prior = before_computing(deciding, facts, overrides)
    frames = _frames(animation.frames, at_frames, prior, progress) if animation is not None and at_frames else None
    # The current frame's parameter set is usually one of the range's: it is not computed twice.
    current = frames.computed.get(_key(settings)) if frames is not None else None
    computed = current or compute(settings, progress, radius=prior.radius, specular=prior.specular)
    compared = frames.widest(computed) if frames is not None and prior.radius else computed
    decisions = decide(compared, deciding, facts, overrides, subsurface=prior.subsurface,
                       evaluations=len(frames.computed) if frames is not None else None)
    albedo = _albedo_maps(settings, computed, decisions, progress)
    works = [c.work for c in (*(frames.computed.values() if frames else ()), *(() if current else (computed,)),
                              *((albedo,) if albedo else ()))]
    return build_plan(settings, computed, decisions, albedo=albedo, work=sum_work(works), live=live() if live else None,
                      animation=frames.animation(decisions, settings.working_space) if frames else None,
                      seconds=time.perf_counter() - start)
