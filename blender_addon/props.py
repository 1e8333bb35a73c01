"""The material's Spectral Skin settings (``Material.spectral_skin``) and what the last Apply computed."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from typing import Any

import bpy
import numpy as np
import spectral_skin

from .core import (
    ACCURACY_DESCRIPTIONS,
    ACCURACY_LEVELS,
    DEFAULT_SURFACE,
    DEFAULT_TRANSPORT,
    DEFAULT_WORKING_SPACE,
    EXTENDED_DEFAULTS,
    EXTENDED_PARAMETERS,
    PARAMETER_INFO,
    PARAMETERS,
    SURFACE_DESCRIPTIONS,
    SURFACES,
    TRANSPORT_DESCRIPTIONS,
    TRANSPORTS,
    MaterialPlan,
    ParameterMap,
    SkinSettings,
    read_map_file,
    read_tile_set,
    texture_prefix,
)
from .core import methods as core_methods
from .core import settings as core_settings
from .core.plan import swatch_albedo
from .nodes import scene_target, scene_working_space
from .scene_facts import OVERRIDE_ITEMS

_PRESETS = core_settings.PRESETS
_DEFAULT_PRESET = core_settings.DEFAULT_PRESET


def _preset_tip(p: dict[str, Any]) -> str:
    """A preset's tooltip: its description, the four values and the extended ones it changes."""
    extended = "".join(f", {PARAMETER_INFO[n].label} {p[n]:g}" for n in EXTENDED_PARAMETERS
                       if p[n] != EXTENDED_DEFAULTS[n])
    return (f"{p.get('description', 'Preset')}: C_m {p['melanin']:g}, β_m {p['melanin_blend']:g}, "
            f"C_h {p['hemoglobin']:g}, oiliness {p['oiliness']:g}{extended}")


PRESET_ITEMS = [("CUSTOM", "Custom", "Parameters as set below")] + [
    (name.upper(), name.replace("-", " ").replace("_", " ").title(), _preset_tip(p)) for name, p in _PRESETS.items()
]

# The albedo swatch of a new material: the default preset's, in Blender's default working space.
_DEFAULT_SWATCH = swatch_albedo(_PRESETS[_DEFAULT_PRESET], DEFAULT_WORKING_SPACE)

# What each method does, for the menu's tooltips (the methods themselves, and which this Blender offers, come from the
# core's target table: core/targets.py).
_METHOD_TIPS = {
    "burley": "Christensen-Burley profile: Base Color is exactly the skin's total diffuse reflectance; the fastest to "
    "render (EEVEE renders every method this way)",
    "random_walk": "Volumetric random walk: Base Color and Radius fitted so the walk reproduces the skin's "
    "reflectance; far more samples for the same noise",
    "random_walk_legacy": "The random walk of Blender before 5.2, fitted as such",
    "random_walk_skin": "Blender's random walk variant for skin: fitted so a flat slab has the skin's reflectance",
}

# Labels as Blender's own menu spells them.
_BLENDER_LABELS = {i.identifier: i.name
                   for i in bpy.types.ShaderNodeBsdfPrincipled.bl_rna.properties["subsurface_method"].enum_items}

METHOD_ITEMS = [
    (m["blender_id"], _BLENDER_LABELS.get(m["blender_id"], m["name"]),
     _METHOD_TIPS.get(m["name"], m["name"]) + ("" if m["tested"] else " (not tested in this Blender)"))
    for m in core_methods(bpy.app.version)
]

# The core's accuracy levels and their descriptions (core/settings.py).
ACCURACY_ITEMS = [(key, name.title(), ACCURACY_DESCRIPTIONS[key]) for key, name in ACCURACY_LEVELS.items()]
# The core's transports and their descriptions (core/settings.py), the core's default first.
TRANSPORT_ITEMS = [(key, name.replace("_", "-").title(), TRANSPORT_DESCRIPTIONS[key])
                   for key, name in TRANSPORTS.items()]
# The core's surface models and their descriptions (core/settings.py).
SURFACE_ITEMS = [(key, name.title(), SURFACE_DESCRIPTIONS[key][:1].upper() + SURFACE_DESCRIPTIONS[key][1:])
                 for key, name in SURFACES.items()]


