"""The live "Spectral Skin" node group: Principled Base Color, Subsurface Radius, Specular IOR Level, Coat Weight and
Coat Roughness computed in the shader from Melanin, Melanin Blend, Hemoglobin and Oiliness inputs (values, textures, drivers, keyframes), with no
baking.

Inside it there is only coordinate maths and, per output, two Image Texture lookups (Linear, Extend, Non-Color; for
EEVEE, whose GPU filtering is not exact, four Closest lookups per slice with the bilinear weights computed here) in the
core's shader table (``spectral_skin.shader_table``; layout and formulas in its docstring and in
src/maps/shader_table.rs): slices over the melanin blend side by side, a grid over the cube-root warped melanin and
haemoglobin in each, ln of the output per texel. The lookups of the two slices around the melanin blend are mixed
linearly and exponentiated: the core's trilinear table lookup, whose error against direct evaluation is in
docs/shader-table.md. The surface's inputs are the core's, linear in the oiliness between its nodes
(``spectral_skin.surface_input_nodes``: exact for the level and the Coat Weight, the Coat Roughness within 6e-5; for
the paper's surface 0.5 * clamp(oiliness, 0, 1) and no Coat).

Apply in Live mode (core/live.py decides, :func:`wire` edits the material) puts the group node (tagged, as the
add-on's other nodes: nodes.py) between the four inputs and the tagged Principled BSDF. Its inputs get the panel's
constants, or an Image Texture of the parameter's map: the image itself where Blender reads it as the core does
(PNG/TIFF files, painted or generated images; 8/16-bit values scaled onto the parameter's range by a Math node), else
a float copy of the core's reading packed into the .blend (EXR files: Blender reads an EXR channel named ``melanin``
as zeros). Anything else can drive the inputs: colour attributes, drivers and keyframes on the group node's sockets.
Keys and a driver on a panel slider are copied onto the input at Apply (:func:`carry_animation`): the slider's own
property exists only where the add-on is registered, the socket's animation renders anywhere.
Masks (masks.py) sit between an input and what feeds it; Apply then sets the constant or map at the head of their
chain (:func:`chain_head`).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from typing import Any

import bpy
import numpy as np

from . import anim, nodes
from .core import NON_COLOR, PARAMETER_INFO, PARAMETERS, MaterialPlan
from .core.maps import map_kinds, split_tiles

GROUP_NAME = "Spectral Skin"
# The group's layout version, stored on the group: a group of another version (such as an EEVEE group from before
# the group computed its own bilinear weights) is rebuilt at the next Apply, not reused.
LAYOUT_KEY, LAYOUT_VERSION = "spectral_skin_layout", 3
INPUTS = ("Melanin", "Melanin Blend", "Hemoglobin", "Oiliness")
OUTPUTS = (
    ("Base Color", "NodeSocketColor"),
    ("Subsurface Radius", "NodeSocketVector"),
    ("Specular IOR Level", "NodeSocketFloat"),
    ("Coat Weight", "NodeSocketFloat"),
    ("Coat Roughness", "NodeSocketFloat"),
)
# Group output -> the key of its values in ``spectral_skin.surface_input_nodes``: the surface's single-channel map
# kinds (core/maps.py), by the Principled input each feeds.
SURFACE_OUTPUTS = {kind.principled_input: kind.field for kind in map_kinds() if kind.scalar}


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
    image.colorspace_settings.name = NON_COLOR
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[:, :, :3] = log_rgb[::-1]
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image


class _Nodes:
    """Node-making helpers over one group's nodes and links (and its table images, by key)."""

    def __init__(self, group: Any, images: dict[str, Any]) -> None:
        self.nodes, self.links, self.images = group.nodes, group.links, images

    def math(self, operation: str, a: Any, b: Any = None, c: Any = None, clamp: bool = False) -> Any:
        node = self.nodes.new("ShaderNodeMath")
        node.operation = operation
        node.use_clamp = clamp
        for i, value in enumerate((a, b, c)):
            if value is None:
                continue
            if isinstance(value, (int, float)):
                node.inputs[i].default_value = float(value)
            else:
                self.links.new(value, node.inputs[i])
        return node.outputs[0]

    def vector_mix(self, factor: Any, a: Any, b: Any) -> Any:
        """(1 - factor) a + factor b of two vectors (the Mix node's visible vector sockets: they share names with
        its float and colour ones)."""
        mix = self.nodes.new("ShaderNodeMix")
        mix.data_type = "VECTOR"
        mix.clamp_factor = False
        self.links.new(factor, mix.inputs["Factor"])
        for value, socket in ((a, "A"), (b, "B")):
            self.links.new(value, next(s for s in mix.inputs if s.name == socket and s.type == "VECTOR"))
        return next(s for s in mix.outputs if s.type == "VECTOR")

    def lookup(self, key: str, x: Any, y: Any, interpolation: str) -> Any:
        combine = self.nodes.new("ShaderNodeCombineXYZ")
        self.links.new(x, combine.inputs["X"])
        self.links.new(y, combine.inputs["Y"])
        tex = self.nodes.new("ShaderNodeTexImage")
        tex.image = self.images[key]
        tex.interpolation = interpolation
        tex.extension = "EXTEND"
        self.links.new(combine.outputs["Vector"], tex.inputs["Vector"])
        return tex.outputs["Color"]


