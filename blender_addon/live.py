"""The live "Spectral Skin" node group: Principled Base Color, Subsurface Radius and Specular IOR Level computed in the
shader from Melanin, Melanin Blend, Hemoglobin and Oiliness inputs (values, textures, drivers, keyframes), with no
baking.

Inside it there is only coordinate maths and, per output, two Image Texture lookups (Linear, Extend, Non-Color) in the
core's shader table (``spectral_skin.shader_table``; layout and formulas in its docstring and in
src/maps/shader_table.rs): slices over the melanin blend side by side, a grid over the cube-root warped melanin and
haemoglobin in each, ln of the output per texel. The lookups of the two slices around the melanin blend are mixed
linearly and exponentiated: the core's trilinear table lookup, whose error against direct evaluation is in
docs/shader-table.md. The Specular IOR Level is exact: 0.5 * clamp(oiliness, 0, 1).

Apply in Live mode (core/live.py decides, :func:`wire` edits the material) puts the group node (tagged, as the
add-on's other nodes: nodes.py) between the four inputs and the tagged Principled BSDF. Its inputs get the panel's
constants, or an Image Texture of the parameter's map: the image itself where Blender reads it as the core does
(PNG/TIFF files, painted or generated images; 8/16-bit values scaled onto the parameter's range by a Math node), else
a float copy of the core's reading packed into the .blend (EXR files: Blender reads an EXR channel named ``melanin``
as zeros). Anything else can drive the inputs: colour attributes, drivers and keyframes on the group node's sockets.
Masks (masks.py) sit between an input and what feeds it; Apply then sets the constant or map at the head of their
chain (:func:`chain_head`).
"""

from __future__ import annotations

import os
from typing import Any

import bpy
import numpy as np

from . import nodes
from .core import PARAMETER_INFO, PARAMETERS

GROUP_NAME = "Spectral Skin"
INPUTS = ("Melanin", "Melanin Blend", "Hemoglobin", "Oiliness")
OUTPUTS = (
    ("Base Color", "NodeSocketColor"),
    ("Subsurface Radius", "NodeSocketVector"),
    ("Specular IOR Level", "NodeSocketFloat"),
)


