"""What the scene calls for: which effects of the skin material any camera can see, decided from plain facts (no bpy).

The bpy glue (``blender_addon/scene_facts.py``) gathers :class:`SceneFacts` from the scene; :func:`decide` turns
them and a computed material plan (core/plan.py) into a list of decisions ``{"effect", "enabled", "reason",
"figures", "override"}`` and :func:`apply_decisions` changes the material plan accordingly, before any texture is
written. The same functions run from the operator and from the headless batch path.

Effects:

- ``subsurface``: the smallest pixel footprint on the skin (mm per pixel) over every view (object, camera, frame),
  compared with the material's largest Subsurface Radius × Scale (mm). When the largest radius is below
  :data:`SUBSURFACE_MIN_RADIUS_PX` pixels everywhere, subsurface scattering is dropped: Subsurface Weight 0 with the
  skin's total diffuse reflectance (the albedo) as Base Color, which keeps the total reflectance exact and only
  loses the blur no pixel can show (Subsurface Weight 0 is a diffuse closure of weight Base Color:
  docs/blender-principled.md, Subsurface Weight).
- ``specular``: the model's only surface term is the oil layer on the skin (Donner & Jensen 2006, ρ_s scales the
  Torrance-Sparrow lobe); oiliness zero everywhere means no oil film, hence no specular lobe at all: Specular IOR
  Level 0 and no specular texture.
- ``constant maps``: an output map whose texels all hold one value is set as a value, not written as a texture
  (exact; the override Off writes the texture all the same).
- ``engine/version``: the target the core computed for (core/targets.py), recorded as the plan's first entry.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

# Largest subsurface radius, in pixels of the smallest footprint, below which subsurface scattering is dropped.
# Chosen from the measurement in docs/scene-effects.md (scripts/scene_effects_report.py): at and below this radius
# the Burley slab and the plain-diffuse slab of the same albedo differ by a mean under 0.5 % of the albedo.
SUBSURFACE_MIN_RADIUS_PX = 0.25

OVERRIDES = ("AUTO", "ON", "OFF")
# Effects an artist can force on or off (engine/version is required by the target). "constant maps" on: an output
# map of one value is set as a value; off: written as a texture all the same.
OVERRIDABLE = ("subsurface", "specular", "constant maps")

MM_PER_METRE = 1000.0


@dataclass(frozen=True)
class CameraFacts:
    """A camera at one frame. Lengths: ``lens_mm``, ``sensor_*_mm`` in mm; ``ortho_scale``, ``clip_start`` and the
    location in scene units; ``forward`` a unit vector (world space) along the view axis."""

    name: str
    type: str  # "PERSP", "ORTHO" or "PANO"
    location: tuple[float, float, float]
    forward: tuple[float, float, float]
    lens_mm: float = 50.0
    sensor_width_mm: float = 36.0
    sensor_height_mm: float = 24.0
    sensor_fit: str = "AUTO"  # "AUTO", "HORIZONTAL", "VERTICAL"
    ortho_scale: float = 6.0
    clip_start: float = 0.1


@dataclass(frozen=True)
class View:
    """One object seen by one camera at one frame: the object's bounding-box corners in world space."""

    object_name: str
    frame: int
    camera: CameraFacts
    corners: tuple[tuple[float, float, float], ...]


@dataclass(frozen=True)
class SceneFacts:
    """What the analysis needs of a scene for one material: render size and the views of the objects using it."""

    resolution_x: int
    resolution_y: int
    resolution_percentage: int = 100
    scale_length: float = 1.0  # metres per scene unit
    views: tuple[View, ...] = field(default_factory=tuple)
    note: str = ""  # why there are no views (no camera, no object), for the reason


def _dot(a: Sequence[float], b: Sequence[float]) -> float:
    return sum(x * y for x, y in zip(a, b, strict=True))