def build_group(table: Mapping[str, Any], name: str = GROUP_NAME, exact: bool | None = None,
                surface_nodes: Mapping[str, Any] | None = None) -> Any:
    """The node group for a ``spectral_skin.shader_table`` result (created, or rebuilt in place if it exists).
    Its images are named ``<name> Base Color`` and ``<name> Radius``. ``exact``: bilinear weights computed in the
    group from four Closest lookups per slice (8 texture reads per output instead of 2), as EEVEE needs (GPU
    texture filtering is not exact); None: for EEVEE tables (the metadata's engine), not for Cycles, whose Linear
    lookup is exact. ``surface_nodes``: ``spectral_skin.surface_input_nodes(...)`` of the material's surface model
    and target, which the group interpolates linearly in the oiliness; None: the paper's (level 0.5 × oiliness, no
    Coat)."""
    import spectral_skin

    meta = table["metadata"]
    if surface_nodes is None:
        surface_nodes = dict(spectral_skin.surface_input_nodes("paper", engine=meta.get("engine", "cycles")))
    if exact is None:
        exact = meta.get("engine") == "eevee"
    images = {
        "base_color_log": table_image(f"{name} Base Color", table["base_color_log"]),
        "radius_log": table_image(f"{name} Radius", table["radius_log"]),
    }
    group = _empty_group(name)
    group_in = group.nodes.new("NodeGroupInput")
    group_out = group.nodes.new("NodeGroupOutput")
    build = _Nodes(group, images)
    _table_outputs(build, meta, exact, group_in, group_out)
    _surface_outputs(build, surface_nodes, group_in, group_out)
    return group


def _empty_group(name: str) -> Any:
    """The node group ``name`` with no nodes, its interface this layout's (kept when it already is: clearing it would
    cut the links and reset the inputs of every group node using the group, another material's or one applied
    earlier in the same batch)."""
    group = bpy.data.node_groups.get(name) or bpy.data.node_groups.new(name, "ShaderNodeTree")
    group.nodes.clear()
    wanted = [(s, "INPUT", "NodeSocketFloat") for s in INPUTS] + [(s, "OUTPUT", t) for s, t in OUTPUTS]
    have = [(i.name, i.in_out, i.socket_type) for i in group.interface.items_tree if i.item_type == "SOCKET"]
    if sorted(have) != sorted(wanted) or [h for h in have if h[1] == "INPUT"] != wanted[:len(INPUTS)]:
        group.interface.clear()
        for socket, in_out, socket_type in wanted:
            group.interface.new_socket(name=socket, in_out=in_out, socket_type=socket_type)
    group[LAYOUT_KEY] = LAYOUT_VERSION
    return group


