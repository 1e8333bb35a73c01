"""Colour spaces, named once (no bpy): the scene-linear working spaces (the core's ``working_space`` names, which are
also Blender's OCIO names), the data space of every texture that is not a colour, and the 8/16-bit image spaces From
Albedo Texture reads (whose one sRGB decoding is core/albedo.py's ``srgb_to_linear``: the core decodes sRGB only
inside its file reader, src/maps/io/read.rs, which Blender's in-memory pixels never reach)."""

from __future__ import annotations

# Blender 5.0's scene-linear working spaces (``bpy.data.colorspace.working_space``), which are also the names of
# their OCIO colour spaces and the core's ``working_space`` names. Blender before 5.0 has only Linear Rec.709.
LINEAR_REC709 = "Linear Rec.709"
WORKING_SPACES = (LINEAR_REC709, "Linear Rec.2020", "ACEScg")
DEFAULT_WORKING_SPACE = LINEAR_REC709
# Blender's colour space of values that are data, not colour (radii, levels, parameter maps, shader tables).
NON_COLOR = "Non-Color"
# Blender's names of the image colour spaces whose 8/16-bit values are sRGB-encoded Rec.709.
SRGB_NAMES = ("sRGB",)
# Blender's names of the linear colour spaces the core knows (Blender 4.x calls Linear Rec.709 "Linear").
LINEAR_NAMES = {**{name: name for name in WORKING_SPACES}, "Linear": LINEAR_REC709}