def nearest_depth(camera: CameraFacts, corners: Sequence[Sequence[float]]) -> float | None:
    """The smallest depth along the view axis of the box (scene units), not less than the camera's clip start; None
    when the whole box is behind the camera. Depth is a linear function, so its minimum over a box is at a corner;
    the depth of a point is never more than its distance, so the footprint from it is never too large."""
    depths = [_dot([c[i] - camera.location[i] for i in range(3)], camera.forward) for c in corners]
    if not depths or max(depths) <= 0.0:
        return None
    return max(min(depths), camera.clip_start)


def pixels_across(facts: SceneFacts, camera: CameraFacts) -> tuple[float, str]:
    """The rendered pixels along the sensor's fitted dimension, and which ("width", "height"), as Blender fits it:
    AUTO fits the sensor width (or the orthographic scale) to the larger image dimension."""
    x = facts.resolution_x * facts.resolution_percentage / 100.0
    y = facts.resolution_y * facts.resolution_percentage / 100.0
    fit = camera.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if x >= y else "VERTICAL"
    return (x, "width") if fit == "HORIZONTAL" else (y, "height")


def footprint_mm(facts: SceneFacts, camera: CameraFacts, depth: float) -> float:
    """Millimetres of a surface facing the camera at ``depth`` (scene units) that one pixel spans.

    Perspective: the fitted sensor dimension over the focal length is the view's width per unit depth; orthographic:
    the orthographic scale is the view's width. ValueError for a panoramic camera (no single footprint)."""
    pixels, _dimension = pixels_across(facts, camera)
    if camera.type == "ORTHO":
        span = camera.ortho_scale
    elif camera.type == "PERSP":
        sensor = camera.sensor_width_mm
        if camera.sensor_fit == "VERTICAL":  # Blender: VERTICAL fits the sensor height, the others its width
            sensor = camera.sensor_height_mm
        span = sensor / camera.lens_mm * depth
    else:
        raise ValueError(f"camera {camera.name!r} is {camera.type}: only perspective and orthographic cameras have a "
                         "pixel footprint")
    return span / pixels * facts.scale_length * MM_PER_METRE


def smallest_footprint(facts: SceneFacts) -> dict[str, Any] | None:
    """The smallest footprint over all views: {"footprint_mm", "frame", "camera", "object", "depth"}; None when no
    view sees the object. ValueError for a panoramic camera."""
    best: dict[str, Any] | None = None
    for view in facts.views:
        depth = nearest_depth(view.camera, view.corners)
        if depth is None:
            continue
        mm = footprint_mm(facts, view.camera, depth)
        if best is None or mm < best["footprint_mm"]:
            best = {"footprint_mm": mm, "frame": view.frame, "camera": view.camera.name, "object": view.object_name,
                    "depth": depth}
    return best


def _entry(effect: str, enabled: bool, reason: str, figures: dict[str, Any] | None = None) -> dict[str, Any]:
    return {"effect": effect, "enabled": bool(enabled), "reason": reason, "figures": figures or {},
            "override": "AUTO"}


def _largest(values: Any) -> float:
    import numpy as np

    return float(np.max(np.asarray(values, dtype=np.float64)))


def _subsurface(plan: dict[str, Any], facts: SceneFacts | None, threshold_px: float) -> dict[str, Any]:
    radius = plan["images"]["radius"] if plan.get("radius") is None else plan["radius"]
    largest_mm = _largest(radius)
    figures: dict[str, Any] = {"largest_radius_mm": largest_mm, "threshold_px": threshold_px}
    if facts is None:
        return _entry("subsurface", True, "no scene facts: kept", figures)
    try:
        best = smallest_footprint(facts)
    except ValueError as error:
        return _entry("subsurface", True, f"kept: {error}", figures)
    if best is None:
        return _entry("subsurface", True, f"kept: {facts.note or 'no camera sees an object using the material'}",
                      figures)
    radius_px = largest_mm / best["footprint_mm"]
    figures.update(best, largest_radius_px=radius_px)
    where = f"at frame {best['frame']}, camera {best['camera']}, object {best['object']}"
    if radius_px < threshold_px:
        return _entry("subsurface", False, f"largest radius {radius_px:.3g} px {where} (under {threshold_px:g} px): "
                      "plain diffuse with the same albedo", figures)
    return _entry("subsurface", True, f"largest radius {radius_px:.3g} px {where} (at least {threshold_px:g} px)",
                  figures)


