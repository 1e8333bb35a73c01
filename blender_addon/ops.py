"""The operators Apply, Remove and From Albedo Texture: each reads its properties, calls the add-on's one path for
the job (apply.py: Apply's prepare / compute / finish, the batch's path too; albedo.py: From Albedo Texture's) and
reports what it did, or the core's error. Started from the UI, Apply with parameter maps (or in Live mode) and From
Albedo Texture run their computing step in a worker thread while a modal timer shows the progress and Esc cancels
with nothing changed (work.py); the material is edited on Blender's main thread once everything is computed and
written. From a script it runs synchronously, the same steps.
"""

from __future__ import annotations

from typing import Any

import bpy
import spectral_skin

from . import albedo, apply, nodes
from .core import MaterialPlan, SkinSettings, describe_error
from .core import albedo as core_albedo
from .core import scene as analysis
from .props import settings_from_material
from .work import ModalWork, Work

ERRORS = (spectral_skin.SpectralSkinError, ValueError, OSError)


def _find_material(name: str, context: bpy.types.Context) -> bpy.types.Material | None:
    """The material named ``name``, or the context's (the panel's, else the active object's) when empty."""
    if name:
        return bpy.data.materials.get(name)
    material = getattr(context, "material", None)
    if material is None and context.object is not None:
        material = context.object.active_material
    return material