def table_image(name: str, log_rgb: np.ndarray) -> Any:
    """A float image (Non-Color) holding an (H, W, 3) array whose row 0 is the top, as the shader table returns it
    (Blender's pixels start at the bottom row)."""
    h, w, _ = log_rgb.shape
    image = bpy.data.images.get(name)
    if image is not None and tuple(image.size) != (w, h):
        bpy.data.images.remove(image)
        image = None
    if image is None:
        image = bpy.data.images.new(name, width=w, height=h, alpha=False, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = log_rgb[::-1]
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image


def build_group(table: dict[str, Any], name: str = GROUP_NAME) -> Any:
    """The node group for a ``spectral_skin.shader_table`` result (created, or rebuilt in place if it exists).
    Its images are named ``<name> Base Color`` and ``<name> Radius``."""
    meta = table["metadata"]
    n_m, n_b, n_h = (int(meta[a]["nodes"]) for a in ("melanin", "melanin_blend", "hemoglobin"))
    width, slice_width, gutter = int(meta["width"]), int(meta["slice_width"]), int(meta["gutter"])
    images = {
        "base_color_log": table_image(f"{name} Base Color", table["base_color_log"]),
        "radius_log": table_image(f"{name} Radius", table["radius_log"]),
    }
    group = bpy.data.node_groups.get(name) or bpy.data.node_groups.new(name, "ShaderNodeTree")
    group.nodes.clear()
    group.interface.clear()
    for socket in INPUTS:
        group.interface.new_socket(name=socket, in_out="INPUT", socket_type="NodeSocketFloat")
    for socket, socket_type in OUTPUTS:
        group.interface.new_socket(name=socket, in_out="OUTPUT", socket_type=socket_type)
    nodes, links = group.nodes, group.links
    group_in = nodes.new("NodeGroupInput")
    group_out = nodes.new("NodeGroupOutput")

    def math(operation: str, a: Any, b: Any = None, c: Any = None, clamp: bool = False) -> Any:
        node = nodes.new("ShaderNodeMath")
        node.operation = operation
        node.use_clamp = clamp
        for i, value in enumerate((a, b, c)):
            if value is None:
                continue
            if isinstance(value, (int, float)):
                node.inputs[i].default_value = float(value)
            else:
                links.new(value, node.inputs[i])
        return node.outputs[0]

    def unit(socket: str, scale: float) -> Any:
        """clamp(value / scale, 0, 1)."""
        return math("DIVIDE", group_in.outputs[socket], scale, clamp=True)

    # Warped coordinates (cube roots of the concentrations over their ranges' maxima; 0.5 and 0.1 from the metadata).
    u_m = math("POWER", unit("Melanin", float(meta["melanin"]["max"])), 1.0 / 3.0)
    u_h = math("POWER", unit("Hemoglobin", float(meta["hemoglobin"]["max"])), 1.0 / 3.0)
    b = math("MULTIPLY", unit("Melanin Blend", float(meta["melanin_blend"]["max"])), float(n_b - 1))
    j = math("MINIMUM", math("FLOOR", b), float(n_b - 2))
    t = math("SUBTRACT", b, j)
    # x(j) = (j * slice_width + gutter + u_m (n_m - 1) + 0.5) / width;  y = (u_h (n_h - 1) + 0.5) / n_h.
    in_slice = math("MULTIPLY_ADD", u_m, float(n_m - 1), float(gutter) + 0.5)
    x0 = math("DIVIDE", math("MULTIPLY_ADD", j, float(slice_width), in_slice), float(width))
    x1 = math("ADD", x0, slice_width / width)
    y = math("DIVIDE", math("MULTIPLY_ADD", u_h, float(n_h - 1), 0.5), float(n_h))
    coords = []
    for x in (x0, x1):
        combine = nodes.new("ShaderNodeCombineXYZ")
        links.new(x, combine.inputs["X"])
        links.new(y, combine.inputs["Y"])
        coords.append(combine.outputs["Vector"])
    for key, output in (("base_color_log", "Base Color"), ("radius_log", "Subsurface Radius")):
        mix = nodes.new("ShaderNodeMix")
        mix.data_type = "VECTOR"
        mix.clamp_factor = False
        links.new(t, mix.inputs["Factor"])
        for coord, socket in zip(coords, ("A", "B"), strict=True):
            tex = nodes.new("ShaderNodeTexImage")
            tex.image = images[key]
            tex.interpolation = "Linear"
            tex.extension = "EXTEND"
            links.new(coord, tex.inputs["Vector"])
            # The Mix node's vector sockets share names with its float and colour ones: pick the visible vector one.
            target = next(s for s in mix.inputs if s.name == socket and s.type == "VECTOR")
            links.new(tex.outputs["Color"], target)
        separate = nodes.new("ShaderNodeSeparateXYZ")
        mix_out = next(s for s in mix.outputs if s.type == "VECTOR")
        links.new(mix_out, separate.inputs["Vector"])
        combine = nodes.new("ShaderNodeCombineXYZ")
        for axis in "XYZ":
            links.new(math("EXPONENT", separate.outputs[axis]), combine.inputs[axis])
        links.new(combine.outputs["Vector"], group_out.inputs[output])
    # Specular IOR Level = 0.5 * clamp(oiliness, 0, 1) (fit::principled_specular::specular_from_oiliness).
    oiliness = math("MULTIPLY", group_in.outputs["Oiliness"], 1.0, clamp=True)
    links.new(math("MULTIPLY", oiliness, 0.5), group_out.inputs["Specular IOR Level"])
    return group


def has_group(name: str) -> bool:
    """Whether the blend file has the node group ``name`` and both its table images, packed (then Apply reuses
    them)."""
    group = bpy.data.node_groups.get(name)
    images = [bpy.data.images.get(f"{name} {kind}") for kind in ("Base Color", "Radius")]
    return group is not None and all(i is not None and i.packed_file is not None for i in images)


def _packed(image: Any) -> Any:
    """Pack a generated float image into the .blend (so nothing depends on a temporary file)."""
    image.pack()
    image.colorspace_settings.name = "Non-Color"
    return image


def _non_color(image: Any) -> None:
    """Tag a parameter image Non-Color (raw values), keeping the pixels of one Blender holds only in memory
    (generated, or painted and not saved), which a colour space change would regenerate or reload."""
    if image.colorspace_settings.name == "Non-Color":
        return
    keep = None
    if image.source == "GENERATED" or image.is_dirty:
        keep = np.empty(len(image.pixels), dtype=np.float32)
        image.pixels.foreach_get(keep)
    image.colorspace_settings.name = "Non-Color"
    if keep is not None:
        image.pixels.foreach_set(keep)
        image.update()


def _roles(param: str) -> tuple[str, str, str]:
    return f"live {param}", f"live {param} channel", f"live {param} range"


def remove_nodes(tree: Any) -> None:
    """Delete the live nodes (group node, parameter textures) from a material's tree: Apply in Baked mode."""
    for node in nodes.tagged_nodes(tree):
        if str(node[nodes.TAG]).startswith("live"):
            tree.nodes.remove(node)


def _direct(image: Any) -> bool | None:
    """How the group reads a parameter image itself: None when it cannot (an EXR file: Blender does not read it as
    the core does), else whether its values are normalized (8/16-bit: 0..1 onto the parameter's range), as the baked
    path reads it (props._image_parameter_maps)."""
    if image.source == "GENERATED" or image.is_dirty:
        return not image.is_float
    if image.source == "FILE" and os.path.splitext(image.filepath)[1].lower() != ".exr":
        return True
    return None


def _parameter_image(material: Any, param: str, maps: dict[str, Any]) -> tuple[Any, bool] | None:
    """The image a parameter's input reads and whether its values are normalized; None for the constant. The
    material's own image where Blender reads it as the core does, else (an EXR file, or maps a batch script gave) a
    packed float copy of the core's reading ``maps[param]``."""
    own = getattr(material.spectral_skin, f"{param}_map")
    if own is not None:
        normalized = _direct(own)
        if normalized is not None:
            return own, normalized
    pmap = maps.get(param)
    if pmap is None:
        return None
    pixels = np.asarray(pmap.pixels, dtype=np.float32)
    copy = table_image(f"SpectralSkin {material.name} {param}", np.repeat(pixels[:, :, None], 3, axis=2))
    return _packed(copy), bool(pmap.normalized)


def chain_head(socket: Any) -> Any:
    """The socket that takes a group input's constant or parameter map: the input itself, or, when masks
    (masks.py) feed it, the Value input of the first mask of their chain."""
    while socket.is_linked:
        node = socket.links[0].from_node
        if not str(node.get(nodes.TAG, "")).endswith(" mask"):
            break
        socket = node.inputs["Value"]
    return socket


def wire(material: Any, plan: dict[str, Any]) -> Any:
    """Live mode's last step (main thread): the group (built from ``plan["live"]["table"]``, its images packed, or
    the blend file's), its node wired into the tagged Principled BSDF, its inputs set (see the module's docstring).
    Returns the group node."""
    info = plan["live"]
    tree = material.node_tree
    principled = nodes.tagged_nodes(tree, "principled")[0]
    name = info["group"]
    if info["table"] is not None:
        group = build_group(info["table"], name)
        for kind in ("Base Color", "Radius"):
            _packed(bpy.data.images[f"{name} {kind}"])
    elif has_group(name):
        group = bpy.data.node_groups[name]
    else:
        raise ValueError(f"the node group {name!r} is gone from the blend file: apply again")
    found = nodes.tagged_nodes(tree, "live")
    node = found[0] if found else tree.nodes.new("ShaderNodeGroup")
    if not found:
        nodes._tag(node, "live")
        node.location = (principled.location.x - 260, principled.location.y)
    node.node_tree = group
    node.width = 200
    for index, (param, socket_name) in enumerate(zip(PARAMETERS, INPUTS, strict=True)):
        node.inputs[socket_name].default_value = float(info["constants"][param])
        for role in _roles(param):
            for stale in nodes.tagged_nodes(tree, role):
                tree.nodes.remove(stale)
        socket = chain_head(node.inputs[socket_name])
        socket.default_value = float(info["constants"][param])
        source = _parameter_image(material, param, info["maps"])
        if source is None:
            continue
        image, normalized = source
        _non_color(image)
        role, channel_role, range_role = _roles(param)
        y = node.location.y - 260 * index
        tex = tree.nodes.new("ShaderNodeTexImage")
        nodes._tag(tex, role)
        tex.image = image
        tex.interpolation = "Linear"
        tex.extension = "EXTEND"
        tex.location = (node.location.x - 620, y)
        channel = tree.nodes.new("ShaderNodeSeparateColor")
        nodes._tag(channel, channel_role)
        channel.location = (node.location.x - 340, y)
        tree.links.new(tex.outputs["Color"], channel.inputs["Color"])
        value = channel.outputs[0]  # the first channel, as the baked path reads it
        if normalized:
            low, high = PARAMETER_INFO[param][:2]
            scale = tree.nodes.new("ShaderNodeMath")
            nodes._tag(scale, range_role)
            scale.operation = "MULTIPLY_ADD"
            scale.inputs[1].default_value = high - low
            scale.inputs[2].default_value = low
            scale.location = (node.location.x - 180, y)
            tree.links.new(value, scale.inputs[0])
            value = scale.outputs[0]
        tree.links.new(value, socket)
    outputs = [("Base Color", True), ("Subsurface Radius", info["subsurface"]),
               ("Specular IOR Level", info["specular"])]
    for output, used in outputs:
        target = nodes._socket(principled.inputs, output)
        if used:
            tree.links.new(node.outputs[output], target)
    return node
