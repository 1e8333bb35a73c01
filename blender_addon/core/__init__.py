"""The add-on's portable part: settings and the material plan, computed by spectral_skin. No bpy imports."""

from .plan import describe_error, make_plan, subsurface_scale, texture_prefix, write_textures
from .settings import (
    ACCURACY_DESCRIPTIONS,
    ACCURACY_LEVELS,
    DEFAULT_WORKING_SPACE,
    EXTENDED_DEFAULTS,
    EXTENDED_PARAMETERS,
    MODES,
    PARAMETER_INFO,
    PARAMETERS,
    WORKING_SPACES,
    ParameterMap,
    SkinSettings,
    check,
    read_map_file,
)
from .targets import engine_name, method_name, methods, version_text

__all__ = [
    "ACCURACY_DESCRIPTIONS",
    "ACCURACY_LEVELS",
    "DEFAULT_WORKING_SPACE",
    "EXTENDED_DEFAULTS",
    "EXTENDED_PARAMETERS",
    "MODES",
    "PARAMETERS",
    "PARAMETER_INFO",
    "WORKING_SPACES",
    "ParameterMap",
    "SkinSettings",
    "check",
    "describe_error",
    "engine_name",
    "make_plan",
    "method_name",
    "methods",
    "read_map_file",
    "subsurface_scale",
    "texture_prefix",
    "version_text",
    "write_textures",
]
