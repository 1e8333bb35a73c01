"""The add-on's portable part: settings and the material plan, computed by spectral_skin. No bpy imports."""

from .plan import make_plan, subsurface_scale, write_textures
from .settings import METHODS, PARAMETER_INFO, PARAMETERS, ParameterMap, SkinSettings, check

__all__ = [
    "METHODS",
    "PARAMETERS",
    "PARAMETER_INFO",
    "ParameterMap",
    "SkinSettings",
    "check",
    "make_plan",
    "subsurface_scale",
    "write_textures",
]
