"""The material's node tree from a material plan (see core/plan.py): set sockets by name, no numerics here.

Nodes the add-on creates carry the custom property ``spectral_skin`` (their role) and a name starting with
``SpectralSkin``; re-applying finds and updates them and never touches other nodes; :func:`remove_skin` deletes them
and puts back the Surface link the material had before.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import bpy

from . import frame_values
from .core import DEFAULT_WORKING_SPACE, NON_COLOR, UDIM_TOKEN, MaterialPlan, map_kinds

TAG = "spectral_skin"
NAME_PREFIX = "SpectralSkin"
# Custom property of the material output: [node name, socket identifier] of the Surface link before Apply.
PREVIOUS_SURFACE = "spectral_skin_previous_surface"


def scene_working_space() -> str:
    """The blend file's scene-linear working space: ``bpy.data.colorspace.working_space`` in Blender 5.0
    ('Linear Rec.709', 'Linear Rec.2020' or 'ACEScg'); 'Linear Rec.709' where it does not exist (Blender 4.x)."""
    colorspace = getattr(bpy.data, "colorspace", None)
    return str(getattr(colorspace, "working_space", "") or DEFAULT_WORKING_SPACE)


def scene_target(scene: bpy.types.Scene) -> dict[str, str]:
    """The target of the running Blender and the scene's render engine: {"blender": "5.0", "engine": "cycles" |
    "eevee"}, from the core's table. ValueError for an engine the table does not know (Workbench)."""
    from .core import engine_name, version_text

    engine = engine_name(bpy.app.version, scene.render.engine)
    if engine is None:
        raise ValueError(f"the scene renders with {scene.render.engine}, which shows no subsurface scattering: "
                         "choose Cycles or EEVEE as the render engine, then apply")
    return {"blender": version_text(bpy.app.version), "engine": engine}


def tagged_nodes(tree: bpy.types.NodeTree, role: str | None = None) -> list[bpy.types.Node]:
    """Nodes the add-on created (of one role, or all)."""
    return [n for n in tree.nodes if TAG in n and (role is None or n[TAG] == role)]


def _tag(node: bpy.types.Node, role: str) -> None:
    node[TAG] = role
    node.name = node.label = f"{NAME_PREFIX} {role.title()}"


def _socket(sockets: Any, name: str) -> bpy.types.NodeSocket:
    """A socket by name, available or not (``inputs[name]`` misses sockets the current method hides)."""
    for socket in sockets:
        if socket.name == name or socket.identifier == name:
            return socket
    raise KeyError(name)


def _unlink(tree: bpy.types.NodeTree, socket: bpy.types.NodeSocket) -> None:
    for link in list(socket.links):
        tree.links.remove(link)


def _output_node(tree: bpy.types.NodeTree) -> bpy.types.Node:
    output = tree.get_output_node("ALL") or tree.get_output_node("CYCLES")
    if output is None:
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        _tag(output, "output")
        output.is_active_output = True
    return output


def _principled(tree: bpy.types.NodeTree) -> bpy.types.Node:
    found = tagged_nodes(tree, "principled")
    if found:
        return found[0]
    node = tree.nodes.new("ShaderNodeBsdfPrincipled")
    _tag(node, "principled")
    output = _output_node(tree)
    node.location = (output.location.x - 320, output.location.y)
    return node


def load_image(path: str) -> bpy.types.Image:
    """The image of a texture the add-on wrote: a file, or a UDIM tile set (``<UDIM>`` in the name; tiles as written
    to disk), which Blender loads from its first tile's file and turns into a tiled image that finds the others."""
    if UDIM_TOKEN not in os.path.basename(path):
        return bpy.data.images.load(path, check_existing=True)
    for image in bpy.data.images:  # the tile set loaded already (a tiled image's file path keeps the token)
        if image.source == "TILED" and os.path.abspath(bpy.path.abspath(image.filepath,
                                                                         library=image.library)) == path:
            return image
    stem, extension = os.path.basename(path).split(UDIM_TOKEN, 1)
    folder = os.path.dirname(path)
    tiles = sorted(name for name in os.listdir(folder)
                   if name.startswith(stem) and name.endswith(extension) and name[len(stem):-len(extension)].isdigit())
    if not tiles:
        raise OSError(f"{path}: no tile of the set was written")
    image = bpy.data.images.load(os.path.join(folder, tiles[0]), check_existing=False)
    image.source = "TILED"
    return image


def _texture_node(tree: bpy.types.NodeTree, role: str, path: str, colorspace: str,
                  principled: bpy.types.Node, index: int) -> bpy.types.Node:
    found = tagged_nodes(tree, role)
    node = found[0] if found else tree.nodes.new("ShaderNodeTexImage")
    if not found:
        _tag(node, role)
        node.location = (principled.location.x - 360, principled.location.y - 280 * index)
    image = node.image
    if image is None or os.path.abspath(bpy.path.abspath(image.filepath, library=image.library)) != path:
        image = load_image(path)
    image.reload()
    image.colorspace_settings.name = colorspace
    if bpy.data.filepath:
        try:
            image.filepath = bpy.path.relpath(path)
        except ValueError:  # another drive (Windows): keep the absolute path
            pass
    node.image = image
    node.interpolation = "Linear"
    node.extension = "EXTEND"
    return node


