"""Spectral Skin: Donner & Jensen's spectral skin model as a Principled BSDF material (Blender glue only)."""

import bpy

from . import masks, ops, panels, props

classes = (*props.classes, *ops.classes, *masks.classes, *panels.classes)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.spectral_skin = bpy.props.PointerProperty(type=props.SpectralSkinSettings)


def unregister() -> None:
    del bpy.types.Material.spectral_skin
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
