"""Live mode's masks (bpy glue; what a mask computes, its ranges and names: core/masks.py).

"Add Blush/Flush Mask" and "Add Tan/Vitiligo Mask" put a mask node (the group "Spectral Skin Mask <parameter>":
clamp(Value + Mask x Strength, the parameter's range)) in front of the live "Spectral Skin" group's Hemoglobin or
Melanin input, fed by a new blank mask: an image (black, Non-Color, packed into the .blend, sized like the material's
parameter maps or 1024 x 1024) or a colour attribute (float, per face corner) on the meshes that use the material.
Paint it white where the parameter should change; the mask node's Strength socket (also shown in the panel) can be
keyed or driven. Masks on one input form a chain; Apply sets the panel's constant or the parameter map at the chain's
head (live.wire).
"""

from __future__ import annotations

from typing import Any

import bpy
import numpy as np

from . import live, nodes
from .core import NON_COLOR, PARAMETERS
from .core.masks import (
    MASK_KINDS,
    check_mask,
    default_strength,
    group_name,
    mask_name,
    mask_size,
    parameter_range,
    strength_range,
)

__all__ = ["add_mask", "build_mask_group", "mask_nodes"]

MASK_ROLE = "live {parameter} mask"


def build_mask_group(parameter: str) -> Any:
    """The node group of ``parameter``'s masks (created, or rebuilt in place): inputs Value, Mask, Strength; output
    Value = clamp(Value + Mask x Strength) into the parameter's range from the core's parameter table."""
    low, high = parameter_range(parameter)
    name = group_name(parameter)
    group = bpy.data.node_groups.get(name) or bpy.data.node_groups.new(name, "ShaderNodeTree")
    group.nodes.clear()
    group.interface.clear()
    for socket in ("Value", "Mask", "Strength"):
        group.interface.new_socket(name=socket, in_out="INPUT", socket_type="NodeSocketFloat")
    group.interface.new_socket(name="Value", in_out="OUTPUT", socket_type="NodeSocketFloat")
    group_in = group.nodes.new("NodeGroupInput")
    group_out = group.nodes.new("NodeGroupOutput")
    add = group.nodes.new("ShaderNodeMath")
    add.operation = "MULTIPLY_ADD"  # Mask x Strength + Value
    group.links.new(group_in.outputs["Mask"], add.inputs[0])
    group.links.new(group_in.outputs["Strength"], add.inputs[1])
    group.links.new(group_in.outputs["Value"], add.inputs[2])
    clamp = group.nodes.new("ShaderNodeClamp")
    clamp.clamp_type = "MINMAX"
    clamp.inputs["Min"].default_value = low
    clamp.inputs["Max"].default_value = high
    group.links.new(add.outputs[0], clamp.inputs["Value"])
    group.links.new(clamp.outputs["Result"], group_out.inputs["Value"])
    return group


def mask_nodes(tree: Any, parameter: str | None = None) -> list[Any]:
    """The mask nodes of a material's tree (of one parameter, or all)."""
    names = PARAMETERS if parameter is None else (parameter,)
    return [n for p in names for n in nodes.tagged_nodes(tree, MASK_ROLE.format(parameter=p))]


def _map_sizes(material: Any) -> list[tuple[int, int]]:
    props = material.spectral_skin
    images = [props.params_map, *(getattr(props, f"{p}_map") for p in PARAMETERS)]
    return [(int(i.size[0]), int(i.size[1])) for i in images if i is not None]


def _mask_image(material: Any, kind: str) -> Any:
    """A new black 8-bit image, Non-Color, packed into the .blend."""
    width, height = mask_size(_map_sizes(material))
    name = mask_name(material.name, kind, (i.name for i in bpy.data.images))
    image = bpy.data.images.new(name, width=width, height=height, alpha=False, float_buffer=False)
    image.colorspace_settings.name = NON_COLOR
    black = np.zeros((height, width, 4), dtype=np.float32)
    black[..., 3] = 1.0
    image.pixels.foreach_set(black.ravel())  # pixels of its own: Blender packs a generated image only once changed
    image.update()
    image.pack()  # after painting, pack again (Image > Pack, or the save prompt for modified images)
    return image


