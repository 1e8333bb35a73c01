"""Live mode's decisions, without bpy: which shader table a material's target needs, what its plan is computed from,
and which effects the live node group keeps (the bpy glue is blender_addon/live.py).

In Live mode the Principled BSDF's Base Color, Subsurface Radius and surface inputs (Specular IOR Level, Coat Weight,
Coat Roughness) come from the "Spectral Skin" node group, which looks its four inputs up in the core's shader table
(``spectral_skin.shader_table``, docs/shader-table.md) and the surface's inputs up in the core's oiliness nodes in
the shader: parameter maps, painted textures, drivers and keyframes change the skin without another Apply. Apply computes the table for the material's target (Blender version, engine, subsurface method:
chosen as the baked path chooses them) and extended physiology (baked into the table: one value per material) and the
plan of the panel's constants, which gives everything else (Subsurface
Scale, IOR, Roughness, the scene analysis).

Subsurface and specular are kept in Live mode unless forced off: the inputs can change per texel and per frame with no
Apply, so neither the scene analysis's radius bound nor "oiliness zero everywhere" can be decided from the constants.
Animated panel parameters are not evaluated per frame (the per-frame values of the baked path): their keys and
drivers are copied onto the group node's input sockets at Apply (live.carry_animation), which the shader follows.
"""

from __future__ import annotations

import dataclasses
import hashlib
from types import MappingProxyType
from typing import Any

import spectral_skin

from .colour import DEFAULT_WORKING_SPACE
from .material_plan import LivePart, MaterialPlan
from .plan import extended_keywords
from .scene import scene_plan
from .settings import (
    ACCURACY_LEVELS,
    DEFAULT_SURFACE,
    DEFAULT_TRANSPORT,
    EXTENDED_PARAMETERS,
    PARAMETER_INFO,
    TRANSPORTS,
    SkinSettings,
    check,
)
from .targets import method_name


def kept(overrides: dict[str, str] | None, effect: str) -> bool:
    """Whether Live mode keeps ``effect`` ("subsurface" or "specular"): yes unless its override is Off."""
    return (overrides or {}).get(effect, "AUTO") != "OFF"


def table_method(settings: SkinSettings, overrides: dict[str, str] | None) -> str:
    """The core's method name the table is built for: the material's, or Burley (whose Base Color is the albedo) when
    subsurface is off, as the baked path does."""
    return method_name(settings.method if kept(overrides, "subsurface") else "BURLEY")


# Blender before 5.0 cuts ID names at 63 bytes; the group's images add " Base Color" (live.build_group).
MAX_NAME = 63 - len(" Base Color")


def table_name(settings: SkinSettings, overrides: dict[str, str] | None) -> str:
    """The name of the node group (and the prefix of its two images) for the table a material needs: one per table
    key (Blender version, engine, method, accuracy, transport, working space, surface model, the extended physiology it
    is baked with; the default accuracy, transport and surface, Linear Rec.709, the paper's extended values left out), shared by materials that
    need the same: changing an extended value gives another name, so Apply computes that table. A name too long for
    Blender ends in a hash of the whole key."""
    parts = [settings.blender or "current", settings.engine, table_method(settings, overrides)]
    if settings.accuracy != "DEFAULT":
        parts.append(settings.accuracy.lower())
    if settings.transport != DEFAULT_TRANSPORT:
        parts.append(TRANSPORTS[settings.transport])
    if settings.working_space != DEFAULT_WORKING_SPACE:
        parts.append(settings.working_space.removeprefix("Linear "))
    if settings.surface != DEFAULT_SURFACE:  # the group computes the surface's inputs (the layout version changed
        parts.append(settings.surface_name())  # with the default, so an older group of no surface name is rebuilt)
    changed = settings.changed_extended()
    # The parameter's label's first word and its value to 7 significant digits (Blender's float properties hold
    # about 7: two values a slider can tell apart get two names).
    parts += [f"{PARAMETER_INFO[p].label.split()[0].lower()}={changed[p]:.7g}" for p in EXTENDED_PARAMETERS
              if p in changed]
    name = "Spectral Skin " + " ".join(parts)
    if len(name) > MAX_NAME:
        name = f"{name[:MAX_NAME - 7]} {hashlib.sha1(name.encode()).hexdigest()[:6]}"
    return name


def shader_table(settings: SkinSettings, overrides: dict[str, str] | None) -> dict[str, Any]:
    """The core's shader table for the material's target (``spectral_skin.shader_table``, default resolution), baked
    with the settings' extended physiology (one value per material: the group's inputs are the four)."""
    extended = extended_keywords(spectral_skin.shader_table, settings, "extended physiology in Live mode")
    return dict(spectral_skin.shader_table(method=table_method(settings, overrides), blender=settings.blender,
                                           engine=settings.engine, accuracy=ACCURACY_LEVELS[settings.accuracy],
                                           **settings.transport_keywords(),
                                           working_space=settings.working_space, **extended))


def live_part(settings: SkinSettings, overrides: dict[str, str] | None, table_needed: bool) -> LivePart:
    """Live mode's part of a material plan: the node group's name, the shader table (None when ``table_needed`` is
    False: the blend file has it), the parameter maps as the core read them (for the files Blender cannot read), the
    panel's constants, the surface's inputs at the oiliness nodes the group interpolates (built into the group), and
    whether subsurface and specular are kept."""
    return LivePart(
        group=table_name(settings, overrides),
        table=shader_table(settings, overrides) if table_needed else None,
        maps=MappingProxyType(dict(settings.maps)),
        constants=MappingProxyType(settings.constants()),
        surface_nodes=MappingProxyType(dict(spectral_skin.surface_input_nodes(
            settings.surface_name(), blender=settings.blender, engine=settings.engine))),
        subsurface=kept(overrides, "subsurface"),
        specular=kept(overrides, "specular"))


def live_plan(settings: SkinSettings, facts: Any, overrides: dict[str, str] | None, table_needed: bool,
              progress: Any = None) -> MaterialPlan:
    """The plan of a Live material (frozen: :class:`~core.material_plan.MaterialPlan`): the scene plan of the panel's
    constants (no maps, no per-frame values, subsurface and specular kept unless forced off) with its
    :func:`live_part` (``plan.live``)."""
    check(settings)  # with its maps: a varying extended-physiology map has no place in a Live group
    forced = {**(overrides or {}),
              "subsurface": "ON" if kept(overrides, "subsurface") else "OFF",
              "specular": "ON" if kept(overrides, "specular") else "OFF"}
    if facts is not None and getattr(facts, "animation", None) is not None:
        facts = dataclasses.replace(facts, animation=None)
    return scene_plan(settings.replace(maps={}, output_dir=""), facts, forced, progress,
                      live=lambda: live_part(settings, overrides, table_needed))