def oiliness_zero_everywhere(settings: Any) -> bool:
    """True when the settings' oiliness is zero at every texel (a map of zeros, or the constant 0 without a map)."""
    import numpy as np

    pmap = settings.maps.get("oiliness")
    if pmap is None:
        return float(settings.oiliness) == 0.0
    return not bool(np.any(np.asarray(pmap.pixels) != 0.0))


def _specular(plan: dict[str, Any], settings: Any) -> dict[str, Any]:
    if oiliness_zero_everywhere(settings):
        return _entry("specular", False, "oiliness is zero everywhere: no oil film, and the oil layer is the model's "
                      "only surface term, so there is no specular lobe (Specular IOR Level 0, no texture)",
                      {"oiliness_max": 0.0})
    return _entry("specular", True, "oiliness above zero: the oil layer's specular lobe",
                  {"specular_ior_level": plan["specular_ior_level"]})


def _texels(image: Any) -> Any:
    """An output image as (texels, channels) float64."""
    import numpy as np

    array = np.asarray(image, dtype=np.float64)
    return array.reshape(-1, array.shape[-1] if array.ndim == 3 else 1)


def _constant_maps(plan: dict[str, Any], settings: Any) -> dict[str, Any]:
    import numpy as np

    if not settings.maps:
        return _entry("constant maps", True, "no parameter maps: values, no textures", {"constant": []})
    constant = sorted(kind for kind, image in plan["images"].items() if float(np.ptp(_texels(image), axis=0).max()) == 0.0)
    figures = {"constant": constant}
    if constant:
        return _entry("constant maps", True, f"{', '.join(sorted(constant))} of one value: set as values, not "
                      "textures", figures)
    return _entry("constant maps", True, "every output map varies: textures", figures)


def _engine(plan: dict[str, Any]) -> dict[str, Any]:
    target = plan["target"]
    tested = "" if target["tested"] else " (newer than tested: newest known behaviour)"
    return _entry("engine/version", True, f"mapping for Blender {target['blender']} {target['engine'].upper()}"
                  f"{tested}", dict(target))


def decide(plan: dict[str, Any], settings: Any, facts: SceneFacts | None,
           overrides: dict[str, str] | None = None,
           threshold_px: float = SUBSURFACE_MIN_RADIUS_PX) -> list[dict[str, Any]]:
    """The decisions for a computed material plan (before its textures are written), with the overrides applied:
    {"subsurface": "AUTO" | "ON" | "OFF", "specular": ...}; an override other than AUTO wins over the decision and
    is recorded in the entry ("override") and its reason."""
    effects = [_engine(plan), _subsurface(plan, facts, threshold_px), _specular(plan, settings),
               _constant_maps(plan, settings)]
    for entry in effects:
        choice = (overrides or {}).get(entry["effect"], "AUTO")
        if choice not in OVERRIDES:
            raise ValueError(f"override of {entry['effect']} must be one of {', '.join(OVERRIDES)}; got {choice!r}")
        if choice != "AUTO" and entry["effect"] in OVERRIDABLE:
            entry["override"] = choice
            entry["enabled"] = choice == "ON"
            entry["reason"] = f"forced {choice.lower()} by the override (automatic: {entry['reason']})"
    return effects


def enabled(effects: list[dict[str, Any]], effect: str) -> bool:
    return next(e["enabled"] for e in effects if e["effect"] == effect)


def _drop_texture(plan: dict[str, Any], kind: str) -> None:
    plan["textures"].pop(kind, None)
    plan["images"].pop(kind, None)


