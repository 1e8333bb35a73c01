"""The Blender target of a scene: which row of the core's table (``spectral_skin.blender_targets()``) a Blender version
uses, which engine name a ``scene.render.engine`` id is, and which subsurface methods the version offers. The table
lives in the core; nothing of it is copied here. No bpy.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import spectral_skin


@functools.cache
def table() -> dict[str, Any]:
    """The core's target table (see ``spectral_skin.blender_targets``)."""
    return spectral_skin.blender_targets()


def _key(version: str) -> tuple[int, ...]:
    return tuple(int(part) for part in version.split("."))


def version_text(version: Sequence[int]) -> str:
    """``bpy.app.version`` (5, 0, 1) -> "5.0", the spelling of the table and of ``evaluate(blender=...)``."""
    return f"{int(version[0])}.{int(version[1])}"


def row(version: Sequence[int]) -> dict[str, Any]:
    """The table's row for a Blender version: the newest at or below it. SpectralSkinError (naming the supported
    range) for a version older than the oldest supported."""
    wanted = (int(version[0]), int(version[1]))
    rows = [r for r in table()["versions"] if _key(r["version"]) <= wanted]
    if not rows:
        raise spectral_skin.SpectralSkinError(
            f"Blender {version_text(version)} is not supported: Spectral Skin needs Blender "
            f"{table()['oldest_supported']} or newer (tested: {', '.join(table()['tested_versions'])})")
    return rows[-1]


def engine_name(version: Sequence[int], engine_id: str) -> str | None:
    """The core's engine name ("cycles", "eevee") of a ``scene.render.engine`` id in this Blender; None for an engine
    the table does not know (Workbench, add-on engines)."""
    for name, blender_id in row(version)["engine_ids"].items():
        if blender_id == engine_id:
            return str(name)
    return None


def methods(version: Sequence[int]) -> list[dict[str, Any]]:
    """The subsurface methods this Blender offers, in its menu order: {"name", "blender_id", "tested", ...}."""
    return list(row(version)["methods"])


def method_name(blender_id: str) -> str:
    """The core's method name of a Principled ``subsurface_method`` id; SpectralSkinError for an unknown one."""
    known = {m["blender_id"]: m["name"] for m in table()["methods"]}
    if blender_id not in known:
        raise spectral_skin.SpectralSkinError(
            f"subsurface method must be one of {', '.join(known)}; got {blender_id!r}")
    return str(known[blender_id])
