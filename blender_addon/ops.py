"""The Apply operator: compute the material plan with the core, write its maps, then edit the material."""

from __future__ import annotations

import bpy
import spectral_skin

from . import nodes, props
from .core import SkinSettings, make_plan, write_textures
from .nodes import scene_working_space


def apply_skin(material: bpy.types.Material, settings: SkinSettings) -> dict:
    """Compute everything, write the maps, and only then edit ``material``; returns the plan.

    Raises spectral_skin.SpectralSkinError / ValueError for bad settings and OSError when a map cannot be written;
    the material and existing files are then unchanged. The plan is computed in the scene's working space
    (:func:`scene_working_space`), whatever ``settings.working_space`` says.
    """
    plan = make_plan(settings.replace(working_space=scene_working_space()))
    write_textures(plan)
    nodes.apply_plan(material, plan)
    props.store_result(material, plan)
    return plan


class SPECTRAL_SKIN_OT_apply(bpy.types.Operator):
    """Compute the skin with spectral-skin and set up the material's Principled BSDF (and texture maps)"""

    bl_idname = "spectral_skin.apply"
    bl_label = "Apply Spectral Skin"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material to set up; empty: the active material")

    def _material(self, context: bpy.types.Context) -> bpy.types.Material | None:
        if self.material:
            return bpy.data.materials.get(self.material)
        material = getattr(context, "material", None)
        if material is None and context.object is not None:
            material = context.object.active_material
        return material

    def execute(self, context: bpy.types.Context) -> set[str]:
        material = self._material(context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
            return {"CANCELLED"}
        try:
            settings = props.settings_from_material(material, context.scene)
            plan = apply_skin(material, settings)
        except (spectral_skin.SpectralSkinError, ValueError, OSError) as error:
            self.report({"ERROR"}, f"Spectral Skin: {error}")
            return {"CANCELLED"}
        summary = plan["summary"]
        self.report({"INFO"}, f"Spectral Skin: {summary['computed']} in {summary['seconds']:.2f} s")
        for warning in summary["warnings"]:
            self.report({"WARNING"}, warning)
        return {"FINISHED"}


classes = (SPECTRAL_SKIN_OT_apply,)
