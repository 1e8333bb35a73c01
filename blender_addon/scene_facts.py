"""The scene's facts for the scene analysis (core/scene.py), gathered with bpy: the decisions themselves are portable.

For a material: every object of the scene that renders it, seen by the camera that renders each sampled frame (the
scene's camera, or the camera of the timeline marker in force: Blender's camera switching), with the camera's lens,
sensor or orthographic scale and the object's evaluated bounding box in world space at that frame. Frames: the first
and last of the scene's range, up to :data:`FRAME_SAMPLES` evenly between, and the marker frames. At the current
frame, each such object's shape: the smallest dimension of its evaluated bounds and whether its evaluated mesh is
closed. And the material's animated Spectral Skin parameters with their values at every frame of the range: an
F-curve of the material's action is evaluated directly; a driver (which may read anything) by setting each frame.
"""

from __future__ import annotations

from typing import Any

import bpy

from . import anim
from .core import PARAMETER_INFO, PARAMETERS
from .core import scene as analysis

FRAME_SAMPLES = 8  # frames sampled between the first and the last (each costs one scene.frame_set)
# Faces whose thickness is measured per object (evenly spread over the face indices): each costs one ray cast, and
# the BVH tree costs a pass over the mesh (docs/scene-effects.md: the time on a 100k-face mesh).
THICKNESS_SAMPLES = 2048

OVERRIDE_ITEMS = [
    ("AUTO", "Auto", "Decided from the scene"),
    ("ON", "On", "Always simulated"),
    ("OFF", "Off", "Never simulated"),
]


def _objects_using(scene: bpy.types.Scene, material: bpy.types.Material) -> list[bpy.types.Object]:
    return [obj for obj in scene.objects
            if not obj.hide_render and any(slot.material == material for slot in getattr(obj, "material_slots", ()))]


def _camera_markers(scene: bpy.types.Scene) -> list[tuple[int, str]]:
    return [(m.frame, m.camera.name) for m in scene.timeline_markers if m.camera is not None]


def _camera_facts(obj: bpy.types.Object) -> analysis.CameraFacts:
    data = obj.data
    matrix = obj.matrix_world
    forward = (matrix.to_3x3() @ _vector((0.0, 0.0, -1.0))).normalized()
    return analysis.CameraFacts(
        name=obj.name, type=data.type, location=tuple(matrix.translation), forward=tuple(forward),
        lens_mm=data.lens, sensor_width_mm=data.sensor_width, sensor_height_mm=data.sensor_height,
        sensor_fit=data.sensor_fit, ortho_scale=data.ortho_scale, clip_start=data.clip_start)


def _vector(values: Any) -> Any:
    from mathutils import Vector

    return Vector(values)


def _part_thickness(evaluated: Any, depsgraph: Any, mesh: Any, mm_per_unit: float) -> tuple[Any, ...]:
    """(thickness_mm, area_mm2, (x, y, z) object-space centre) of up to :data:`THICKNESS_SAMPLES` faces, evenly
    spread over the face indices: the distance in world space from the face's centre along its inward normal to the
    first surface the ray meets (cast from just inside, in object space, so scale and modifiers count). Faces whose
    ray meets nothing (an open or one-sided surface) are left out."""
    import numpy as np
    from mathutils import Vector
    from mathutils.bvhtree import BVHTree

    count = len(mesh.polygons)
    indices = np.unique(np.linspace(0, count - 1, min(count, THICKNESS_SAMPLES)).round().astype(np.int64))
    centres = np.empty(count * 3)
    normals = np.empty(count * 3)
    areas = np.empty(count)
    mesh.polygons.foreach_get("center", centres)
    mesh.polygons.foreach_get("normal", normals)
    mesh.polygons.foreach_get("area", areas)
    centres, normals = centres.reshape(-1, 3)[indices], normals.reshape(-1, 3)[indices]
    linear = np.array(evaluated.matrix_world.to_3x3())
    inverse_transpose = np.linalg.inv(linear).T
    # A face's world normal is M^-T n; its world area is its area x |det M| x |M^-T n|.
    world_normals = normals @ inverse_transpose.T
    lengths = np.linalg.norm(world_normals, axis=1)
    world_areas = areas[indices] * abs(np.linalg.det(linear)) * lengths
    # The inward world direction -n_w, as an object-space direction (an affine map keeps lines).
    inward = -(world_normals / np.maximum(lengths, 1e-300)[:, None]) @ np.linalg.inv(linear).T
    inward /= np.maximum(np.linalg.norm(inward, axis=1), 1e-300)[:, None]
    tree = BVHTree.FromObject(evaluated, depsgraph)
    extent = float(np.linalg.norm(np.ptp(np.array([tuple(c) for c in evaluated.bound_box]), axis=0)))
    start = 1e-6 * extent if extent > 0.0 else 1e-9
    samples = []
    for k, face in enumerate(indices):
        centre = Vector(centres[k])
        direction = Vector(inward[k])
        hit, _normal, index, _distance = tree.ray_cast(centre + direction * start, direction)
        if hit is None or index == face:
            continue
        world = float(np.linalg.norm(linear @ np.array(hit - centre)))
        samples.append((world * mm_per_unit, float(world_areas[k]) * mm_per_unit**2, tuple(centres[k])))
    return tuple(samples)


