"""From Albedo Texture's steps on Blender's data (the portable fit is core/albedo.py): :func:`prepare_albedo` reads the
material's Base Color image (or UDIM tile set) and Skin Mask as linear RGB (main thread), ``core.albedo.fit_and_write``
fits and writes the parameter EXR (safe in a worker thread: :func:`albedo_task`), :func:`finish_albedo` sets the
result on the material (main thread), once everything succeeded.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import bpy

from . import nodes
from .core import NON_COLOR, texture_prefix
from .core import albedo as core_albedo
from .core.maps import stack_tiles
from .nodes import scene_working_space
from .work import Task


def base_color_image(material: bpy.types.Material) -> bpy.types.Image:
    """The image of the material's Base Color: an Image Texture (not one the add-on made) linked, directly or
    through reroutes, to a Principled BSDF's Base Color; ValueError when there is none."""
    tree = material.node_tree
    for node in (tree.nodes if tree is not None else ()):
        if node.type != "BSDF_PRINCIPLED":
            continue
        socket = nodes._socket(node.inputs, "Base Color")
        while socket.is_linked:
            source = socket.links[0].from_node
            if source.type == "REROUTE":
                socket = source.inputs[0]
                continue
            if source.type == "TEX_IMAGE" and source.image is not None and nodes.TAG not in source:
                return source.image
            break
    raise ValueError(f"the material {material.name!r} has no image linked to a Principled BSDF's Base Color")


def image_pixels(image: bpy.types.Image) -> Any:
    """An image's pixels as Blender holds them: (H, W, channels) float32, row 0 at the top."""
    import numpy as np

    width, height = image.size
    if width == 0 or height == 0 or image.channels < 3:
        raise ValueError(f"the Base Color image {image.name!r} has no RGB pixels (is its file missing?)")
    flat = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(flat)
    return flat.reshape(height, width, image.channels)[::-1]


def base_color_texels(image: bpy.types.Image, raw: bool = False) -> tuple[Any, str, list[tuple[int, int]]]:
    """The Base Color image's texels as (H, W, 3) linear RGB, their working space, and for a UDIM tile set the
    (tile, rows) of each tile stacked top to bottom (empty for one image). A tile set's tiles are read from their
    files (Blender's pixels of a tiled image are its first tile's), in the tiled image's colour space; they must share
    one width (ValueError naming them). ``raw``: Blender's pixel values as they are, not decoded (a mask's)."""
    import numpy as np

    def texels(single: bpy.types.Image) -> tuple[Any, str]:
        if raw:
            return np.ascontiguousarray(image_pixels(single)[:, :, :3]), scene_working_space()
        return core_albedo.linear_albedo(image_pixels(single), single.colorspace_settings.name, single.is_float,
                                         scene_working_space())

    if image.source != "TILED":
        pixels, space = texels(image)
        return pixels, space, []
    pattern = bpy.path.abspath(image.filepath, library=image.library)
    parts = []
    for tile in sorted(t.number for t in image.tiles):
        single = bpy.data.images.load(pattern.replace(core_albedo.UDIM_TOKEN, str(tile)), check_existing=False)
        try:
            single.colorspace_settings.name = image.colorspace_settings.name
            pixels, space = texels(single)
        finally:
            bpy.data.images.remove(single)
        parts.append((tile, pixels))
    stacked, tiles = stack_tiles(parts, f"the tile set {image.name!r}")
    return stacked, space, list(tiles)


