"""Animation as Blender data (bpy only): F-curves and drivers that Apply writes, so that a render node with nothing but
Blender (no add-on, no handler, Python auto-run off) renders every frame as the session does.

Blender 4.2 keeps an action's F-curves in ``action.fcurves``; from 4.4 on actions are layered and slotted (the
F-curves of an ID live in the channel bag of its slot; 4.4-4.5's ``action.fcurves`` shows the first slot's only) and
5.0 removed ``action.fcurves``: :func:`curve_collection`
hides the difference. Keys are inserted with Blender's own ``keyframe_insert`` (which makes the action, slot, layer
and strip as each version needs), then their points are set in bulk. Drivers are copied as they are: a driver of
type Average/Sum/Min/Max, or a scripted one whose expression is a "simple expression" (``var``, ``var * 2``, ...),
is evaluated without Python, also where auto-run is off.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

# Action group of every F-curve the add-on writes.
GROUP = "Spectral Skin"


def curve_collection(id_data: Any) -> Any:
    """The F-curve collection of an ID's action (``action.fcurves``, or the channel bag of its slot); None without
    an action."""
    animation_data = getattr(id_data, "animation_data", None)
    if animation_data is None or animation_data.action is None:
        return None
    action = animation_data.action
    # 4.4 and 4.5 keep ``action.fcurves`` for layered actions too, but it shows the first slot's curves only: a node
    # tree keyed into its material's action (as 4.4+ do) has its curves in its own slot's channel bag.
    if hasattr(action, "fcurves") and not getattr(action, "is_action_layered", False):
        return action.fcurves
    from bpy_extras import anim_utils

    bag = anim_utils.action_get_channelbag_for_slot(action, animation_data.action_slot)
    return bag.fcurves if bag is not None else None


def fcurves(id_data: Any) -> list[Any]:
    """The F-curves of an ID's action (empty without one)."""
    curves = curve_collection(id_data)
    return list(curves) if curves is not None else []


def drivers(id_data: Any) -> list[Any]:
    animation_data = getattr(id_data, "animation_data", None)
    return list(animation_data.drivers) if animation_data is not None else []


def remove(id_data: Any, keep: Callable[[str, int], bool], with_drivers: bool = True) -> int:
    """Remove the ID's F-curves (and drivers) for which ``keep(data_path, index)`` is False; returns how many."""
    removed = 0
    curves = curve_collection(id_data)
    if curves is not None:
        for curve in [c for c in curves if not keep(c.data_path, c.array_index)]:
            curves.remove(curve)
            removed += 1
    if with_drivers and getattr(id_data, "animation_data", None) is not None:
        for driver in [d for d in id_data.animation_data.drivers if not keep(d.data_path, d.array_index)]:
            id_data.animation_data.drivers.remove(driver)
            removed += 1
    return removed


def _new_curve(target: Any, prop: str, index: int, frame: float) -> Any:
    """A new F-curve of ``target.prop[index]`` with one key at ``frame`` (any old one removed first)."""
    id_data = target.id_data
    path, slot = target.path_from_id(prop), max(index, 0)  # a scalar's F-curve has index 0
    remove(id_data, lambda p, i: not (p == path and i == slot), with_drivers=False)
    target.keyframe_insert(prop, index=index, frame=frame, group=GROUP)
    curve = curve_collection(id_data).find(path, index=slot)
    if curve is None:  # pragma: no cover - keyframe_insert made it
        raise RuntimeError(f"no F-curve for {path}[{index}] after keyframe_insert")
    return curve


def write_keys(target: Any, prop: str, index: int, frames: Sequence[int], values: Sequence[float],
               interpolation: str = "CONSTANT") -> Any:
    """One key per frame on ``target.prop[index]`` (``index`` -1 for a scalar), replacing its F-curve; CONSTANT
    keeps each frame's value until the next frame (sub-frames, motion blur). Returns the F-curve."""
    curve = _new_curve(target, prop, index, frames[0])
    points = curve.keyframe_points
    points.add(len(frames) - 1)
    flat = [float(v) for pair in zip(frames, values, strict=True) for v in pair]
    points.foreach_set("co", flat)
    for point in points:
        point.interpolation = interpolation
        point.handle_left = point.handle_right = point.co
    curve.update()
    return curve


