"""Per-frame values of an animated constant-parameter material as Blender data: F-curves on the add-on's Principled
BSDF (bpy only; no frame-change handler).

Apply writes the plan's ``animation`` (core/scene.py: Base Color, Subsurface Radius and Specular IOR Level at every
frame of the scene's range, computed by the core) as one key per frame (CONSTANT interpolation) on those sockets'
``default_value`` in the material's node tree (anim.py), so the .blend renders every frame right on a render node
with plain Blender: no add-on, no script, Python auto-run off. Re-applying replaces these F-curves; a plan without
animation, or a socket a texture now feeds, removes them; other F-curves of the tree are kept.
"""

from __future__ import annotations

import bpy

from . import anim
from .core import MaterialPlan
from .core.maps import PLAN_INPUTS

# Per-frame values of an Apply before they became F-curves (JSON on the material): removed at the next Apply.
LEGACY_PROPERTY = "spectral_skin_frames"
# The plan's field -> the Principled input it sets.
SOCKETS = PLAN_INPUTS


def _paths(node: bpy.types.Node) -> set[str]:
    return {s.path_from_id("default_value") for s in node.inputs if s.name in SOCKETS.values()}


def clear(material: bpy.types.Material, node: bpy.types.Node | None) -> int:
    """Remove the per-frame F-curves of ``node`` (the add-on's Principled) and the legacy property."""
    if LEGACY_PROPERTY in material:
        del material[LEGACY_PROPERTY]
    tree = material.node_tree
    if node is None or tree is None:
        return 0
    paths = _paths(node)
    return anim.remove(tree, lambda path, _index: path not in paths, with_drivers=False)


def store(material: bpy.types.Material, node: bpy.types.Node, plan: MaterialPlan) -> int:
    """Write the plan's per-frame values as keys on ``node``'s sockets (the old ones removed first); returns the
    number of F-curves written (0 without animation)."""
    clear(material, node)
    animation = plan.animation
    if not animation:
        return 0
    frames = [int(f) for f in animation["frames"]]
    written = 0
    for key, name in SOCKETS.items():
        values = animation[key]
        socket = next((s for s in node.inputs if s.name == name), None)
        if socket is None or socket.is_linked or any(v is None for v in values):
            continue
        if not isinstance(values[0], (list, tuple)):  # one number per frame
            anim.write_keys(socket, "default_value", -1, frames, values)
            written += 1
            continue
        for channel in range(3):
            anim.write_keys(socket, "default_value", channel, frames, [v[channel] for v in values])
            written += 1
    return written