def apply_decisions(plan: dict[str, Any], effects: list[dict[str, Any]], albedo: Sequence[float] | None = None) -> None:
    """Change the material plan as the decisions say (in place; before :func:`~core.plan.write_textures`).

    Subsurface off: Subsurface Weight 0 and ``albedo`` as Base Color (the skin's total diffuse reflectance: the
    Burley Base Color; None keeps the plan's Base Color or albedo texture, right for a Burley plan); the radius
    texture is not written (the radius, unused at weight 0, becomes the mean). Specular off: Specular IOR Level 0 and
    no specular texture. Constant maps: an output texture of one value becomes that value.
    """
    plan["effects"] = effects
    plan["subsurface_weight"] = 1.0
    if not enabled(effects, "subsurface"):
        plan["subsurface_weight"] = 0.0
        plan["radius"] = [float(v) for v in plan["summary"]["radius_mm"]]
        _drop_texture(plan, "radius")
        if albedo is not None:
            plan["base_color"] = [float(v) for v in albedo]
            _drop_texture(plan, "albedo")
    if not enabled(effects, "specular"):
        plan["specular_ior_level"] = 0.0
        _drop_texture(plan, "specular")
    entry = next(e for e in effects if e["effect"] == "constant maps")
    constant = entry["figures"].get("constant", []) if entry["enabled"] else []
    for kind in constant:
        if kind not in plan["images"]:
            continue
        value = [float(v) for v in _texels(plan["images"][kind])[0]]
        key = {"albedo": "base_color", "radius": "radius", "specular": "specular_ior_level"}[kind]
        plan[key] = value[0] if kind == "specular" else value
        _drop_texture(plan, kind)


def describe(effects: list[dict[str, Any]]) -> list[str]:
    """One line per decision, for the batch log and the operator's report."""
    return [f"{e['effect']}: {'on' if e['enabled'] else 'off'} ({e['reason']})" for e in effects]


def sample_frames(start: int, end: int, count: int = 8, extra: Sequence[int] = ()) -> list[int]:
    """Frames to look at: the first, the last, up to ``count`` evenly between, and ``extra`` ones in range (markers),
    sorted without repeats."""
    if end < start:
        start, end = end, start
    frames = {start, end, *(f for f in extra if start <= f <= end)}
    span = end - start
    for i in range(1, count + 1):
        frames.add(start + round(span * i / (count + 1)))
    return sorted(frames)


def active_camera(frame: int, scene_camera: str | None, markers: Sequence[tuple[int, str]]) -> str | None:
    """The camera that renders ``frame``: the camera of the last camera-binding marker at or before it, else of the
    earliest such marker (as Blender's camera switching does), else the scene's camera. ``markers``: (frame, camera
    name) of the markers bound to a camera."""
    if not markers:
        return scene_camera
    before = [m for m in markers if m[0] <= frame]
    chosen = max(before, key=lambda m: m[0]) if before else min(markers, key=lambda m: m[0])
    return chosen[1]


def scene_plan(settings: Any, facts: SceneFacts | None, overrides: dict[str, str] | None = None,
               progress: Any = None) -> dict[str, Any]:
    """The material plan for a scene: :func:`~core.plan.make_plan`, :func:`decide`, :func:`apply_decisions`; the
    decisions are in ``plan["effects"]``. The one path of the operator and of the batch apply (textures still to be
    written with :func:`~core.plan.write_textures`).

    Where subsurface is dropped from a method other than Burley (whose Base Color is not the albedo), the albedo is
    Burley's (the skin's total diffuse reflectance), computed by the core for that method."""
    from .plan import make_plan

    plan = make_plan(settings, progress)
    effects = decide(plan, settings, facts, overrides)
    albedo = None
    if not enabled(effects, "subsurface") and settings.method != "BURLEY":
        burley = make_plan(settings.replace(method="BURLEY"), progress)
        if burley["base_color"] is not None:
            albedo = burley["base_color"]
        else:
            plan["images"]["albedo"] = burley["images"]["albedo"]
        plan["summary"]["albedo"] = burley["summary"]["albedo"]
    apply_decisions(plan, effects, albedo)
    return plan
