"""The scene's facts for the scene analysis (core/scene.py), gathered with bpy: the decisions themselves are portable.

For a material: every object of the scene that renders it, seen by the camera that renders each sampled frame (the
scene's camera, or the camera of the timeline marker in force: Blender's camera switching), with the camera's lens,
sensor or orthographic scale and the object's evaluated bounding box in world space at that frame. Frames: the first
and last of the scene's range, up to :data:`FRAME_SAMPLES` evenly between, and the marker frames.
"""

from __future__ import annotations

from typing import Any

import bpy

from .core import scene as analysis

FRAME_SAMPLES = 8  # frames sampled between the first and the last (each costs one scene.frame_set)

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


def gather(scene: bpy.types.Scene, material: bpy.types.Material) -> analysis.SceneFacts:
    """The facts of ``scene`` for ``material``; the scene's current frame is restored afterwards."""
    render = scene.render
    base = {"resolution_x": render.resolution_x, "resolution_y": render.resolution_y,
            "resolution_percentage": render.resolution_percentage, "scale_length": scene.unit_settings.scale_length}
    objects = _objects_using(scene, material)
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


def scene_plan(material: bpy.types.Material, scene: bpy.types.Scene, settings: Any, progress: Any = None) -> dict:
    """The material plan for this scene: the one path of the operator and of the batch apply (maps not yet
    written)."""
    return analysis.scene_plan(settings, gather(scene, material), overrides(material), progress)