def _shape(obj: bpy.types.Object, depsgraph: Any, scale_length: float) -> analysis.ShapeFacts:
    """The object's evaluated bounds' smallest dimension in mm, whether its evaluated mesh is closed (every edge
    shared by exactly two faces, counted from the faces' loops) and its thickness part by part
    (:func:`_part_thickness`)."""
    import numpy as np

    evaluated = obj.evaluated_get(depsgraph)
    mm_per_unit = scale_length * analysis.MM_PER_METRE
    thickness_mm = min(evaluated.dimensions) * mm_per_unit
    mesh = evaluated.to_mesh()
    try:
        if mesh is None or len(mesh.polygons) == 0:
            return analysis.ShapeFacts(obj.name, thickness_mm, None)
        edges = np.empty(len(mesh.loops), dtype=np.int64)
        mesh.loops.foreach_get("edge_index", edges)
        faces_per_edge = np.bincount(edges, minlength=len(mesh.edges))
        open_edges = int(np.count_nonzero(faces_per_edge != 2))
        parts = _part_thickness(evaluated, depsgraph, mesh, mm_per_unit)
        sampled = min(len(mesh.polygons), THICKNESS_SAMPLES)
    finally:
        evaluated.to_mesh_clear()
    return analysis.ShapeFacts(obj.name, thickness_mm, open_edges == 0, open_edges, parts=parts,
                               sampled_faces=sampled)


def gather_animation(scene: bpy.types.Scene, material: bpy.types.Material) -> analysis.AnimationFacts | None:
    """The material's keyframed or driven Spectral Skin parameters and their values at every frame of the scene's
    range, clamped into the parameters' ranges as Blender clamps the property; None when none is animated. Muted
    curves and drivers are left out; NLA strips are not looked at."""
    animation_data = material.animation_data
    if animation_data is None:
        return None
    paths = {f"spectral_skin.{name}": name for name in PARAMETERS}
    curves = {paths[c.data_path]: c for c in anim.fcurves(material) if c.data_path in paths and not c.mute}
    drivers = {paths[d.data_path] for d in animation_data.drivers if d.data_path in paths and not d.mute}
    how = {name: "keyframed" for name in curves} | {name: "driven" for name in drivers}
    if not how:
        return None
    frames = tuple(range(min(scene.frame_start, scene.frame_end), max(scene.frame_start, scene.frame_end) + 1))
    values: dict[str, list[float]] = {name: [] for name in how}
    current = scene.frame_current, scene.frame_subframe
    try:
        for frame in frames:
            if drivers:
                scene.frame_set(frame)
            for name in how:
                value = float(getattr(material.spectral_skin, name)) if drivers else curves[name].evaluate(frame)
                low, high = PARAMETER_INFO[name][:2]
                values[name].append(min(max(float(value), low), high))
    finally:
        if drivers:
            scene.frame_set(current[0], subframe=current[1])
    return analysis.AnimationFacts(parameters=how, frames=frames, values={k: tuple(v) for k, v in values.items()},
                                   current_frame=scene.frame_current)


def gather(scene: bpy.types.Scene, material: bpy.types.Material) -> analysis.SceneFacts:
    """The facts of ``scene`` for ``material``; the scene's current frame is restored afterwards."""
    render = scene.render
    objects = _objects_using(scene, material)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    scale_length = scene.unit_settings.scale_length
    base = {"resolution_x": render.resolution_x, "resolution_y": render.resolution_y,
            "resolution_percentage": render.resolution_percentage, "scale_length": scale_length,
            "shapes": tuple(_shape(obj, depsgraph, scale_length) for obj in objects),
            "animation": gather_animation(scene, material)}
    markers = _camera_markers(scene)
    if not objects:
        return analysis.SceneFacts(**base, note="no object in the scene renders the material")
    if scene.camera is None and not markers:
        return analysis.SceneFacts(**base, note="the scene has no camera")
    frames = analysis.sample_frames(scene.frame_start, scene.frame_end, FRAME_SAMPLES, [m[0] for m in markers])
    current = scene.frame_current, scene.frame_subframe
    views = []
    try:
        for frame in frames:
            scene.frame_set(frame)
            name = analysis.active_camera(frame, scene.camera.name if scene.camera else None, markers)
            camera = scene.objects.get(name) if name else None
            if camera is None or camera.type != "CAMERA":
                continue
            camera_facts = _camera_facts(camera)
            depsgraph = bpy.context.evaluated_depsgraph_get()
            for obj in objects:
                evaluated = obj.evaluated_get(depsgraph)
                matrix = evaluated.matrix_world
                corners = tuple(tuple(matrix @ _vector(corner)) for corner in evaluated.bound_box)
                views.append(analysis.View(obj.name, frame, camera_facts, corners))
    finally:
        scene.frame_set(current[0], subframe=current[1])
    return analysis.SceneFacts(**base, views=tuple(views))


def overrides(material: bpy.types.Material) -> dict[str, str]:
    """The material's overrides (Spectral Skin settings): {"subsurface": "AUTO" | "ON" | "OFF", "specular": ...,
    "constant maps": ...}."""
    props = material.spectral_skin
    return {effect: getattr(props, override_property(effect)) for effect in analysis.OVERRIDABLE}


def override_property(effect: str) -> str:
    """The name of an effect's override on the material's Spectral Skin settings: ``override_constant_maps``."""
    return "override_" + effect.replace(" ", "_")