def prepare_albedo(material: bpy.types.Material, hold_thickness: bool = False,
                   auto_gains: bool = False) -> core_albedo.AlbedoJob:
    """From Albedo Texture's first step (main thread; reads Blender's data, changes nothing): the material's Base
    Color image (or UDIM tile set, fitted as one texture) as linear RGB, the material's Skin Mask (if set, of the same
    size or tiles) as the texels that count, the held epidermis thickness (``hold_thickness``; else chosen for the
    texture), ``auto_gains`` (exposure and white balance corrected first), and the parameter and residual EXR paths
    beside the .blend. Raises ValueError for a material it cannot read."""
    image = base_color_image(material)
    pixels, space, tiles = base_color_texels(image)
    settings = material.spectral_skin
    mask = None
    if settings.skin_mask is not None:
        mask_rgb, _, mask_tiles = base_color_texels(settings.skin_mask, raw=True)
        if [t for t, _ in mask_tiles] != [t for t, _ in tiles]:
            raise ValueError(f"the skin mask {settings.skin_mask.name!r} has the tiles {[t for t, _ in mask_tiles]} "
                             f"but the Base Color {image.name!r} has {[t for t, _ in tiles]}: they must be the same")
        mask = core_albedo.skin_mask(mask_rgb, pixels.shape, settings.skin_mask.name, image.name)
    prefix = texture_prefix(bpy.data.filepath, material.name)
    return core_albedo.AlbedoJob(
        image=image.name, albedo=pixels, working_space=space, tiles=tiles,
        epidermis_thickness_mm=float(settings.epidermis_thickness_mm) if hold_thickness else None,
        transport=settings.transport, auto_gains=auto_gains, mask=mask,
        path=core_albedo.parameter_map_path(bpy.data.filepath, prefix, tiled=bool(tiles)),
        residual_path=core_albedo.parameter_map_path(bpy.data.filepath, prefix, tiled=bool(tiles), kind="residual"))


def finish_albedo(material: bpy.types.Material, job: core_albedo.AlbedoJob, result: dict[str, Any]) -> dict[str, Any]:
    """From Albedo Texture's last step, once the fit and its files succeeded (main thread only): the parameter EXR
    set as the material's Parameter Map (a Non-Color image), the residual loaded as an image to inspect, the Advanced
    sliders set to the extended physiology the fit holds for. Returns the fit's summary (``result`` without the fit
    object, plus "path", "residual", "image", "working_space", "tiles")."""
    loaded = nodes.load_image(job.path)
    loaded.reload()
    loaded.colorspace_settings.name = NON_COLOR
    residual_image = nodes.load_image(job.residual_path)
    residual_image.reload()
    residual_image.colorspace_settings.name = NON_COLOR
    settings = material.spectral_skin
    settings.params_map = loaded
    for name, value in result["extended"].items():
        setattr(settings, name, value)
    return {key: value for key, value in result.items() if key != "fit"} | {
        "path": job.path, "residual": residual_image.name, "image": job.image, "working_space": job.working_space,
        "tiles": [t for t, _ in job.tiles]}


def from_albedo_texture(material: bpy.types.Material, hold_thickness: bool = False,
                        auto_gains: bool = False) -> dict[str, Any]:
    """From Albedo Texture at once (:func:`prepare_albedo`, ``core.albedo.fit_and_write``, :func:`finish_albedo`;
    the operator started from the panel runs the middle step in a worker thread): the material's Base Color image fitted
    per texel by the core (core/albedo.py), the parameter and residual EXRs written beside the .blend by the core,
    then the parameter map set on the material. Returns the fit's summary. Raises ValueError / OSError /
    spectral_skin.SpectralSkinError; the material is then unchanged."""
    job = prepare_albedo(material, hold_thickness, auto_gains)
    result = core_albedo.fit_and_write(job)
    if result is None:  # only a cancel (before_write) gives None, and there is none here
        raise RuntimeError("From Albedo Texture: the fit returned no result")
    return finish_albedo(material, job, result)


def albedo_task(job: core_albedo.AlbedoJob) -> Task:
    """From Albedo Texture's ``core.albedo.fit_and_write`` of ``job`` as a worker's task (work.py)."""
    def task(progress: Callable[[int, int], bool], before_write: Callable[[], bool]) -> dict[str, Any] | None:
        return core_albedo.fit_and_write(job, progress, before_write)
    return task