def _table_outputs(build: _Nodes, meta: dict[str, Any], exact: bool, group_in: Any, group_out: Any) -> None:
    """Base Color and Subsurface Radius: the table's two slices around the melanin blend, each looked up at the
    warped (melanin, haemoglobin), mixed, and exponentiated (the table holds logarithms)."""
    math, vector_mix, lookup = build.math, build.vector_mix, build.lookup
    n_m, n_b, n_h = (int(meta[a]["nodes"]) for a in ("melanin", "melanin_blend", "hemoglobin"))
    width, slice_width, gutter = int(meta["width"]), int(meta["slice_width"]), int(meta["gutter"])

    def unit(socket: str, scale: float) -> Any:
        """clamp(value / scale, 0, 1)."""
        return math("DIVIDE", group_in.outputs[socket], scale, clamp=True)

    # Warped coordinates (cube roots of the concentrations over their ranges' maxima; 0.5 and 0.1 from the metadata).
    u_m = math("POWER", unit("Melanin", float(meta["melanin"]["max"])), 1.0 / 3.0)
    u_h = math("POWER", unit("Hemoglobin", float(meta["hemoglobin"]["max"])), 1.0 / 3.0)
    b = math("MULTIPLY", unit("Melanin Blend", float(meta["melanin_blend"]["max"])), float(n_b - 1))
    j = math("MINIMUM", math("FLOOR", b), float(n_b - 2))
    t = math("SUBTRACT", b, j)
    # Texel coordinates (texel k's centre at k): p_x(j) = j * slice_width + gutter + u_m (n_m - 1), p_y = u_h (n_h - 1);
    # image coordinates x = (p_x + 0.5) / width, y = (p_y + 0.5) / n_h.
    p_m = math("MULTIPLY", u_m, float(n_m - 1))
    p_y = math("MULTIPLY", u_h, float(n_h - 1))
    slice_x = math("MULTIPLY_ADD", j, float(slice_width), float(gutter) + 0.5)  # + 0.5: to image coordinates
    if exact:
        # Bilinear weights computed here, four Closest lookups at texel centres per slice: GPU filtering is not
        # exact (EEVEE under llvmpipe missed by up to 0.03 texel along x, several % where the table is steep).
        i_m, i_y = math("FLOOR", p_m), math("FLOOR", p_y)
        f_m, f_y = math("SUBTRACT", p_m, i_m), math("SUBTRACT", p_y, i_y)
        ys = [math("DIVIDE", math("ADD", i_y, 0.5 + k), float(n_h)) for k in (0, 1)]
        corners = []  # per slice: [(x_a, x_b)]
        for s in (0, 1):
            x_a = math("DIVIDE", math("ADD", math("ADD", slice_x, i_m), float(s * slice_width)), float(width))
            corners.append((x_a, math("ADD", x_a, 1.0 / width)))
    else:
        x0 = math("DIVIDE", math("ADD", slice_x, p_m), float(width))
        xs = (x0, math("ADD", x0, slice_width / width))
        y = math("DIVIDE", math("ADD", p_y, 0.5), float(n_h))
    for key, output in (("base_color_log", "Base Color"), ("radius_log", "Subsurface Radius")):
        if exact:
            slices = []
            for x_a, x_b in corners:
                rows = [vector_mix(f_m, lookup(key, x_a, y_k, "Closest"), lookup(key, x_b, y_k, "Closest"))
                        for y_k in ys]
                slices.append(vector_mix(f_y, rows[0], rows[1]))
        else:
            slices = [lookup(key, x, y, "Linear") for x in xs]
        mix_out = vector_mix(t, slices[0], slices[1])
        separate = build.nodes.new("ShaderNodeSeparateXYZ")
        build.links.new(mix_out, separate.inputs["Vector"])
        combine = build.nodes.new("ShaderNodeCombineXYZ")
        for axis in "XYZ":
            build.links.new(math("EXPONENT", separate.outputs[axis]), combine.inputs[axis])
        build.links.new(combine.outputs["Vector"], group_out.inputs[output])


def _surface_outputs(build: _Nodes, surface_nodes: Mapping[str, Any], group_in: Any, group_out: Any) -> None:
    """The surface's inputs, linear in the oiliness between the core's nodes o_k (exact for the level and the Coat
    Weight; the Coat Roughness within 6e-5: spectral_skin.surface_input_nodes): v(o) = v_0 + sum over segments of
    clamp((o - o_k) / (o_k+1 - o_k), 0, 1) (v_k+1 - v_k). The paper's one segment is 0.5 * clamp(oiliness, 0, 1)."""
    knots = [float(o) for o in surface_nodes["oiliness"]]
    ramps = [build.math("MULTIPLY_ADD", group_in.outputs["Oiliness"], 1.0 / (b - a), -a / (b - a), clamp=True)
             for a, b in zip(knots, knots[1:], strict=False)]
    for output, key in SURFACE_OUTPUTS.items():
        values = [float(v) for v in surface_nodes[key]]
        value: Any = values[0]
        for ramp, (a, b) in zip(ramps, zip(values, values[1:], strict=False), strict=True):
            value = build.math("MULTIPLY_ADD", ramp, b - a, value)
        if isinstance(value, float):
            group_out.inputs[output].default_value = value
        else:
            build.links.new(value, group_out.inputs[output])


