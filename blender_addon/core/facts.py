"""The plain facts the scene analysis reads (no bpy): the cameras, the views of the objects using a material, their
shapes and the material's animated parameters, gathered by the bpy glue (``blender_addon/scene_facts.py``); and the
geometry of a pixel's footprint on the skin and of thin parts, which the decisions (core/scene.py) compare the
material's radius with.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

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