# True while a preset writes the parameters, so that their update does not switch the menu to Custom (nor compute the
# swatch once per parameter).
_setting_preset = False


def update_swatch(props: SpectralSkinSettings) -> None:
    """Compute the albedo swatch of the material's constant values (the four and the extended physiology; one
    ``evaluate(outputs=["albedo"])``, about 0.1 ms) in the blend file's working space and keep it on the material
    (``swatch_value``). Called by the parameters' update callbacks, never while drawing. Values the core refuses
    leave the swatch as it was (Apply reports them)."""
    values = {name: float(getattr(props, name)) for name in (*PARAMETERS, *EXTENDED_PARAMETERS)}
    try:
        props.swatch_value = swatch_albedo(values, scene_working_space(), props.transport)
    except (spectral_skin.SpectralSkinError, ValueError):
        pass


def _apply_preset(self: SpectralSkinSettings, _context: bpy.types.Context) -> None:
    """A preset chosen: its four parameters and its extended physiology set on the sliders."""
    global _setting_preset
    if self.preset == "CUSTOM":
        return
    values = _PRESETS[self.preset.lower()]
    _setting_preset = True
    try:
        for name in (*PARAMETERS, *EXTENDED_PARAMETERS):
            setattr(self, name, values[name])
    finally:
        _setting_preset = False
    update_swatch(self)


def _transport_changed(self: SpectralSkinSettings, _context: bpy.types.Context) -> None:
    """The transport chosen: the swatch follows (the sliders, and so the preset menu, do not change)."""
    update_swatch(self)


def _parameter_edited(self: SpectralSkinSettings, _context: bpy.types.Context) -> None:
    """A slider moved by hand: the parameters are no longer the preset's, so the menu shows Custom; the swatch
    follows."""
    if _setting_preset:
        return
    if self.preset != "CUSTOM":
        self.preset = "CUSTOM"
    update_swatch(self)


def _parameter(name: str) -> bpy.props.FloatProperty:
    """A parameter's slider, from the core's table (range, label, tooltip); the default: the default preset's for the
    four, the paper's for the extended physiology (the core's default)."""
    low, high, label, description = PARAMETER_INFO[name]
    default = EXTENDED_DEFAULTS[name] if name in EXTENDED_DEFAULTS else _PRESETS[_DEFAULT_PRESET][name]
    return bpy.props.FloatProperty(
        name=label, description=description, default=default, min=low, max=high,
        precision=3, step=0.1 if high <= 0.1 else 1, subtype="FACTOR", update=_parameter_edited)


def _swatch(self: SpectralSkinSettings) -> Any:
    return self.swatch_value


def _parameter_map(name: str) -> bpy.props.PointerProperty:
    label = PARAMETER_INFO[name][2]
    return bpy.props.PointerProperty(
        type=bpy.types.Image, name=f"{label} Map",
        description=f"Optional image of {label} per texel (replaces the constant), read as `spectral-skin maps` reads "
        "it: a one-channel or grey RGB EXR holds the value itself; an 8/16-bit greyscale or grey RGB PNG, TIFF or JPEG "
        "maps 0..1 onto the parameter's range")


MODE_ITEMS = [
    ("BAKED", "Baked", "Apply computes Base Color, Subsurface Radius and Specular IOR Level (texture maps from parameter "
     "maps, written to the Texture Folder): for export and render farms; a change needs another Apply"),
    ("LIVE", "Live", "Apply wires the 'Spectral Skin' node group, which computes them in the shader from its inputs "
     "(the constants, the parameter maps, or anything linked, keyed or driven on the group node's sockets): painted "
     "textures and keyframes show without another Apply (docs/shader-table.md)"),
]


