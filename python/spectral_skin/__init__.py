"""spectral-skin: Donner & Jensen 2006's spectral BSSRDF for human skin.

Four physiological parameters (melanin fraction, eumelanin share, blood fraction, oiliness) in; the model's diffuse
reflectance, radial profiles and the inputs of Blender's Principled BSDF out. Units: millimetres, mm^-1, mm^-2 and
nanometres. The work runs in the compiled core (``spectral_skin._core``) with the GIL released.

MODEL_VERSION: the model's version, raised whenever its numbers change (maps' sidecars and the docs' figures name it).

Functions:
    evaluate: what a material needs (albedo, Subsurface Radius, specular) or any subset of the outputs.
    profile: the radial reflectance profile R(r), RGB or per wavelength.
    parameters: each parameter's name, symbol, label, meaning, unit and range (the core's parameter table).
    parameter_ranges: the allowed range of each parameter.
    accuracy_levels: the named accuracy levels and what each is for.
    surface_models: the surface reflections the specular inputs can stand in for (measured, paper).
    transports: how the totals are computed (adding-doubling, the default, or the paper's diffusion).
    presets: the named parameter sets.
    layered_reflectance: the layered solver alone (exact total, multipole profile), for checks against other solvers.
    maps: Base Color, Subsurface Radius and specular texture maps from per-texel parameter maps (numpy arrays), as a
        read-only :class:`Maps` that writes itself (``Maps.write``: one image or a UDIM tile set).
    map_kinds: the kinds of texture map (name, file, channels, unit, Principled input, colour space, output).
    blender_targets: the Blender versions, engines and subsurface methods the mappings target.
    read_parameter_map: parameter maps read from an EXR, PNG, TIFF or JPEG file by the CLI's rules.
    write_maps: a maps() result (or a dict of images) written as EXRs, atomically, by the CLI's writer.
    shader_table: Base Color and Subsurface Radius tabulated as images for a live node group in Blender.
    write_shader_table: a shader_table() result written as EXRs and a JSON sidecar.
    fit_albedo: the parameters whose model albedo is closest (CIEDE2000) to an RGB colour.
    fit_albedo_map: parameter maps and a per-texel ΔE00 residual from an albedo texture.
    fit_spectrum: model parameters fitted to a measured reflectance spectrum.
    fit_spectra: fit_spectrum for many spectra at once, with one fitter, in parallel, with progress.
    cielab, delta_e00: the core's CIELAB and CIEDE2000 colour difference of linear RGB colours (the fits' own).
    surface_brdf, surface_albedo: the skin surface's reflection (BRDF and directional albedo), the measured two-lobe
        model or the paper's oil layer.
    surface_input_nodes: the surface's oiliness-dependent Principled inputs at nodes to interpolate linearly.

Invalid input raises :class:`SpectralSkinError`, a :class:`ValueError` whose message names the input, its allowed
range and the value received; a file that cannot be read or written raises :class:`SpectralSkinIOError`, an
:class:`OSError` whose message names the file. A result changed on its way out (a negative radial-profile lobe of the model set to 0)
is reported by a :class:`SpectralSkinWarning`, and so is an input read with something ignored (an alpha channel, an
unknown channel).
"""

from ._core import (
    MODEL_VERSION,
    AlbedoMapFit,
    Maps,
    SpectralSkinError,
    SpectralSkinIOError,
    SpectralSkinWarning,
    __version__,
    accuracy_levels,
    blender_targets,
    cielab,
    delta_e00,
    evaluate,
    fit_albedo,
    fit_albedo_map,
    fit_spectra,
    fit_spectrum,
    layered_reflectance,
    map_kinds,
    maps,
    parameter_ranges,
    parameters,
    presets,
    profile,
    read_parameter_map,
    shader_table,
    surface_albedo,
    surface_brdf,
    surface_input_nodes,
    surface_models,
    transports,
    write_maps,
    write_shader_table,
)

__all__ = [
    "MODEL_VERSION",
    "AlbedoMapFit",
    "Maps",
    "SpectralSkinError",
    "SpectralSkinIOError",
    "SpectralSkinWarning",
    "__version__",
    "accuracy_levels",
    "blender_targets",
    "cielab",
    "delta_e00",
    "evaluate",
    "fit_albedo",
    "fit_albedo_map",
    "fit_spectra",
    "fit_spectrum",
    "layered_reflectance",
    "map_kinds",
    "maps",
    "parameter_ranges",
    "parameters",
    "presets",
    "profile",
    "read_parameter_map",
    "shader_table",
    "surface_albedo",
    "surface_brdf",
    "surface_input_nodes",
    "surface_models",
    "transports",
    "write_maps",
    "write_shader_table",
]
