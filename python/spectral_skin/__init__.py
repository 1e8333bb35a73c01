"""spectral-skin: Donner & Jensen 2006's spectral BSSRDF for human skin.

Four physiological parameters (melanin fraction, eumelanin share, blood fraction, oiliness) in; the model's diffuse
reflectance, radial profiles and the inputs of Blender's Principled BSDF out. Units: millimetres, mm^-1, mm^-2 and
nanometres. The work runs in the compiled core (``spectral_skin._core``) with the GIL released.

Functions:
    evaluate: what a material needs (albedo, Subsurface Radius, specular) or any subset of the outputs.
    profile: the radial reflectance profile R(r), RGB or per wavelength.
    parameter_ranges: the allowed range of each parameter.
    presets: the named parameter sets.
    layered_reflectance: the layered diffusion solver alone, for checks against other solvers.
    maps: Base Color, Subsurface Radius and specular texture maps from per-texel parameter maps (numpy arrays).
    blender_targets: the Blender versions, engines and subsurface methods the mappings target.

Invalid input raises :class:`SpectralSkinError`, a :class:`ValueError` whose message names the input, its allowed
range and the value received.
"""

from ._core import (
    SpectralSkinError,
    __version__,
    blender_targets,
    evaluate,
    layered_reflectance,
    maps,
    parameter_ranges,
    presets,
    profile,
)

__all__ = [
    "SpectralSkinError",
    "__version__",
    "blender_targets",
    "evaluate",
    "layered_reflectance",
    "maps",
    "parameter_ranges",
    "presets",
    "profile",
]