def _principled_values(plan: MaterialPlan) -> dict[str, Any]:
    """The plan's value of each Principled input it sets (None: a texture feeds it)."""
    return {
        "Base Color": None if plan.base_color is None else [*plan.base_color, 1.0],
        "Subsurface Radius": None if plan.radius is None else list(plan.radius),
        "Specular IOR Level": plan.specular_ior_level,
        # 0 where the scene analysis dropped subsurface scattering (core/scene.py): plain diffuse, same albedo.
        "Subsurface Weight": plan.subsurface_weight,
        "Subsurface Scale": plan.scale,
        "Roughness": plan.roughness,
        "IOR": plan.ior,
        "Subsurface IOR": plan.subsurface_ior,
        # The surface's sharp lobe (the measured surface; weight 0 for the paper's oil layer).
        "Coat Weight": plan.coat_weight,
        "Coat Roughness": plan.coat_roughness,
        "Coat IOR": plan.coat_ior,
    }


def _link_textures(tree: bpy.types.NodeTree, node: bpy.types.Node, files: Mapping[str, str],
                   working_space: str) -> None:
    """An Image Texture per file the core wrote, feeding its map kind's Principled input (the albedo tagged with the
    working space, the rest Non-Color); the add-on's texture nodes of kinds without a file removed."""
    for index, kind in enumerate(map_kinds()):
        path = files.get(kind.name)
        if path is None:
            for stale in tagged_nodes(tree, kind.name):
                tree.nodes.remove(stale)
            continue
        colorspace = working_space if kind.colour else NON_COLOR
        texture = _texture_node(tree, kind.name, os.path.abspath(path), colorspace, node, index)
        tree.links.new(texture.outputs["Color"], _socket(node.inputs, kind.principled_input))


def apply_plan(material: bpy.types.Material, plan: MaterialPlan,
               files: Mapping[str, str] | None = None) -> bpy.types.Node:
    """Make (or update) the add-on's Principled BSDF and texture nodes from a computed plan and the files the core
    wrote for its textures (``files``: {map name: path}, :func:`~core.material_plan.write_textures`); returns the
    Principled. Each texture feeds the Principled input of its map kind (core/maps.py).

    A constant Base Color is taken as it is, so the plan must be in the scene's working space (ValueError if not);
    the albedo texture is tagged with the plan's working space, which Blender converts to the scene's; every other
    texture is data (Non-Color).
    """
    working_space = plan.working_space
    if plan.base_color is not None and working_space != scene_working_space():
        raise ValueError(f"the plan's Base Color is in {working_space} but the scene's working space is "
                         f"{scene_working_space()}: compute the plan with working_space={scene_working_space()!r}")
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    node = _principled(tree)
    for name, value in _principled_values(plan).items():
        socket = _socket(node.inputs, name)
        _unlink(tree, socket)
        if value is not None:
            socket.default_value = value
    # Set after the values: the method hides sockets it does not use.
    node.subsurface_method = plan.method
    _link_textures(tree, node, files or {}, working_space)
    output = _output_node(tree)
    surface = _socket(output.inputs, "Surface")
    if not any(link.from_node == node for link in surface.links):
        # Remembered on the output node, so that remove_skin can put the material's own shader back.
        previous = [[link.from_node.name, link.from_socket.identifier] for link in surface.links]
        output[PREVIOUS_SURFACE] = previous[0] if previous else []
        _unlink(tree, surface)
        tree.links.new(node.outputs["BSDF"], surface)
    # An animated constant material: its values per frame as F-curves on these sockets (frame_values.py).
    frame_values.store(material, node, plan)
    return node


def remove_skin(material: bpy.types.Material) -> int:
    """Delete the add-on's nodes from ``material`` and link the material output's Surface back to what it was before
    the first Apply (when that node is still there); returns how many nodes were removed. Images the add-on loaded
    and nothing else uses are removed too."""
    tree = material.node_tree
    if tree is None:
        return 0
    images = [n.image for n in tagged_nodes(tree) if n.type == "TEX_IMAGE" and n.image is not None]
    outputs = [n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and PREVIOUS_SURFACE in n]
    removed = 0
    for principled in tagged_nodes(tree, "principled"):
        frame_values.clear(material, principled)
    for node in tagged_nodes(tree):
        tree.nodes.remove(node)
        removed += 1
    for output in outputs:
        if output.name not in tree.nodes:
            continue
        previous = list(output[PREVIOUS_SURFACE])
        del output[PREVIOUS_SURFACE]
        if len(previous) == 2 and previous[0] in tree.nodes:
            source = tree.nodes[previous[0]]
            sockets = [s for s in source.outputs if s.identifier == previous[1]]
            if sockets:
                tree.links.new(sockets[0], _socket(output.inputs, "Surface"))
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)
    return removed