def _mask_attribute(material: Any, kind: str, objects: list[Any]) -> str:
    """A new float colour attribute (per face corner, black) on each mesh among ``objects`` that uses the material;
    its name. ValueError when there is no such mesh."""
    meshes = {o.data for o in objects if o.type == "MESH" and material.name in o.data.materials}
    if not meshes:
        raise ValueError(f"no mesh uses the material {material.name!r}: a colour attribute mask needs one "
                         "(or choose an image mask)")
    name = mask_name(material.name, kind, (a.name for m in meshes for a in m.color_attributes))
    for mesh in meshes:
        attribute = mesh.color_attributes.new(name, "FLOAT_COLOR", "CORNER")
        black = np.zeros((len(attribute.data), 4), dtype=np.float32)
        black[:, 3] = 1.0
        attribute.data.foreach_set("color", black.ravel())  # not always zero when new
    return name


def add_mask(material: Any, kind: str, source: str = "IMAGE", strength: float | None = None,
             objects: list[Any] | None = None) -> Any:
    """Add a mask of ``kind`` ("BLUSH", "TAN") fed by a new blank ``source`` ("IMAGE" or "ATTRIBUTE") in front of
    the live group's input. Returns the mask node (its Strength socket: keyable). ValueError when the material is not
    applied in Live mode; SpectralSkinError for a strength out of range."""
    strength = default_strength(kind) if strength is None else float(strength)
    check_mask(kind, source, strength)
    tree = material.node_tree
    found = nodes.tagged_nodes(tree, "live") if tree is not None else []
    if not found:
        raise ValueError(f"the material {material.name!r} has no live Spectral Skin node group: apply it in Live "
                         "mode first")
    group_node = found[0]
    parameter = MASK_KINDS[kind].parameter
    # The mask's data first: an error there leaves the material as it was.
    image, attribute = None, ""
    if source == "IMAGE":
        image = _mask_image(material, kind)
    else:
        attribute = _mask_attribute(material, kind, list(objects if objects is not None else bpy.context.scene.objects))
    socket = group_node.inputs[live.INPUTS[PARAMETERS.index(parameter)]]
    chain = mask_nodes(tree, parameter)
    mask = tree.nodes.new("ShaderNodeGroup")
    mask.node_tree = build_mask_group(parameter)
    nodes._tag(mask, MASK_ROLE.format(parameter=parameter))
    mask.label = f"{MASK_KINDS[kind].label} Mask"
    x, y = group_node.location.x - 200, group_node.location.y - 260 * PARAMETERS.index(parameter)
    mask.location = (x, y - 140 * len(chain))
    # Insert between the socket and what fed it (or take over its constant).
    if socket.is_linked:
        tree.links.new(socket.links[0].from_socket, mask.inputs["Value"])
    else:
        mask.inputs["Value"].default_value = socket.default_value
    tree.links.new(mask.outputs["Value"], socket)
    mask.inputs["Strength"].default_value = strength
    if source == "IMAGE":
        reader = tree.nodes.new("ShaderNodeTexImage")
        reader.image = image
        reader.interpolation = "Linear"
        reader.extension = "EXTEND"
    else:
        reader = tree.nodes.new("ShaderNodeVertexColor")
        reader.layer_name = attribute
    colour = reader.outputs["Color"]
    nodes._tag(reader, f"live {parameter} mask source")
    reader.location = (x - 500, mask.location.y - 120)
    channel = tree.nodes.new("ShaderNodeSeparateColor")
    nodes._tag(channel, f"live {parameter} mask channel")
    channel.location = (x - 220, mask.location.y - 120)
    tree.links.new(colour, channel.inputs["Color"])
    tree.links.new(channel.outputs[0], mask.inputs["Mask"])  # the first channel, as parameter maps are read
    return mask