class SpectralSkinSettings(bpy.types.PropertyGroup):
    mode: bpy.props.EnumProperty(
        name="Mode", description="How Apply sets up the material", items=MODE_ITEMS, default="BAKED")
    preset: bpy.props.EnumProperty(
        name="Preset", description="Skin type (the Donner & Jensen 2006 sketch's, or fitted to measured skin): sets "
        "the four parameters and the Advanced ones",
        items=PRESET_ITEMS, default=_DEFAULT_PRESET.upper(), update=_apply_preset)
    melanin: _parameter("melanin")
    melanin_blend: _parameter("melanin_blend")
    hemoglobin: _parameter("hemoglobin")
    oiliness: _parameter("oiliness")
    # The extended physiology (core.EXTENDED_PARAMETERS), in the panel's Advanced section: one value per material.
    epidermis_thickness_mm: _parameter("epidermis_thickness_mm")
    baseline_absorption_scale: _parameter("baseline_absorption_scale")
    blood_oxygenation: _parameter("blood_oxygenation")
    # The albedo swatch: kept up to date by the parameters' update callbacks (update_swatch), shown read-only.
    swatch_value: bpy.props.FloatVectorProperty(
        name="Albedo Swatch Value", size=3, subtype="COLOR", default=_DEFAULT_SWATCH, options={"HIDDEN"})
    swatch: bpy.props.FloatVectorProperty(
        name="Albedo", description="The skin's total diffuse reflectance for the constant values above (the four and "
        "the Advanced ones; parameter maps not included), linear RGB of the working space: follows the sliders",
        size=3, subtype="COLOR", get=_swatch)
    melanin_map: _parameter_map("melanin")
    melanin_blend_map: _parameter_map("melanin_blend")
    hemoglobin_map: _parameter_map("hemoglobin")
    oiliness_map: _parameter_map("oiliness")
    params_map: bpy.props.PointerProperty(
        type=bpy.types.Image, name="Parameter Map",
        description="Optional four-channel parameter EXR (channels melanin, melanin_blend, hemoglobin, oiliness, as "
        "`spectral-skin example` writes): gives all four parameters per texel; a parameter's own map replaces its "
        "channel")
    skin_mask: bpy.props.PointerProperty(
        type=bpy.types.Image, name="Skin Mask",
        description="Optional for From Albedo Texture: an image of the Base Color's size (or tile set), white (over "
        "half) where the texture is skin. Only those texels choose the epidermis thickness and the gains and count in "
        "the figures; the others (hair, eyes, a background) are fitted to their nearest skin colour")
    clamp: bpy.props.BoolProperty(
        name="Clamp Out-of-Range Texels",
        description="Clamp NaN, infinite and out-of-range values of the parameter maps into range (and say how many) "
        "instead of refusing the maps", default=False)
    method: bpy.props.EnumProperty(
        name="Subsurface Method",
        description="Subsurface method the material is made for (the methods this Blender has); the mapping also "
        "follows the scene's render engine",
        items=METHOD_ITEMS, default="BURLEY")
    accuracy: bpy.props.EnumProperty(
        name="Accuracy", description="Accuracy of the spectral computation (docs/accuracy-vs-time.md)",
        items=ACCURACY_ITEMS, default="DEFAULT")
    transport: bpy.props.EnumProperty(
        name="Transport", description="How the skin's total reflectance (Base Color, and the scale of the profile "
        "the radius is fitted to) is computed: the core's transports",
        items=TRANSPORT_ITEMS, default=DEFAULT_TRANSPORT, update=_transport_changed)
    surface: bpy.props.EnumProperty(
        name="Surface", description="The surface reflection the specular inputs (Specular IOR Level and Coat) stand "
        "in for: the core's surface models", items=SURFACE_ITEMS, default=DEFAULT_SURFACE)
    output_dir: bpy.props.StringProperty(
        name="Texture Folder",
        description="Folder for the texture maps computed from parameter maps ('//' is the .blend's folder); the "
        "files are named <blend>_<material>_albedo.exr etc., so .blend files sharing a folder keep their own maps",
        default="//skin_maps", subtype="DIR_PATH")
    # Overrides of the scene analysis (core/scene.py): Auto decides from the scene; they survive re-applying.
    override_subsurface: bpy.props.EnumProperty(
        name="Subsurface", description="Subsurface scattering: Auto drops it where no camera can resolve the largest "
        "radius (plain diffuse with the same albedo)", items=OVERRIDE_ITEMS, default="AUTO")
    override_specular: bpy.props.EnumProperty(
        name="Specular", description="The surface's specular reflection (and Coat): Auto drops it (Specular IOR "
        "Level 0, Coat Weight 0, no texture) where nothing reflects: the paper's oil layer with the oiliness zero "
        "everywhere (the measured surface always reflects)", items=OVERRIDE_ITEMS, default="AUTO")
    override_constant_maps: bpy.props.EnumProperty(
        name="Constant Maps", description="Auto (or On) sets an output map of one value as a value; Off writes it "
        "as a texture all the same", items=OVERRIDE_ITEMS, default="AUTO")

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
    result_target: bpy.props.StringProperty(
        name="Target", description="The Blender version and render engine the last Apply computed for")
    result_effects: bpy.props.StringProperty(
        name="Effects", description="The last Apply's decisions as JSON: [{effect, enabled, reason, figures, "
        "override}] (core/scene.py)")
    result_work: bpy.props.StringProperty(
        name="Work", description="What the core computed for the last Apply, as JSON (the plan's work: core/plan.py)")
    result_textures: bpy.props.StringProperty(
        name="Textures", description="The texture files the core wrote for the last Apply, as JSON: {map name: "
        "path} (empty without parameter maps)")


