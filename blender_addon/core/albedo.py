"""From Albedo Texture, without bpy: the albedo image's pixels as linear RGB, the core's per-texel fit
(``spectral_skin.fit_albedo_map``) and what the operator reports (the bpy glue is
``ops.SPECTRAL_SKIN_OT_from_albedo_texture``); the core's fit writes the parameter EXR itself.

The fit inverts the model: per texel the four parameters whose albedo is nearest the texel's colour (CIEDE2000), with
the extended physiology one value per texture, the epidermis thickness chosen for it (docs/model.md, Extended
physiology). Its parameter map is what ``spectral-skin maps`` and the panel's *Parameter Map* read: channels
melanin, melanin_blend, hemoglobin, oiliness per texel and the extended physiology as channels of one value.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import spectral_skin

from .colour import LINEAR_NAMES, LINEAR_REC709, SRGB_NAMES
from .maps import UDIM_TOKEN
from .settings import DEFAULT_TRANSPORT, EXTENDED_PARAMETERS, TRANSPORTS


def available() -> bool:
    """Whether this spectral_skin has the per-texel albedo fit."""
    return callable(getattr(spectral_skin, "fit_albedo_map", None))


UNAVAILABLE = ("needs a spectral_skin with fit_albedo_map (the albedo-texture fit; this is spectral_skin "
               f"{getattr(spectral_skin, '__version__', '?')})")


def srgb_to_linear(encoded: Any) -> Any:
    """The sRGB decoding (IEC 61966-2-1: linear below 0.04045, else a 2.4 power), as float32: the add-on's one (the
    core's is inside its file reader, which Blender's in-memory pixels never reach)."""
    import numpy as np

    v = np.asarray(encoded, dtype=np.float32)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_albedo(pixels: Any, colorspace: str, is_float: bool, scene_space: str) -> tuple[Any, str]:
    """The albedo as (H, W, 3) float32 linear RGB and its working space, from an image's pixels as Blender gives
    them ((H, W, >= 3), row 0 at the top): a float image's are scene-linear already (Blender converts float images
    into the working space ``scene_space`` on loading); an 8/16-bit image's are its encoded values, decoded here from
    sRGB (Rec.709 primaries) or taken as they are in a linear colour space the core knows. ValueError for any other
    colour space (naming it)."""
    import numpy as np

    rgb = np.ascontiguousarray(np.asarray(pixels, dtype=np.float32)[:, :, :3])
    if is_float:
        return rgb, scene_space
    if colorspace in SRGB_NAMES:
        return srgb_to_linear(rgb), LINEAR_REC709
    if colorspace in LINEAR_NAMES:
        return rgb, LINEAR_NAMES[colorspace]
    raise ValueError(f"the Base Color image is in the colour space {colorspace!r}; From Albedo Texture reads an "
                     f"8/16-bit image in {', '.join((*SRGB_NAMES, *LINEAR_NAMES))}, or any float image")


def fit(albedo: Any, working_space: str, epidermis_thickness_mm: float | None,
        transport: str = DEFAULT_TRANSPORT, auto_gains: bool = False, mask: Any = None,
        progress: Callable[[int, int], bool | None] | None = None) -> dict[str, Any]:
    """The core's per-texel fit (``spectral_skin.fit_albedo_map``, of the model with ``transport``, a key of
    TRANSPORTS; the epidermis thickness chosen for the texture when ``epidermis_thickness_mm`` is None, as the core's
    default, else held; with ``auto_gains`` the exposure and white-balance gains estimated and applied first; with
    ``mask``, an (H, W) bool array, only the texels it marks choose the thickness and the gains and count in the
    figures, the others are fitted to their nearest skin colour) and what
    the operator needs of it: {"fit": the core's ``AlbedoMapFit`` (``write(path)`` writes the parameter EXR),
    "extended": the extended physiology the parameters hold for, "thickness": how the thickness was chosen (None:
    held), "gains" (applied, or measured as the diagnosis' remedy; None), "diagnosis" (why the texture does not look
    like an albedo; None), "median_delta_e00", "max_delta_e00" (over the masked texels), "outside_skin_texels" (the
    core's count of texels outside skin's colours, the one the diagnosis judges),
    "masked_out_texels"}. The core's warning about a
    texture that is not an albedo is not raised here: it is the "diagnosis". ``progress(done, total)`` is the core's
    callback (returning False cancels: InterruptedError). Raises
    spectral_skin.SpectralSkinError when the core refuses the input; RuntimeError when this spectral_skin has no fit."""
    import numpy as np

    fit_map: Any = getattr(spectral_skin, "fit_albedo_map", None)
    if not callable(fit_map):
        raise RuntimeError(f"From Albedo Texture {UNAVAILABLE}")
    keywords: dict[str, Any] = {} if transport == DEFAULT_TRANSPORT else {"transport": TRANSPORTS[transport]}
    if auto_gains:
        keywords["rgb_gains"] = "auto"
    if mask is not None:
        keywords["mask"] = mask
    if progress is not None:
        keywords["progress"] = progress
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", spectral_skin.SpectralSkinWarning)  # the same text is result.diagnosis
        result = fit_map(albedo, working_space=working_space, epidermis_thickness_mm=epidermis_thickness_mm,
                         **keywords)
    residual = np.asarray(result.residual_delta_e00, dtype=np.float32)
    if tuple(result.shape) != tuple(albedo.shape[:2]) or residual.shape != albedo.shape[:2]:
        raise RuntimeError(f"spectral_skin.fit_albedo_map returned a fit of {tuple(result.shape)} for an albedo of "
                           f"{albedo.shape}")
    extended = {name: float(result.extended[name]) for name in EXTENDED_PARAMETERS}
    skin = residual if mask is None or not np.any(mask) else residual[np.asarray(mask, dtype=bool)]
    return {"fit": result, "extended": extended, "thickness": result.thickness,
            "gains": getattr(result, "gains", None), "diagnosis": getattr(result, "diagnosis", None),
            "median_delta_e00": float(np.median(skin)), "max_delta_e00": float(np.max(skin)),
            "outside_skin_texels": int(result.stats["outside_skin_texels"]),
            "masked_out_texels": int(result.stats.get("masked_out_texels", 0))}


def skin_mask(mask_rgb: Any, albedo_shape: tuple[int, ...], mask_name: str, albedo_name: str) -> Any:
    """The skin mask as an (H, W) bool array, from the mask image's values as Blender holds them (H, W, 3), not
    decoded: white, over half on average over the channels, is skin (0 and 1 are the same in every colour space).
    ValueError when its size is not the albedo's (naming both)."""
    import numpy as np

    rgb = np.asarray(mask_rgb, dtype=np.float32)
    if rgb.shape[:2] != tuple(albedo_shape[:2]):
        raise ValueError(f"the skin mask {mask_name!r} is {rgb.shape[1]}x{rgb.shape[0]} texels but the Base Color "
                         f"{albedo_name!r} is {albedo_shape[1]}x{albedo_shape[0]}: they must have one size (a tile "
                         "set: the same tiles)")
    return np.ascontiguousarray(rgb[:, :, :3].mean(axis=2) > 0.5)


