"""The material's Spectral Skin settings (``Material.spectral_skin``) and what the last Apply computed."""

from __future__ import annotations

import bpy
import numpy as np
import spectral_skin

from .core import PARAMETER_INFO, PARAMETERS, ParameterMap, SkinSettings
from .nodes import scene_working_space

_PRESETS = spectral_skin.presets()
_DEFAULT_PRESET = "caucasian" if "caucasian" in _PRESETS else next(iter(_PRESETS))

PRESET_ITEMS = [("CUSTOM", "Custom", "Parameters as set below")] + [
    (name.upper(), name.title(), f"{p['description']}: C_m {p['melanin']}, β_m {p['melanin_blend']}, "
     f"C_h {p['hemoglobin']}, oiliness {p['oiliness']}")
    for name, p in _PRESETS.items()
]

METHOD_ITEMS = [
    ("BURLEY", "Christensen-Burley",
     "Cycles' Christensen-Burley profile: Base Color is exactly the skin's total diffuse reflectance"),
    ("RANDOM_WALK", "Random Walk",
     "Cycles' volumetric random walk: Base Color and Radius are fitted so the walk reproduces the skin's reflectance"),
]

ACCURACY_ITEMS = [
    ("DRAFT", "Draft", "Fast preview: fewer wavelengths and fit frequencies (see docs/accuracy-vs-time.md)"),
    ("DEFAULT", "Default", "Albedo within 0.2 % and radius within 1 % of the converged reference"),
    ("REFERENCE", "Reference", "The converged reference: 1 nm wavelength steps; about 30 times slower"),
]


def _apply_preset(self: SpectralSkinSettings, _context: bpy.types.Context) -> None:
    if self.preset == "CUSTOM":
        return
    values = _PRESETS[self.preset.lower()]
    for name in PARAMETERS:
        setattr(self, name, values[name])


def _parameter(name: str) -> bpy.props.FloatProperty:
    low, high, label, description = PARAMETER_INFO[name]
    return bpy.props.FloatProperty(
        name=label, description=description, default=_PRESETS[_DEFAULT_PRESET][name], min=low, max=high,
        precision=3, step=0.1 if high <= 0.1 else 1, subtype="FACTOR")


def _parameter_map(name: str) -> bpy.props.PointerProperty:
    label = PARAMETER_INFO[name][2]
    return bpy.props.PointerProperty(
        type=bpy.types.Image, name=f"{label} Map",
        description=f"Optional greyscale image of {label} per texel (replaces the constant): float images hold the "
        "value itself, 8/16-bit images map 0..1 onto the parameter's range")


class SpectralSkinSettings(bpy.types.PropertyGroup):
    preset: bpy.props.EnumProperty(
        name="Preset", description="Skin type from the Donner & Jensen 2006 sketch; sets the four parameters",
        items=PRESET_ITEMS, default=_DEFAULT_PRESET.upper(), update=_apply_preset)
    melanin: _parameter("melanin")
    melanin_blend: _parameter("melanin_blend")
    hemoglobin: _parameter("hemoglobin")
    oiliness: _parameter("oiliness")
    melanin_map: _parameter_map("melanin")
    melanin_blend_map: _parameter_map("melanin_blend")
    hemoglobin_map: _parameter_map("hemoglobin")
    oiliness_map: _parameter_map("oiliness")
    method: bpy.props.EnumProperty(
        name="Subsurface Method", description="Cycles subsurface method the material is made for",
        items=METHOD_ITEMS, default="BURLEY")
    accuracy: bpy.props.EnumProperty(
        name="Accuracy", description="Accuracy of the spectral computation (docs/accuracy-vs-time.md)",
        items=ACCURACY_ITEMS, default="DEFAULT")
    output_dir: bpy.props.StringProperty(
        name="Texture Folder",
        description="Folder for the texture maps computed from parameter maps ('//' is the .blend's folder)",
        default="//skin_maps", subtype="DIR_PATH")

    # What the last Apply computed, for the panel.
    has_result: bpy.props.BoolProperty(name="Applied", default=False)
    result_albedo: bpy.props.FloatVectorProperty(
        name="Albedo", description="Total diffuse reflectance (mean over the maps), linear Rec.709",
        size=3, subtype="COLOR", min=0.0, max=1.0)
    result_radius_mm: bpy.props.FloatVectorProperty(
        name="Radius (mm)", description="Subsurface Radius × Scale in millimetres, R, G, B (mean over the maps)",
        size=3, precision=3)
    result_computed: bpy.props.StringProperty(name="Computed", description="What was computed")
    result_seconds: bpy.props.FloatProperty(name="Seconds", description="Time the computation took, seconds")
    result_warning: bpy.props.StringProperty(name="Warning", description="Warnings of the last Apply")


def _image_parameter_map(image: bpy.types.Image, name: str) -> ParameterMap:
    """The first channel of a Blender image as an (H, W) float32 array, row 0 at the top."""
    width, height = image.size
    if width == 0 or height == 0:
        raise ValueError(f"{name} map {image.name!r} has no pixels (missing or unreadable file?)")
    flat = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(flat)
    pixels = flat.reshape(height, width, image.channels)[::-1, :, 0]
    return ParameterMap(pixels=np.ascontiguousarray(pixels), normalized=not image.is_float, name=image.name)


def settings_from_material(material: bpy.types.Material, scene: bpy.types.Scene) -> SkinSettings:
    """The portable settings of a material's properties (raises ValueError for unusable images or folders)."""
    props = material.spectral_skin
    maps = {}
    for name in PARAMETERS:
        image = getattr(props, f"{name}_map")
        if image is not None:
            maps[name] = _image_parameter_map(image, name)
    output_dir = ""
    if maps:
        output_dir = bpy.path.abspath(props.output_dir)
        if output_dir.startswith("//") or not output_dir:
            raise ValueError("the texture folder is relative to the .blend, which is not saved yet: "
                             "save it first or choose an absolute folder")
    return SkinSettings(
        **{name: getattr(props, name) for name in PARAMETERS}, method=props.method, accuracy=props.accuracy, maps=maps,
        output_dir=output_dir, file_prefix=material.name, scale_length=scene.unit_settings.scale_length,
        working_space=scene_working_space())


def store_result(material: bpy.types.Material, plan: dict) -> None:
    props = material.spectral_skin
    summary = plan["summary"]
    props.has_result = True
    props.result_albedo = [min(max(c, 0.0), 1.0) for c in summary["albedo"]]
    props.result_radius_mm = summary["radius_mm"]
    props.result_computed = summary["computed"]
    props.result_seconds = summary["seconds"]
    props.result_warning = "; ".join(summary["warnings"])


classes = (SpectralSkinSettings,)