def copy_keys(source: Any, target: Any, prop: str, index: int = -1) -> Any | None:
    """Copy the F-curve ``source`` (its keys, handles, interpolation, extrapolation, modifiers) onto
    ``target.prop[index]``; None (nothing changed) for a curve without keys."""
    points = source.keyframe_points
    if len(points) == 0:
        return None
    curve = _new_curve(target, prop, index, points[0].co[0] if len(points) else 0.0)
    curve.keyframe_points.add(len(points) - 1)
    for src, dst in zip(points, curve.keyframe_points, strict=True):
        for name in ("co", "handle_left", "handle_right", "handle_left_type", "handle_right_type", "interpolation",
                     "easing", "back", "amplitude", "period"):
            setattr(dst, name, getattr(src, name))
    curve.extrapolation = source.extrapolation
    curve.mute = source.mute
    copy_modifiers(source, curve)
    curve.update()
    return curve


# F-curve modifier properties set first: they size or switch the others (a Generator's coefficients).
_MODIFIER_FIRST = ("mode", "poly_order", "function_type")


def copy_modifiers(source: Any, curve: Any) -> None:
    """Replace ``curve``'s F-curve modifiers by copies of ``source``'s (Cycles, Noise, Generator, ...: every
    writable plain property; an Envelope's control points are not copied)."""
    for modifier in list(curve.modifiers):
        curve.modifiers.remove(modifier)
    for original in source.modifiers:
        copy = curve.modifiers.new(original.type)
        names = [p.identifier for p in original.bl_rna.properties
                 if not p.is_readonly and p.type != "POINTER" and p.identifier not in {"rna_type", "type"}]
        for name in sorted(names, key=lambda n: n not in _MODIFIER_FIRST):
            try:
                setattr(copy, name, getattr(original, name))
            except (AttributeError, TypeError, ValueError):  # pragma: no cover - a property of another mode
                pass


def copy_driver(source: Any, target: Any, prop: str, index: int = -1) -> Any:
    """Copy the driver F-curve ``source`` (type, expression, variables and their targets, its own keys) onto
    ``target.prop[index]``, replacing any driver there."""
    path, slot = target.path_from_id(prop), max(index, 0)
    id_data = target.id_data
    if id_data.animation_data is not None:
        for old in [d for d in id_data.animation_data.drivers if d.data_path == path and d.array_index == slot]:
            id_data.animation_data.drivers.remove(old)
    curve = target.driver_add(prop, index)
    driver, original = curve.driver, source.driver
    driver.type = original.type
    driver.expression = original.expression
    driver.use_self = original.use_self
    for variable in original.variables:
        copy = driver.variables.new()
        copy.name, copy.type = variable.name, variable.type
        for src, dst in zip(variable.targets, copy.targets, strict=False):
            if variable.type == "SINGLE_PROP":
                dst.id_type = src.id_type
            dst.id = src.id
            for name in ("data_path", "bone_target", "transform_type", "transform_space", "rotation_mode"):
                setattr(dst, name, getattr(src, name))
    # The mapping from the driver's value: the source's keys and modifiers, in place of the default mapping
    # driver_add gives a new curve in this version (a Generator modifier, or keys).
    for point in reversed(list(curve.keyframe_points)):
        curve.keyframe_points.remove(point, fast=True)
    curve.keyframe_points.add(len(source.keyframe_points))
    for src, dst in zip(source.keyframe_points, curve.keyframe_points, strict=True):
        for name in ("co", "handle_left", "handle_right", "handle_left_type", "handle_right_type", "interpolation"):
            setattr(dst, name, getattr(src, name))
    copy_modifiers(source, curve)
    curve.mute = source.mute
    curve.update()
    return curve
