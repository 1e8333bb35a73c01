"""The Spectral Skin panel in Material Properties."""

from __future__ import annotations

import bpy

from .core import EXTENDED_PARAMETERS, PARAMETERS
from .masks import mask_nodes
from .props import stored_effects


class SPECTRAL_SKIN_PT_material(bpy.types.Panel):
    bl_label = "Spectral Skin"
    bl_idname = "SPECTRAL_SKIN_PT_material"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return getattr(context, "material", None) is not None

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        layout.use_property_split = True
        material = context.material
        props = material.spectral_skin
        layout.row().prop(props, "mode", expand=True)
        layout.prop(props, "preset")
        for name in PARAMETERS:
            row = layout.row(align=True)
            row.active = getattr(props, f"{name}_map") is None and props.params_map is None
            row.prop(props, name, slider=True)
        if props.mode == "LIVE":
            # live.carry_animation: the slider's own property exists only where the add-on is registered.
            layout.label(text="Keys and drivers on these sliders reach the shader at Apply", icon="INFO")
        # The albedo of the constant values, as the sliders move (props.update_swatch; read-only).
        layout.prop(props, "swatch")
        box = layout.box()
        box.label(text="Parameter Maps (optional)")
        box.template_ID(props, "params_map", open="image.open")
        # Disabled, with the reason as its tooltip, where this spectral_skin has no albedo fit.
        box.operator("spectral_skin.from_albedo_texture", icon="IMAGE_RGB").material = material.name
        box.template_ID(props, "skin_mask", open="image.open")
        for name in PARAMETERS:
            box.template_ID(props, f"{name}_map", open="image.open")
        box.prop(props, "clamp")
        layout.prop(props, "method")
        layout.prop(props, "surface")
        layout.prop(props, "accuracy")
        row = layout.row()
        row.active = props.mode == "BAKED"  # Live mode writes no texture maps
        row.prop(props, "output_dir")
        overrides = layout.box()
        overrides.label(text="Effects (Auto: decided from the scene's cameras and maps)")
        overrides.prop(props, "override_subsurface")
        overrides.prop(props, "override_specular")
        overrides.prop(props, "override_constant_maps")
        if props.mode == "LIVE":
            overrides.label(text="Live: subsurface and specular are kept unless Off", icon="INFO")
        if props.mode == "LIVE":
            self._draw_masks(layout, material)
        row = layout.row(align=True)
        row.operator("spectral_skin.apply", icon="MATERIAL").material = material.name
        row.operator("spectral_skin.remove", icon="X", text="Remove").material = material.name
        if props.has_result:
            result = layout.box()
            result.prop(props, "result_albedo")
            row = result.row()
            row.enabled = False
            row.prop(props, "result_radius_mm")
            result.label(text=f"{props.result_computed} in {props.result_seconds:.2f} s")
            if props.result_warning:
                result.label(text=props.result_warning, icon="ERROR")
            for effect in stored_effects(material):
                icon = "CHECKBOX_HLT" if effect["enabled"] else "CHECKBOX_DEHLT"
                result.label(text=f"{effect['effect']}: {effect['reason']}", icon=icon)

    @staticmethod
    def _draw_masks(layout: bpy.types.UILayout, material: bpy.types.Material) -> None:
        """Live mode: the mask operators and each mask's Strength (keyable here: hover, I)."""
        box = layout.box()
        box.label(text="Masks (Live: paint white where the parameter changes)")
        row = box.row(align=True)
        row.operator("spectral_skin.add_blush_mask", icon="BRUSH_DATA").material = material.name
        row.operator("spectral_skin.add_tan_mask", icon="BRUSH_DATA").material = material.name
        if material.node_tree is None:
            return
        for node in mask_nodes(material.node_tree):
            box.prop(node.inputs["Strength"], "default_value", text=f"{node.label} Strength")


class SPECTRAL_SKIN_PT_advanced(bpy.types.Panel):
    """The extended physiology (core.EXTENDED_PARAMETERS: sliders from the core's table) and the transport (the
    core's transports), closed by default: the paper's values and the core's default unless changed; one value per
    material."""

    bl_label = "Advanced"
    bl_idname = "SPECTRAL_SKIN_PT_advanced"
    bl_parent_id = "SPECTRAL_SKIN_PT_material"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        return getattr(context, "material", None) is not None

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        layout.use_property_split = True
        props = context.material.spectral_skin
        layout.prop(props, "transport")
        for name in EXTENDED_PARAMETERS:
            layout.prop(props, name, slider=True)
        layout.label(text="Extended physiology: the defaults are the paper's model", icon="INFO")


classes = (SPECTRAL_SKIN_PT_material, SPECTRAL_SKIN_PT_advanced)