def _image_parameter_maps(image: bpy.types.Image, name: str | None) -> dict[str, ParameterMap]:
    """Parameter maps of a Blender image: ``name``'s map, or the four of a parameter EXR (``name`` None).

    An image from a file is read from that file by the core (``spectral_skin.read_parameter_map``: the CLI's formats
    and rules; Blender reads an EXR channel named ``melanin`` as zeros); a packed one from its packed bytes, the same
    way. Only an image Blender made itself (generated, or painted and not saved) is read from Blender's pixels: the
    first channel of a one-parameter map. Anything else raises ValueError.
    """
    what = f"{PARAMETER_INFO[name][2]} map" if name else "Parameter Map"
    if image.source == "TILED" and (image.packed_file is not None or image.is_dirty):
        raise ValueError(f"{what} {image.name!r} is a UDIM tile set that is packed or painted and not saved: its tiles "
                         "are read from their files, so save them (Image > Save) first")
    if image.source == "TILED":
        # A UDIM tile set: every tile's file, read by the core, stacked into one texture (core.read_tile_set).
        path = bpy.path.abspath(image.filepath, library=image.library)
        if not path or path.startswith("//"):
            raise ValueError(f"{what} {image.name!r}: its file path {image.filepath!r} is relative to a .blend that is "
                             "not saved yet: save the .blend or use an absolute path")
        return read_tile_set(os.path.abspath(path), [tile.number for tile in image.tiles], name)
    if image.source == "FILE" and image.packed_file is None and not image.is_dirty:
        path = bpy.path.abspath(image.filepath, library=image.library)
        if not path or path.startswith("//"):
            raise ValueError(f"{what} {image.name!r}: its file path {image.filepath!r} is relative to a .blend that is "
                             "not saved yet: save the .blend or use an absolute path")
        return read_map_file(os.path.abspath(path), name)
    if image.source == "FILE" and image.packed_file is not None and not image.is_dirty:
        suffix = os.path.splitext(image.filepath)[1] or ".exr"
        with tempfile.TemporaryDirectory(prefix="spectral_skin_") as folder:
            path = os.path.join(folder, bpy.path.clean_name(image.name) + suffix)
            with open(path, "wb") as file:
                file.write(image.packed_file.data)
            maps = read_map_file(path, name)
        return {p: ParameterMap(m.pixels, m.normalized, f"{image.name} (packed)", m.notes) for p, m in maps.items()}
    if image.source == "GENERATED" or image.is_dirty:
        if name is None:
            raise ValueError(f"{what} {image.name!r} is not a file: a four-channel parameter map must be an EXR file")
        width, height = image.size
        if width == 0 or height == 0:
            raise ValueError(f"{what} {image.name!r} has no pixels")
        flat = np.empty(width * height * image.channels, dtype=np.float32)
        image.pixels.foreach_get(flat)
        pixels = flat.reshape(height, width, image.channels)[::-1, :, 0]
        return {name: ParameterMap(pixels=np.ascontiguousarray(pixels), normalized=not image.is_float,
                                   name=image.name)}
    raise ValueError(f"{what} {image.name!r}: a {image.source.lower()} image is not supported; use an image file "
                     "(EXR, PNG, TIFF or JPEG) or a UDIM tile set of them, not packed")