def has_group(name: str) -> bool:
    """Whether the blend file has the node group ``name`` of this layout version and both its table images, packed
    (then Apply reuses them)."""
    group = bpy.data.node_groups.get(name)
    images = [bpy.data.images.get(f"{name} {kind}") for kind in ("Base Color", "Radius")]
    return (group is not None and group.get(LAYOUT_KEY) == LAYOUT_VERSION
            and all(i is not None and i.packed_file is not None for i in images))


def _packed(image: Any) -> Any:
    """Pack a generated float image into the .blend (so nothing depends on a temporary file)."""
    image.pack()
    image.colorspace_settings.name = NON_COLOR
    return image


def _non_color(image: Any) -> None:
    """Tag a parameter image Non-Color (raw values), keeping the pixels of one Blender holds only in memory
    (generated, or painted and not saved), which a colour space change would regenerate or reload."""
    if image.colorspace_settings.name == NON_COLOR:
        return
    keep = None
    if image.source == "GENERATED" or image.is_dirty:
        keep = np.empty(len(image.pixels), dtype=np.float32)
        image.pixels.foreach_get(keep)
    image.colorspace_settings.name = NON_COLOR
    if keep is not None:
        image.pixels.foreach_set(keep)
        image.update()


def _roles(param: str) -> tuple[str, str, str]:
    return f"live {param}", f"live {param} channel", f"live {param} range"


def remove_nodes(tree: Any) -> None:
    """Delete the live nodes (group node, parameter textures) from a material's tree: Apply in Baked mode."""
    gone = [node for node in nodes.tagged_nodes(tree) if str(node[nodes.TAG]).startswith("live")]
    prefixes = tuple(f'nodes["{bpy.utils.escape_identifier(node.name)}"]' for node in gone)
    # Keys and drivers on the removed nodes' sockets (carry_animation's copies) would dangle in the tree's action.
    anim.remove(tree, lambda path, _index: not path.startswith(prefixes))
    for node in gone:
        tree.nodes.remove(node)


def _direct(image: Any) -> bool | None:
    """How the group reads a parameter image itself: None when it cannot (an EXR file: Blender does not read it as
    the core does), else whether its values are normalized (8/16-bit: 0..1 onto the parameter's range), as the baked
    path reads it (props._image_parameter_maps)."""
    if image.source == "GENERATED" or image.is_dirty:
        return not image.is_float
    if image.source in ("FILE", "TILED") and os.path.splitext(image.filepath)[1].lower() != ".exr":
        return True  # a tiled image (UDIM tile set) is read by the Image Texture node tile by tile, from the UVs
    return None


def _parameter_image(material: Any, param: str, maps: Mapping[str, Any]) -> tuple[Any, bool] | None:
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
    name = f"SpectralSkin {material.name} {param}"
    if pmap.tiles:
        return tiled_copy(name, pixels, pmap.tiles), bool(pmap.normalized)
    copy = table_image(name, np.repeat(pixels[:, :, None], 3, axis=2))
    return _packed(copy), bool(pmap.normalized)


def tiled_copy(name: str, pixels: np.ndarray, tiles: tuple[tuple[int, int], ...]) -> Any:
    """A packed float UDIM image (Non-Color, grey) holding a tile set's values: ``pixels`` (H, W) are the tiles
    stacked top to bottom, ``tiles`` each tile's (number, rows), as the core reads a tile set
    (core.read_tile_set; split by core.maps.split_tiles). Blender's Python API sets the pixels of a tiled image's first tile only, so each tile is
    written by Blender as a 32-bit float EXR into a temporary folder, loaded as one tiled image and packed into the
    .blend (Blender packs every tile); the folder is then removed: nothing depends on it."""
    old = bpy.data.images.get(name)
    if old is not None:
        bpy.data.images.remove(old)
    with tempfile.TemporaryDirectory(prefix="spectral-skin-") as folder:
        for tile, rows in split_tiles(pixels, tiles):
            part = table_image(f"{name} {tile}", np.repeat(rows[:, :, None], 3, axis=2))
            part.filepath_raw = os.path.join(folder, f"copy.{tile}.exr")
            part.file_format = "OPEN_EXR"
            part.use_half_precision = False  # the core's reading, not rounded
            part.save()
            bpy.data.images.remove(part)
        image = bpy.data.images.load(os.path.join(folder, f"copy.{tiles[0][0]}.exr"))
        image.source = "TILED"
        found = sorted(t.number for t in image.tiles)
        if found != sorted(t for t, _ in tiles):
            raise RuntimeError(f"{name}: Blender loaded the tiles {found}, expected {[t for t, _ in tiles]}")
        image.pack()
    image.name = name
    image.colorspace_settings.name = NON_COLOR
    return image


