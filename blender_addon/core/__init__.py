"""The add-on's portable part: settings and the material plan, computed by spectral_skin. No bpy imports."""

from .plan import make_plan, subsurface_scale, write_textures
from .settings import (
    ACCURACY_LEVELS,
    DEFAULT_WORKING_SPACE,
    METHODS,
    PARAMETER_INFO,
    PARAMETERS,
    WORKING_SPACES,
    ParameterMap,
    SkinSettings,
    check,
)

__all__ = [
    "ACCURACY_LEVELS",
    "DEFAULT_WORKING_SPACE",
    "METHODS",
    "PARAMETERS",
    "PARAMETER_INFO",
    "WORKING_SPACES",
    "ParameterMap",
    "SkinSettings",
    "check",
    "make_plan",
    "subsurface_scale",
    "write_textures",
]