def material_maps(material: bpy.types.Material) -> dict[str, ParameterMap]:
    """The parameter maps set on a material: the four-channel Parameter Map's, then each parameter's own map."""
    props = material.spectral_skin
    maps = {}
    if props.params_map is not None:
        maps.update(_image_parameter_maps(props.params_map, None))
    for name in PARAMETERS:
        image = getattr(props, f"{name}_map")
        if image is not None:
            maps.update(_image_parameter_maps(image, name))
    return maps


def texture_folder(props: SpectralSkinSettings) -> str:
    """The absolute texture folder; ValueError when it would depend on Blender's working folder (an unsaved .blend
    with a '//' folder, or a relative one)."""
    folder = props.output_dir.strip()
    if folder.startswith("//") and not bpy.data.filepath:
        raise ValueError("the .blend is not saved yet, so its texture folder "
                         f"'{folder}' has no place: save the .blend first, or choose an absolute Texture Folder")
    folder = bpy.path.abspath(folder) if folder else ""
    if not folder or not os.path.isabs(folder):
        raise ValueError(f"the Texture Folder must be absolute or start with '//' (the .blend's folder); got {folder!r}")
    return os.path.normpath(folder)


def settings_from_material(material: bpy.types.Material, scene: bpy.types.Scene) -> SkinSettings:
    """The portable settings of a material's properties (raises ValueError for unusable images or folders,
    spectral_skin.SpectralSkinIOError, an OSError, for files the core cannot read)."""
    props = material.spectral_skin
    maps = material_maps(material)
    output_dir = texture_folder(props) if maps and props.mode == "BAKED" else ""
    target = scene_target(scene)
    return SkinSettings(
        **{name: getattr(props, name) for name in (*PARAMETERS, *EXTENDED_PARAMETERS)}, method=props.method, accuracy=props.accuracy,
        transport=props.transport, surface=props.surface,
        clamp=props.clamp, output_dir=output_dir, file_prefix=texture_prefix(bpy.data.filepath, material.name),
        scale_length=scene.unit_settings.scale_length, working_space=scene_working_space(),
        blender=target["blender"], engine=target["engine"], mode=props.mode).with_maps(maps)


def store_result(material: bpy.types.Material, plan: MaterialPlan, files: Mapping[str, str]) -> None:
    """The plan's summary, decisions and work, and the texture ``files`` the core wrote for it, stored on the
    material (what the panel shows and the batch's sidecar records)."""
    props = material.spectral_skin
    summary = plan.summary
    props.has_result = True
    props.result_albedo = [min(max(c, 0.0), 1.0) for c in summary.albedo]
    props.result_radius_mm = summary.radius_mm
    props.result_computed = summary.computed
    props.result_seconds = summary.seconds
    props.result_warning = "; ".join(summary.warnings)
    target = plan.target
    props.result_target = f"Blender {target['blender']}, {target['engine'].upper()}"
    json_plan = plan.as_json()
    props.result_effects = json.dumps(json_plan["effects"], default=float)
    props.result_work = json.dumps(json_plan["work"])
    props.result_textures = json.dumps(dict(files))
    update_swatch(props)  # in the working space of this Apply (the blend file's may have changed since a slider moved)


def stored_work(material: bpy.types.Material) -> dict:
    """What the core computed for the material's last Apply (the plan's ``work``; empty before the first)."""
    text = material.spectral_skin.result_work
    return dict(json.loads(text)) if text else {}


def stored_textures(material: bpy.types.Material) -> dict[str, str]:
    """The texture files the core wrote for the material's last Apply ({map name: path}; empty without maps)."""
    text = material.spectral_skin.result_textures
    return dict(json.loads(text)) if text else {}


def stored_effects(material: bpy.types.Material) -> list[dict]:
    """The decisions of the material's last Apply (empty before the first)."""
    text = material.spectral_skin.result_effects
    return list(json.loads(text)) if text else []


classes = (SpectralSkinSettings,)

