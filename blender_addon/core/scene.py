"""What the scene calls for: which effects of the skin material any camera can see, decided from plain facts (no bpy).

The bpy glue (``blender_addon/scene_facts.py``) gathers :class:`SceneFacts` from the scene; :func:`decide` turns
them and a computed material plan (core/plan.py) into a list of decisions ``{"effect", "enabled", "reason",
"figures", "override"}`` and :func:`apply_decisions` changes the material plan accordingly, before any texture is
written. The same functions run from the operator and from the headless batch path. :func:`scene_plan` takes what
it can decide before computing first (:func:`subsurface_before`, the oiliness), so that a dropped effect is not
computed: the plan's ``work`` (the core's count) shows no radius fit or no specular evaluation.

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
  material gets its values per frame (``plan["animation"]``: computed by the core for each distinct parameter set,
  with the same decisions), written as F-curves by blender_addon/frame_values.py; a material with parameter
  maps renders the current frame's values (``enabled`` False): its animation needs per-frame maps or the live
  shader.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from .material_plan import FIELD_OF_TEXTURE, SURFACE_TEXTURES, MaterialPlan, freeze

# Largest subsurface radius, in pixels of the smallest footprint, below which subsurface scattering is dropped.
# Chosen from the measurement in docs/scene-effects.md (scripts/reports/scene_effects_report.py): at and below this
# radius the Burley slab and the plain-diffuse slab of the same albedo differ by a mean under 0.5 % of the albedo.
SUBSURFACE_MIN_RADIUS_PX = 0.25


OVERRIDES = ("AUTO", "ON", "OFF")
# Effects an artist can force on or off (engine/version is required by the target). "constant maps" on: an output
# map of one value is set as a value; off: written as a texture all the same.
OVERRIDABLE = ("subsurface", "specular", "constant maps")

MM_PER_METRE = 1000.0

# An object thinner than this many largest scatter radii (Subsurface Radius × Scale, mm) gets a random walk
# recommended. Burley's profile is a half-space's: light reaching the far side of a part only 1 to 2 radii thick (most
# of the profile's energy lies within one radius) is projected onto the near surface instead; at 3 radii the
# half-space is a fair model. A rule of thumb, not a measurement (docs/scene-effects.md, Thin and open geometry).
THIN_RADII = 3.0
# An object with at least this fraction of its surface area thinner than THIN_RADII radii (measured part by part,
# docs/scene-effects.md) has thin parts. A rule of thumb, not a measurement: 1 % ignores a few stray samples (a
# crease whose ray meets the surface nearby) and keeps parts such as ears, a few per cent of a head (an estimate).
THIN_AREA_FRACTION = 0.01


def thin_parts(shape: ShapeFacts, thin_mm: float) -> dict[str, Any] | None:
    """The part-by-part figures of ``shape`` against ``thin_mm``: {"sampled_faces", "measured_faces",
    "thin_area_fraction", "thinnest_mm", "thin_median_mm", "thin_centre"} (the area-weighted median thickness and
    the mean object-space centre of the thin samples; None without thin ones); None when no sample was measured."""
    if not shape.parts:
        return None
    total = sum(area for _t, area, _c in shape.parts)
    thin = sorted((p for p in shape.parts if p[0] < thin_mm), key=lambda p: p[0])
    thin_area = sum(area for _t, area, _c in thin)
    figures: dict[str, Any] = {"sampled_faces": shape.sampled_faces, "measured_faces": len(shape.parts),
                               "thin_area_fraction": thin_area / total if total > 0.0 else 0.0,
                               "thinnest_mm": min(p[0] for p in shape.parts), "thin_median_mm": None,
                               "thin_centre": None}
    if thin:
        running = 0.0
        for thickness, area, _c in thin:
            running += area
            if running >= thin_area / 2.0:
                figures["thin_median_mm"] = thickness
                break
        figures["thin_centre"] = tuple(sum(p[2][i] for p in thin) / len(thin) for i in range(3))
    return figures


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
class ShapeFacts:
    """An object using the material, at the current frame: the smallest dimension of its evaluated bounds (object
    axes, with its scale) in mm, whether its evaluated mesh is closed (every edge shared by exactly two faces;
    None: no faces, e.g. not a mesh) with the count of edges that are not, and its thickness part by part:
    ``parts``, one ``(thickness_mm, area_mm2, (x, y, z))`` per sampled face whose inward ray met the opposite
    surface (the face's object-space centre), of ``sampled_faces`` sampled."""

    object_name: str
    thickness_mm: float
    closed: bool | None
    open_edges: int = 0
    parts: tuple[tuple[float, float, tuple[float, float, float]], ...] = ()
    sampled_faces: int = 0


@dataclass(frozen=True)
class AnimationFacts:
    """The material's animated Spectral Skin parameters: {parameter: "keyframed" | "driven"}, their values at each
    frame of the scene's range (ascending, consecutive) and the frame the scene is at."""

    parameters: dict[str, str]
    frames: tuple[int, ...]
    values: dict[str, tuple[float, ...]]
    current_frame: int

    def at(self, frame: int) -> dict[str, float]:
        """The animated parameters' values at ``frame`` (clamped into the range)."""
        index = min(max(frame - self.frames[0], 0), len(self.frames) - 1)
        return {name: float(values[index]) for name, values in self.values.items()}


@dataclass(frozen=True)
class SceneFacts:
    """What the analysis needs of a scene for one material: render size, the views of the objects using it, their
    shapes and the material's animated parameters."""

    resolution_x: int
    resolution_y: int
    resolution_percentage: int = 100
    scale_length: float = 1.0  # metres per scene unit
    views: tuple[View, ...] = field(default_factory=tuple)
    note: str = ""  # why there are no views (no camera, no object), for the reason
    shapes: tuple[ShapeFacts, ...] = field(default_factory=tuple)
    animation: AnimationFacts | None = None


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


def extent_mm(plan: dict[str, Any], settings: Any) -> float:
    """The largest physical extent of the plan's profile, mm, as the Burley radius of the same skin: what
    :data:`SUBSURFACE_MIN_RADIUS_PX` was measured with, whatever the material's method (a random walk's radius is
    a mean free path, several times shorter than Burley's for the same skin in Blender 5.2+, longer before). A
    constant plan has it from its one evaluation (``extent_radius_mm``); a map plan's method radius is scaled by the
    largest Burley-to-method ratio over the bound grid (:func:`radius_bound_mm`), an upper bound."""
    if plan.get("extent_radius_mm") is not None:
        return _largest(plan["extent_radius_mm"])
    radius = plan["images"]["radius"] if plan.get("radius") is None else plan["radius"]
    return _largest(radius) * (1.0 if settings is None else extent_ratio(settings))


def _subsurface(plan: dict[str, Any], facts: SceneFacts | None, threshold_px: float,
                settings: Any = None) -> dict[str, Any]:
    radius = plan["images"]["radius"] if plan.get("radius") is None else plan["radius"]
    largest_mm = _largest(radius)
    extent = extent_mm(plan, settings) if plan.get("extent_radius_mm") is not None or settings is not None \
        else largest_mm
    figures: dict[str, Any] = {"largest_radius_mm": largest_mm, "extent_mm": extent, "threshold_px": threshold_px}
    if facts is None:
        return _entry("subsurface", True, "no scene facts: kept", figures)
    try:
        best = smallest_footprint(facts)
    except ValueError as error:
        return _entry("subsurface", True, f"kept: {error}", figures)
    if best is None:
        return _entry("subsurface", True, f"kept: {facts.note or 'no camera sees an object using the material'}",
                      figures)
    radius_px = extent / best["footprint_mm"]
    figures.update(best, largest_radius_px=radius_px)
    where = f"at frame {best['frame']}, camera {best['camera']}, object {best['object']}"
    thin = thin_objects(facts, largest_mm) if radius_px < threshold_px else []
    if thin:
        figures["thin_objects"] = thin
        return _entry("subsurface", True, f"kept: {', '.join(thin)} {'has' if len(thin) == 1 else 'have'} parts "
                      f"thinner than {THIN_RADII:g} radii, through which subsurface scattering carries light (plain "
                      f"diffuse would lose it at any distance), although the largest radius is {radius_px:.3g} px "
                      f"{where}", figures)
    if radius_px < threshold_px:
        return _entry("subsurface", False, f"largest extent (Burley radius) {radius_px:.3g} px {where} (under "
                      f"{threshold_px:g} px): plain diffuse with the same albedo", figures)
    return _entry("subsurface", True, f"largest extent (Burley radius) {radius_px:.3g} px {where} (at least "
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
                      threshold_px: float = SUBSURFACE_MIN_RADIUS_PX) -> dict[str, Any] | None:
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
    return _entry("subsurface", False, f"the largest radius of any skin is {bound_px:.3g} px {where} (under "
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


def _specular(plan: dict[str, Any], settings: Any) -> dict[str, Any]:
    if settings.surface_reflects_dry():
        return _entry("specular", True, f"the {settings.surface_name()} surface reflects at every oiliness (skin is a "
                      "dielectric: Fresnel reflection even where it is dry)",
                      {"specular_ior_level": plan["specular_ior_level"], "coat_weight": plan["coat_weight"]})
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
    tested = "" if target["tested"] else f" ({target['untested_reason']})"
    return _entry("engine/version", True, f"mapping for Blender {target['blender']} {target['engine'].upper()}"
                  f"{tested}", dict(target))


def is_thin(shape: ShapeFacts, largest_mm: float, parts: dict[str, Any] | None = None) -> bool:
    """Whether ``shape`` has parts thinner than :data:`THIN_RADII` × ``largest_mm``: measured part by part when the
    object has such samples (at least :data:`THIN_AREA_FRACTION` of its surface), else by the smallest dimension of
    its bounds. ``parts``: :func:`thin_parts` of the shape against that thickness, when the caller has it."""
    if parts is None:
        parts = thin_parts(shape, THIN_RADII * largest_mm)
    if parts is not None:
        return bool(parts["thin_area_fraction"] >= THIN_AREA_FRACTION)
    return shape.thickness_mm < THIN_RADII * largest_mm


def thin_objects(facts: SceneFacts | None, largest_mm: float) -> list[str]:
    """The objects using the material that have thin parts (:func:`is_thin`) for the largest radius ``largest_mm``."""
    if facts is None:
        return []
    return [shape.object_name for shape in facts.shapes if is_thin(shape, largest_mm)]


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


def _method(plan: dict[str, Any], settings: Any, facts: SceneFacts | None, subsurface: bool) -> dict[str, Any]:
    """The recommended subsurface method per object (a recommendation: nothing is changed)."""
    method = settings.method
    figures: dict[str, Any] = {"method": method, "thin_radii": THIN_RADII, "objects": {}}
    if not subsurface:
        return _entry("subsurface method", True, "subsurface is off: the method does not matter", figures)
    radius = plan["images"]["radius"] if plan.get("radius") is None else plan["radius"]
    largest_mm = _largest(radius)
    figures["largest_radius_mm"] = largest_mm
    if plan["target"]["engine"] == "eevee":
        return _entry("subsurface method", True, "EEVEE renders every method with its screen-space Burley-like "
                      "blur: no method to recommend", figures)
    if facts is None or not facts.shapes:
        return _entry("subsurface method", True, f"{method} as chosen: no object using the material to look at",
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
        return _entry("subsurface method", False, "; ".join(wrong), figures)
    return _entry("subsurface method", True, f"{method} suits every object: "
                  + "; ".join(o["reason"] for o in figures["objects"].values()), figures)


def _animation(settings: Any, facts: SceneFacts | None) -> dict[str, Any]:
    """Whether per-frame values are part of the plan (figures completed by :func:`scene_plan`)."""
    animation = facts.animation if facts is not None else None
    if animation is None or not animation.parameters:
        return _entry("animation", False, "no keyframed or driven parameter: one value each", {"parameters": {}})
    names = ", ".join(f"{name} {how}" for name, how in sorted(animation.parameters.items()))
    figures: dict[str, Any] = {"parameters": dict(animation.parameters), "first_frame": animation.frames[0],
                               "last_frame": animation.frames[-1]}
    if settings.maps:
        return _entry("animation", False, f"{names}, but the material uses parameter maps, computed once with the "
                      f"values of frame {animation.current_frame}: animation needs per-frame maps or the live shader",
                      figures)
    return _entry("animation", True, f"{names}: values per frame for frames {animation.frames[0]}-"
                  f"{animation.frames[-1]}, keyed on the material's nodes", figures)


def decide(plan: dict[str, Any], settings: Any, facts: SceneFacts | None,
           overrides: dict[str, str] | None = None,
           threshold_px: float = SUBSURFACE_MIN_RADIUS_PX,
           subsurface: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """The decisions for a computed material plan (before its textures are written), with the overrides applied:
    {"subsurface": "AUTO" | "ON" | "OFF", "specular": ...}; an override other than AUTO wins over the decision and
    is recorded in the entry ("override") and its reason. ``subsurface``: the subsurface decision when it was taken
    before the plan was computed (:func:`subsurface_before`; the plan then has no radius)."""
    sub = subsurface if subsurface is not None else _subsurface(plan, facts, threshold_px, settings)
    effects = [_engine(plan), sub, _specular(plan, settings), _constant_maps(plan, settings)]
    for entry in effects:
        choice = (overrides or {}).get(entry["effect"], "AUTO")
        if choice not in OVERRIDES:
            raise ValueError(f"override of {entry['effect']} must be one of {', '.join(OVERRIDES)}; got {choice!r}")
        if choice != "AUTO" and entry["effect"] in OVERRIDABLE:
            entry["override"] = choice
            entry["enabled"] = choice == "ON"
            entry["reason"] = f"forced {choice.lower()} by the override (automatic: {entry['reason']})"
    # After the overrides: the method matters only where subsurface scattering stays.
    effects.insert(2, _method(plan, settings, facts, enabled(effects, "subsurface")))
    effects.append(_animation(settings, facts))
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
        if plan.get("computed", {}).get("radius", True):
            plan["radius"] = [float(v) for v in plan["summary"]["radius_mm"]]
        _drop_texture(plan, "radius")
        if albedo is not None:
            plan["base_color"] = [float(v) for v in albedo]
            _drop_texture(plan, "albedo")
    if not enabled(effects, "specular"):
        plan["specular_ior_level"] = 0.0
        plan["coat_weight"] = 0.0
        if plan.get("coat_roughness") is None:
            plan["coat_roughness"] = plan["roughness"]  # unused at weight 0
        for kind in SURFACE_TEXTURES:
            _drop_texture(plan, kind)
    entry = next(e for e in effects if e["effect"] == "constant maps")
    constant = entry["figures"].get("constant", []) if entry["enabled"] else []
    for kind in constant:
        if kind not in plan["images"]:
            continue
        value = [float(v) for v in _texels(plan["images"][kind])[0]]
        plan[FIELD_OF_TEXTURE[kind]] = value[0] if kind in SURFACE_TEXTURES else value
        _drop_texture(plan, kind)


def describe(effects: Sequence[Mapping[str, Any]]) -> list[str]:
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


def _decided_plan(settings: Any, effects: list[dict[str, Any]], progress: Any,
                  plan: dict[str, Any] | None = None) -> dict[str, Any]:
    """The material plan of ``settings`` (``plan`` when already computed: changed in place) changed as ``effects``
    say. Where subsurface is dropped from a method other than Burley (whose Base Color is not the albedo), Base
    Color is the albedo (the skin's total diffuse reflectance): the core's, which came with a plan of constants (and
    is all a plan computed without the radius has), else the albedo maps computed by the core without radius or
    specular (their work added)."""
    from .plan import make_plan

    if plan is None:
        plan = make_plan(settings, progress)
    albedo = None
    radius_computed = plan.get("computed", {}).get("radius", True)
    if not enabled(effects, "subsurface") and settings.method != "BURLEY" and radius_computed:
        if plan.get("albedo") is not None:
            albedo = plan["albedo"]
            plan["summary"]["albedo"] = albedo
        else:
            # The albedo alone: no radius fit, no specular (the core's maps(outputs=["albedo"])).
            burley = make_plan(settings.replace(method="BURLEY"), progress, radius=False, specular=False)
            plan["work"] = sum_work([plan["work"], burley["work"]])
            if burley["base_color"] is not None:
                albedo = burley["base_color"]
            else:
                plan["images"]["albedo"] = burley["images"]["albedo"]
            plan["summary"]["albedo"] = burley["summary"]["albedo"]
    apply_decisions(plan, effects, albedo)
    return plan


def sum_work(works: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The core's work counts of several computations added up, key by key (nested dicts too)."""
    total: dict[str, Any] = {}
    for work in works:
        for key, value in work.items():
            if isinstance(value, dict):
                total[key] = sum_work([total.get(key, {}), value])
            else:
                total[key] = total.get(key, 0) + value
    return total


# The plan's values that the animation sets per frame (keys of the material plan).
ANIMATED_VALUES = ("base_color", "radius", "specular_ior_level", "coat_weight", "coat_roughness")


def scene_plan(settings: Any, facts: SceneFacts | None, overrides: dict[str, str] | None = None,
               progress: Any = None) -> MaterialPlan:
    """The material plan for a scene (frozen: :class:`~core.material_plan.MaterialPlan`): :func:`scene_draft`. The
    one path of the operator and of the batch apply in Baked mode (textures still to be written with
    :func:`~core.plan.write_textures`)."""
    return freeze(scene_draft(settings, facts, overrides, progress))


def scene_draft(settings: Any, facts: SceneFacts | None, overrides: dict[str, str] | None = None,
                progress: Any = None) -> dict[str, Any]:
    """The draft of the material plan for a scene: :func:`~core.plan.make_plan` of only the effects decided before
    computing, :func:`decide`, :func:`apply_decisions`; the decisions are in ``draft["effects"]``.

    Animated parameters (``facts.animation``) take their values at the current frame. For a material without maps
    the plan also gets ``plan["animation"]``: ``{"frames": [...], "base_color": [[r, g, b], ...], "radius": [...],
    "specular_ior_level": [...], "units": {...}}``, one value per frame, each computed by the core (once per distinct parameter set)
    and changed by the same decisions, which are taken over every frame: the largest radius over the frames, and
    oiliness zero only if it is zero at every frame.
    """
    from .plan import make_plan

    animation = facts.animation if facts is not None else None
    if animation is not None and animation.parameters:
        settings = settings.replace(**animation.at(animation.current_frame))
    per_frame: list[Any] = []
    decision_settings = settings
    if animation is not None and animation.parameters and not settings.maps:
        per_frame = [settings.replace(**animation.at(frame)) for frame in animation.frames]
        decision_settings = settings.replace(oiliness=max(s.oiliness for s in per_frame))
    # Effects decided before anything is computed are not computed: subsurface dropped by the bound on every skin's
    # radius (or forced off), specular off (oiliness zero at every texel and frame, or forced off).
    choice = {effect: (overrides or {}).get(effect, "AUTO") for effect in OVERRIDABLE}
    before = None if choice["subsurface"] == "ON" else subsurface_before(settings, facts)
    if before is None and choice["subsurface"] == "OFF":
        before = _entry("subsurface", True, "not compared: the radius is not computed when forced off",
                        {"threshold_px": SUBSURFACE_MIN_RADIUS_PX})
    radius = before is None
    specular = choice["specular"] == "ON" or (choice["specular"] == "AUTO" and specular_needed(decision_settings))
    decision_plan: dict[str, Any] = {}
    if per_frame:
        distinct = {tuple(s.constants().items()): s for s in per_frame}
        plans = {key: make_plan(s, progress, radius=radius, specular=specular) for key, s in distinct.items()}
        current = plans.get(tuple(settings.constants().items()))
        # The current frame's parameter set is usually one of the range's: its plan is not computed twice.
        plan = copy.deepcopy(current) if current is not None else make_plan(settings, progress, radius=radius,
                                                                             specular=specular)
        works = [p["work"] for p in plans.values()] + ([] if current is not None else [plan["work"]])
        plan["work"] = sum_work(works)
        decision_plan = plan
        if radius:
            import numpy as np

            largest = np.max([p["radius"] for p in plans.values()], axis=0)
            extent = np.max([p["extent_radius_mm"] for p in plans.values()], axis=0)
            decision_plan = {**plan, "radius": [float(v) for v in largest],
                             "extent_radius_mm": [float(v) for v in extent]}
    else:
        plan = decision_plan = make_plan(settings, progress, radius=radius, specular=specular)
    effects = decide(decision_plan, decision_settings, facts, overrides, subsurface=before)
    plan = _decided_plan(settings, effects, progress, plan)
    if per_frame and animation is not None:
        decided = {key: _decided_plan(s, effects, progress, plans[key]) for key, s in distinct.items()}
        frames = [decided[tuple(s.constants().items())] for s in per_frame]
        plan["animation"] = {"frames": list(animation.frames),
                             **{name: [p[name] for p in frames] for name in ANIMATED_VALUES},
                             "units": {"base_color": f"linear RGB, {settings.working_space}",
                                       "radius": "mm (Principled Subsurface Radius; Subsurface Scale makes it scene "
                                       "units)", "specular_ior_level": "Principled Specular IOR Level",
                                       "coat_weight": "Principled Coat Weight",
                                       "coat_roughness": "Principled Coat Roughness"}}
        entry = next(e for e in effects if e["effect"] == "animation")
        entry["figures"]["evaluations"] = len(distinct)
        entry["reason"] += f" ({len(distinct)} distinct parameter sets evaluated)"
    return plan