def keyed_input(mask: Any) -> str | None:
    """The name of the group input a new mask took over if that input is keyed or driven (its animation no longer
    applies once the mask feeds it: key the mask's Value input instead); else None."""
    tree = mask.id_data
    socket = mask.outputs["Value"].links[0].to_socket
    animation = tree.animation_data
    if animation is None:
        return None
    path = socket.path_from_id("default_value")
    curves = list(animation.drivers)
    action = animation.action
    if action is not None:
        if hasattr(action, "layers"):  # Blender 4.4+: layered actions (the only kind from 5.0)
            curves += [c for layer in action.layers for strip in layer.strips
                       for bag in getattr(strip, "channelbags", ()) for c in bag.fcurves]
        if hasattr(action, "fcurves"):  # Blender before 5.0
            curves += list(action.fcurves)
    return str(socket.name) if any(c.data_path == path for c in curves) else None


def _live_material(context: Any, name: str) -> Any:
    material = bpy.data.materials.get(name) if name else getattr(context, "material", None)
    return material


class _AddMask:
    """Shared body of the two mask operators (their ``kind`` differs)."""

    kind = "BLUSH"
    bl_options = {"REGISTER", "UNDO"}

    def invoke(self, context: Any, _event: Any) -> set[str]:
        """From the panel: a dialog to pick the mask's source and Strength first."""
        return context.window_manager.invoke_props_dialog(self)  # type: ignore[no-any-return]

    def execute(self, context: Any) -> set[str]:
        material = _live_material(context, self.material)  # type: ignore[attr-defined]
        if material is None:
            self.report({"ERROR"}, "no material")  # type: ignore[attr-defined]
            return {"CANCELLED"}
        strength = self.strength if self.properties.is_property_set("strength") else None  # type: ignore[attr-defined]
        try:
            mask = add_mask(material, self.kind, self.source, strength)  # type: ignore[attr-defined]
        except (ValueError, OSError, RuntimeError) as error:
            self.report({"ERROR"}, f"Spectral Skin: {error}")  # type: ignore[attr-defined]
            return {"CANCELLED"}
        self.report({"INFO"}, f"Spectral Skin: added {mask.label} (Strength "  # type: ignore[attr-defined]
                    f"{mask.inputs['Strength'].default_value:g}): paint it white where it applies")
        keyed = keyed_input(mask)
        if keyed is not None:
            self.report({"WARNING"}, f"Spectral Skin: the group's {keyed} input is keyed or driven; "  # type: ignore[attr-defined]
                        "with the mask in front of it, key or drive the mask's Value input instead")
        return {"FINISHED"}


def _properties(kind: str) -> dict[str, Any]:
    low, high = strength_range(kind)
    info = MASK_KINDS[kind]
    return {
        "material": bpy.props.StringProperty(name="Material", description="Material; empty: the active material"),
        "source": bpy.props.EnumProperty(
            name="Mask", description="What the mask is painted in",
            items=[("IMAGE", "Image", "A new black image (packed), painted in Texture Paint"),
                   ("ATTRIBUTE", "Color Attribute", "A new colour attribute on the meshes using the material, "
                    "painted in Vertex Paint")], default="IMAGE"),
        "strength": bpy.props.FloatProperty(
            name="Strength", description=f"{info.parameter} added where the mask is white (negative: removed); "
            f"keyable and drivable on the mask node", min=low, max=high, default=default_strength(kind)),
    }


class SPECTRAL_SKIN_OT_add_blush_mask(_AddMask, bpy.types.Operator):
    """Add a blush/flush mask: a blank image or colour attribute that adds haemoglobin where painted"""

    bl_idname = "spectral_skin.add_blush_mask"
    bl_label = "Add Blush/Flush Mask"
    kind = "BLUSH"
    __annotations__ = _properties("BLUSH")


class SPECTRAL_SKIN_OT_add_tan_mask(_AddMask, bpy.types.Operator):
    """Add a tan/vitiligo mask: a blank image or colour attribute that adds (or, with a negative strength, removes)
    melanin where painted"""

    bl_idname = "spectral_skin.add_tan_mask"
    bl_label = "Add Tan/Vitiligo Mask"
    kind = "TAN"
    __annotations__ = _properties("TAN")


classes = (SPECTRAL_SKIN_OT_add_blush_mask, SPECTRAL_SKIN_OT_add_tan_mask)