def chain_head(socket: Any) -> Any:
    """The socket that takes a group input's constant or parameter map: the input itself, or, when masks
    (masks.py) feed it, the Value input of the first mask of their chain."""
    while socket.is_linked:
        node = socket.links[0].from_node
        if not str(node.get(nodes.TAG, "")).endswith(" mask"):
            break
        socket = node.inputs["Value"]
    return socket


def pack_painted(tree: Any) -> list[str]:
    """Pack again every painted image the material's nodes read (a generated or packed image with unsaved
    changes: a painted parameter map or mask), so that the saved .blend carries the painting to a render node
    (Blender saves a generated image as its generator, and a packed one as last packed). Returns their names."""
    packed = []
    for node in tree.nodes:
        image = getattr(node, "image", None) if node.type == "TEX_IMAGE" else None
        if image is not None and image.is_dirty and (image.source == "GENERATED" or image.packed_file is not None):
            image.pack()
            packed.append(image.name)
    return packed


def carry_animation(material: Any, param: str, socket: Any) -> list[str]:
    """The keys and the driver of the panel's slider ``spectral_skin.<param>`` copied onto the group's input
    ``socket`` (anim.py), so that they animate the shader in the session and on a render node without the add-on
    (where the slider's own property does not exist); each replaces what the socket had of its kind, and keys or a
    driver the artist put on the socket itself stay when the slider has none. Returns what was copied."""
    path = f"spectral_skin.{param}"
    copied = []
    for curve in anim.fcurves(material):
        if curve.data_path == path and anim.copy_keys(curve, socket, "default_value") is not None:
            copied.append("keys")
    for driver in anim.drivers(material):
        if driver.data_path == path:
            anim.copy_driver(driver, socket, "default_value")
            copied.append("driver")
    return copied


def _wire_parameter_image(material: Any, node: Any, index: int, param: str, socket: Any,
                          maps: Mapping[str, Any]) -> None:
    """The Image Texture that feeds a group input ``socket`` with the parameter's map (:func:`_parameter_image`; its
    first channel, scaled onto the parameter's range when its values are normalized); nothing for a constant."""
    source = _parameter_image(material, param, maps)
    if source is None:
        return
    tree = material.node_tree
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


def wire(material: Any, plan: MaterialPlan) -> Any:
    """Live mode's last step (main thread): the group (built from ``plan.live.table``, its images packed, or
    the blend file's), its node wired into the tagged Principled BSDF, its inputs set (see the module's docstring).
    Returns the group node."""
    info = plan.live
    if info is None:
        raise ValueError("the plan is not a Live plan (core/live.py live_plan)")
    tree = material.node_tree
    principled = nodes.tagged_nodes(tree, "principled")[0]
    name = info.group
    if info.table is not None:
        group = build_group(info.table, name, surface_nodes=dict(info.surface_nodes))
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
        node.inputs[socket_name].default_value = float(info.constants[param])
        for role in _roles(param):
            for stale in nodes.tagged_nodes(tree, role):
                tree.nodes.remove(stale)
        socket = chain_head(node.inputs[socket_name])
        socket.default_value = float(info.constants[param])
        carry_animation(material, param, socket)
        _wire_parameter_image(material, node, index, param, socket, info.maps)
    pack_painted(tree)
    outputs = [("Base Color", True), ("Subsurface Radius", info.subsurface),
               *((output, info.specular) for output in SURFACE_OUTPUTS)]
    for output, used in outputs:
        target = nodes._socket(principled.inputs, output)
        if used:
            tree.links.new(node.outputs[output], target)
    return node