class SPECTRAL_SKIN_OT_apply(ModalWork, bpy.types.Operator):
    """Compute the skin with spectral-skin and set up the material's Principled BSDF (and texture maps)"""

    bl_idname = "spectral_skin.apply"
    bl_label = "Apply Spectral Skin"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material to set up; empty: the active material")

    _material_name = ""

    def _material(self, context: bpy.types.Context) -> bpy.types.Material | None:
        return _find_material(self.material, context)

    def _settings(self, context: bpy.types.Context) -> tuple[bpy.types.Material | None, SkinSettings | None]:
        material = self._material(context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
            return None, None
        try:
            return material, settings_from_material(material, context.scene)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return material, None

    def _done(self, plan: MaterialPlan) -> set[str]:
        summary = plan.summary
        self.report({"INFO"}, f"Spectral Skin: {summary.computed} in {summary.seconds:.2f} s")
        for line in analysis.describe(plan.effects):
            self.report({"INFO"}, f"Spectral Skin: {line}")
        for warning in summary.warnings:
            self.report({"WARNING"}, warning)
        return {"FINISHED"}

    def execute(self, context: bpy.types.Context) -> set[str]:
        material, settings = self._settings(context)
        if material is None or settings is None:
            return {"CANCELLED"}
        try:
            plan = apply.apply_skin(material, settings)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return {"CANCELLED"}
        return self._done(plan)

    def invoke(self, context: bpy.types.Context, _event: bpy.types.Event) -> set[str]:
        material, settings = self._settings(context)
        if material is None or settings is None:
            return {"CANCELLED"}
        if (not settings.maps and settings.mode != "LIVE") or context.window is None:
            return self.execute(context)  # one evaluation: no time to show (Live mode may build its shader table)
        self._material_name = material.name
        return self._start(context, Work(apply.apply_task(apply.prepare(material, settings, context.scene))))

    def _succeed(self, context: bpy.types.Context, result: Any) -> set[str]:
        material = bpy.data.materials.get(self._material_name)
        if material is None:
            self.report({"ERROR"}, f"Spectral Skin: the material {self._material_name!r} is gone")
            return {"CANCELLED"}
        try:
            plan = apply.finish(material, result)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return {"CANCELLED"}
        return self._done(plan)


class SPECTRAL_SKIN_OT_remove(bpy.types.Operator):
    """Delete the nodes Spectral Skin added and link the material's previous shader back to its output"""

    bl_idname = "spectral_skin.remove"
    bl_label = "Remove Spectral Skin"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material; empty: the active material")

    def execute(self, context: bpy.types.Context) -> set[str]:
        material = _find_material(self.material, context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
            return {"CANCELLED"}
        removed = nodes.remove_skin(material)
        material.spectral_skin.has_result = False
        self.report({"INFO"}, f"Spectral Skin: removed {removed} node{'s' if removed != 1 else ''}")
        return {"FINISHED"}


class SPECTRAL_SKIN_OT_from_albedo_texture(ModalWork, bpy.types.Operator):
    """Fit the skin parameters per texel to the material's Base Color image (the core's albedo fit) and set the
    result, a parameter EXR written beside the .blend, as the material's Parameter Map"""

    bl_idname = "spectral_skin.from_albedo_texture"
    bl_label = "From Albedo Texture"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material; empty: the active material")
    auto_gains: bpy.props.BoolProperty(
        name="Correct Exposure and White Balance", default=False,
        description="Estimate the exposure and white-balance gains that bring the most texels inside skin's colours "
                    "(for a photograph) and apply them before the fit")
    hold_thickness: bpy.props.BoolProperty(
        name="Hold Epidermis Thickness", default=False,
        description="Fit at the material's Epidermis Thickness instead of choosing one for the texture (the "
                    "default: the thickness of 0.05 to 0.5 mm that fits the texture best, never worse than 0.25)")

    _writing_state = "writing the parameter map"
    _material_name = ""
    _job: core_albedo.AlbedoJob | None = None

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        if not core_albedo.available():
            cls.poll_message_set(f"From Albedo Texture {core_albedo.UNAVAILABLE}")
            return False
        return True

    def _fail(self, error: BaseException) -> set[str]:
        self.report({"ERROR"}, f"Spectral Skin: From Albedo Texture: {describe_error(error)}")
        return {"CANCELLED"}

    def _material_or_report(self, context: bpy.types.Context) -> bpy.types.Material | None:
        material = _find_material(self.material, context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
        return material

    def execute(self, context: bpy.types.Context) -> set[str]:
        material = self._material_or_report(context)
        if material is None:
            return {"CANCELLED"}
        try:
            summary = albedo.from_albedo_texture(material, self.hold_thickness, self.auto_gains)
        except ERRORS as error:
            return self._fail(error)
        return self._done(material, summary)

    def invoke(self, context: bpy.types.Context, _event: bpy.types.Event) -> set[str]:
        if context.window is None:
            return self.execute(context)
        material = self._material_or_report(context)
        if material is None:
            return {"CANCELLED"}
        try:
            job = albedo.prepare_albedo(material, self.hold_thickness, self.auto_gains)
        except ERRORS as error:
            return self._fail(error)
        self._material_name, self._job = material.name, job
        return self._start(context, Work(albedo.albedo_task(job)))

    def _succeed(self, context: bpy.types.Context, result: Any) -> set[str]:
        material = bpy.data.materials.get(self._material_name)
        if material is None or self._job is None:
            self.report({"ERROR"}, f"Spectral Skin: the material {self._material_name!r} is gone")
            return {"CANCELLED"}
        try:
            summary = albedo.finish_albedo(material, self._job, result)
        except ERRORS as error:
            return self._fail(error)
        return self._done(material, summary)

    def _done(self, material: bpy.types.Material, summary: dict[str, Any]) -> set[str]:
        thickness = summary["extended"]["epidermis_thickness_mm"]
        masked = (f", {summary['masked_out_texels']} outside the skin mask (fitted to their nearest skin colour)"
                  if material.spectral_skin.skin_mask is not None else "")
        self.report({"INFO"}, f"Spectral Skin: fitted {summary['image']!r} ({summary['working_space']}): ΔE00 median "
                    f"{summary['median_delta_e00']:.2f}, max {summary['max_delta_e00']:.2f}, "
                    f"{summary['outside_skin_texels']} texel(s) outside skin's colours{masked}; epidermis thickness "
                    f"{thickness:g} mm ({'held' if summary['thickness'] is None else 'chosen for the texture'}); "
                    f"parameter map {summary['path']} set (Apply to use it); residual ΔE00 in the image "
                    f"{summary['residual']!r}")
        if self.auto_gains and summary["gains"]:
            g = summary["gains"]
            self.report({"INFO"}, "Spectral Skin: exposure and white balance corrected, R G B x "
                        f"{' '.join(f'{v:.3f}' for v in g['rgb_gains'])} ({g['exposure_stops']:+.2f} stops)")
        if summary["diagnosis"]:
            self.report({"WARNING"}, f"Spectral Skin: {summary['diagnosis']}"
                        + ("" if self.auto_gains else " (tick Correct Exposure and White Balance to apply the gains)"))
        return {"FINISHED"}


classes = (SPECTRAL_SKIN_OT_apply, SPECTRAL_SKIN_OT_remove, SPECTRAL_SKIN_OT_from_albedo_texture)
