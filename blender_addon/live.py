"""The live "Spectral Skin" node group: Principled Base Color, Subsurface Radius and Specular IOR Level computed in the
shader from Melanin, Melanin Blend, Hemoglobin and Oiliness inputs (values, textures, drivers, keyframes), with no
baking.

Inside it there is only coordinate maths and, per output, two Image Texture lookups (Linear, Extend, Non-Color) in the
core's shader table (``spectral_skin.shader_table``; layout and formulas in its docstring and in
src/maps/shader_table.rs): slices over the melanin blend side by side, a grid over the cube-root warped melanin and
haemoglobin in each, ln of the output per texel. The lookups of the two slices around the melanin blend are mixed
linearly and exponentiated: the core's trilinear table lookup, whose error against direct evaluation is in
docs/shader-table.md. The Specular IOR Level is exact: 0.5 * clamp(oiliness, 0, 1).

Not yet wired into the add-on's panel and Apply operator (issue 14, items 2-4): :func:`build_group` is the building
block they will use.
"""

from __future__ import annotations

from typing import Any

import bpy
import numpy as np

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