def parameter_map_path(blend_path: str, prefix: str, tiled: bool = False, kind: str = "params") -> str:
    """Where the fit's EXR of ``kind`` ("params", the parameter map, or "residual") goes: beside the .blend,
    ``<prefix>_params.exr`` (prefix: core.texture_prefix), or the tile set ``<prefix>_params.<UDIM>.exr`` with
    ``tiled``. ValueError for an unsaved .blend (no place beside it)."""
    if not blend_path:
        raise ValueError("the .blend is not saved yet, so the parameter map has no place beside it: save it first")
    name = f"{prefix}_{kind}.{UDIM_TOKEN}.exr" if tiled else f"{prefix}_{kind}.exr"
    return os.path.join(os.path.dirname(os.path.abspath(blend_path)), name)


@dataclass(frozen=True)
class AlbedoJob:
    """What From Albedo Texture fits and where it writes, gathered from bpy on Blender's main thread (``ops``): the
    Base Color image's name, the albedo as (H, W, 3) linear RGB in ``working_space``, the UDIM ``tiles`` stacked top to bottom ((tile, rows); empty
    for one image), the held epidermis thickness (None: chosen), the transport (a key of TRANSPORTS), whether to
    correct exposure and white balance, the skin mask ((H, W) bool or None) and the parameter and residual EXR paths
    (:func:`parameter_map_path`)."""

    image: str
    albedo: Any
    working_space: str
    tiles: list[tuple[int, int]]
    epidermis_thickness_mm: float | None
    transport: str
    auto_gains: bool
    mask: Any
    path: str
    residual_path: str


def fit_and_write(job: AlbedoJob, progress: Callable[[int, int], bool | None] | None = None,
                  before_write: Callable[[], bool] | None = None) -> dict[str, Any] | None:
    """From Albedo Texture's computing step, which needs no bpy (safe in a worker thread): :func:`fit`, then the core
    writes the parameter and residual EXRs (tile sets for ``job.tiles``). ``progress`` is the fit's callback (False
    cancels: InterruptedError); ``before_write()`` is called between the two, and when it returns False nothing is
    written and None is returned (a cancel). Returns :func:`fit`'s result."""
    result = fit(job.albedo, job.working_space, job.epidermis_thickness_mm, job.transport, job.auto_gains, job.mask,
                 progress)
    if before_write is not None and not before_write():
        return None
    result["fit"].write(job.path, job.residual_path, tiles=job.tiles or None)
    return result
