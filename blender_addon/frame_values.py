"""Per-frame values of an animated constant-parameter material, set by a frame-change handler (bpy only).

Apply stores the plan's ``animation`` (core/scene.py: Base Color, Subsurface Radius × Scale and Specular IOR Level
at every frame of the scene's range, computed by the core) on the material as the custom property
:data:`PROPERTY` (JSON), so it is saved with the .blend. :func:`frame_change` (``bpy.app.handlers.frame_change_pre``,
persistent: it stays through loading other files) sets those values on the add-on's Principled BSDF at each frame
change; a frame outside the range takes the nearest frame's values. No numerics here, and nothing but bpy: the
headless render script (scripts/render_blend.py, outside the extension) loads this file and installs the handler
without the add-on or ``spectral_skin``.
"""

from __future__ import annotations

import json
from typing import Any

import bpy

PROPERTY = "spectral_skin_frames"
TAG = "spectral_skin"  # nodes.TAG: the role of the add-on's nodes
# Plan key -> Principled input.
SOCKETS = {"base_color": "Base Color", "radius": "Subsurface Radius", "specular_ior_level": "Specular IOR Level"}
HANDLER_NAME = "spectral_skin_frame_change"


def store(material: bpy.types.Material, plan: dict[str, Any]) -> None:
    """Keep the plan's per-frame values on the material (or remove stale ones when the plan has none)."""
    animation = plan.get("animation")
    if animation:
        material[PROPERTY] = json.dumps(animation)
    elif PROPERTY in material:
        del material[PROPERTY]


def set_frame(material: bpy.types.Material, frame: int) -> bool:
    """Set the material's stored values of ``frame`` on its Spectral Skin Principled BSDF; False when it has none."""
    text = material.get(PROPERTY)
    tree = material.node_tree
    if not text or tree is None:
        return False
    animation = json.loads(text)
    frames = animation["frames"]
    index = min(max(int(frame) - int(frames[0]), 0), len(frames) - 1)
    changed = False
    for node in tree.nodes:
        if node.get(TAG) != "principled":
            continue
        for key, name in SOCKETS.items():
            value = animation[key][index]
            if value is None:
                continue
            socket = next((s for s in node.inputs if s.name == name), None)
            if socket is not None and not socket.is_linked:
                socket.default_value = [*value, 1.0] if key == "base_color" else value
                changed = True
    return changed


@bpy.app.handlers.persistent
def spectral_skin_frame_change(scene: bpy.types.Scene, _depsgraph: Any = None) -> None:
    """frame_change_pre handler: every material with stored per-frame values gets those of the scene's frame."""
    for material in bpy.data.materials:
        if PROPERTY in material:
            set_frame(material, scene.frame_current)


def install() -> None:
    """Add the handler once (a copy of this module loaded under another name replaces the earlier one)."""
    uninstall()
    bpy.app.handlers.frame_change_pre.append(spectral_skin_frame_change)


def uninstall() -> None:
    handlers = bpy.app.handlers.frame_change_pre
    for handler in [h for h in handlers if getattr(h, "__name__", "") == HANDLER_NAME]:
        handlers.remove(handler)
