#!/usr/bin/env python3
"""docs/blender-principled.md's table of what the add-on sets on its Principled BSDF (block ``principled inputs``),
read back from Blender: the add-on applied headless to new materials, the default preset with each surface model
(Baked mode), the measured surface again with a parameter map (which inputs take textures) and in Live mode (which
the node group feeds). An input counts as set when Apply changed it from a placeholder put there before (two
placeholders, so that no value the add-on sets can hide), or linked it. Stamped with the model's version
(scripts/lib/doc_stamp.py).

    .venv-blender/5.3/bin/python scripts/reports/principled_inputs.py

Any venv with bpy and OpenImageIO runs it (.venv has bpy 5.0.1); the table names the bpy it was read in.
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
for _folder in (ROOT, ROOT / "scripts" / "lib"):
    sys.path.insert(0, str(_folder))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenImageIO as oiio  # noqa: E402
import spectral_skin  # noqa: E402
from doc_stamp import command, paragraph, write_blocks  # noqa: E402
from doc_stamp import markdown_table as table  # noqa: E402

import blender_addon  # noqa: E402
from blender_addon import nodes as addon_nodes  # noqa: E402
from blender_addon.core.settings import DEFAULT_PRESET  # noqa: E402

DOC = ROOT / "docs" / "blender-principled.md"
BLOCK = "principled inputs"
PYTHON = ".venv-blender/5.3/bin/python"
# Two placeholders for every input before Apply: a value Apply sets equals at most one of them.
PLACEHOLDERS = (0.123457, 0.654321)
# The node's own settings (not sockets) read back the same way.
NODE_SETTINGS = ("subsurface_method", "distribution")
PARAMETERS = ("melanin", "melanin_blend", "hemoglobin", "oiliness")
# Short hand-written notes, by input; the rest of each row is read back from Blender or the core.
NOTES = {
    "Base Color": "the method's Base Color for the target, linear RGB in the scene's working space",
    "Subsurface Weight": "0 where the scene analysis drops subsurface scattering (plain diffuse, same albedo)",
    "Subsurface Radius": "the method's radius for the target, mm",
    "Subsurface Scale": "0.001 / `unit_settings.scale_length`: scene units per mm, so Radius × Scale is in scene units",
    "subsurface_method": "set after the values: switching the method hides sockets",
    "IOR": "the surface's index of refraction",
    "Subsurface IOR": "assumed by the Random Walk (Skin) mapping (`SKIN_SUBSURFACE_IOR`)",
    "Specular IOR Level": "the broad lobe's level",
    "Roughness": "the broad lobe: Roughness² is GGX α",
    "Coat Weight": "the sharp lobe of the measured surface; 0 turns it off",
    "Coat Roughness": "the sharp lobe's roughness",
    "Coat IOR": "the sharp lobe's index of refraction",
}
# The surface inputs that follow the oiliness, by the key of ``surface_input_nodes()``.
OILINESS_INPUTS = {
    "Specular IOR Level": "specular_ior_level",
    "Coat Weight": "coat_weight",
    "Coat Roughness": "coat_roughness",
}


def fmt(value: Any) -> str:
    """A read-back value as the table shows it (colours without their alpha of 1)."""
    if isinstance(value, str):
        return f"`{value}`"
    if isinstance(value, tuple):
        shown = value[:3] if len(value) == 4 and value[3] == 1.0 else value
        return "(" + ", ".join(f"{v:.4g}" for v in shown) + ")"
    return f"{value:.4g}"


def _read(socket: Any) -> Any:
    value = socket.default_value
    return value if isinstance(value, (str, float, int)) else tuple(round(float(v), 7) for v in value)


def _fill(node: Any, placeholder: int) -> dict[str, Any]:
    """Every input of ``node`` (and its settings) set to a placeholder; their values as read back."""
    for socket in node.inputs:
        if not hasattr(socket, "default_value") or isinstance(socket.default_value, str):
            continue
        value = PLACEHOLDERS[placeholder]
        try:
            socket.default_value = (
                value if isinstance(socket.default_value, (float, int)) else (value,) * len(socket.default_value)
            )
        except (TypeError, ValueError):
            pass
    for name in NODE_SETTINGS:
        items = [item.identifier for item in node.bl_rna.properties[name].enum_items]
        setattr(node, name, items[-1] if placeholder == 0 else items[0])
    return _snapshot(node)


def _snapshot(node: Any) -> dict[str, Any]:
    values = {s.name: _read(s) for s in node.inputs if hasattr(s, "default_value")}
    return values | {name: getattr(node, name) for name in NODE_SETTINGS}


def _link(node: Any, name: str) -> str | None:
    """What feeds input ``name``: the add-on's texture (its map kind and colour space) or group output; None."""
    links = [s for s in node.inputs if s.name == name and s.is_linked]
    if not links:
        return None
    link = links[0].links[0]
    source = link.from_node
    if source.type == "TEX_IMAGE":
        return f"`{source.get(addon_nodes.TAG, source.name)}` texture ({source.image.colorspace_settings.name})"
    return f"group output {link.from_socket.name}"


def new_material(name: str) -> tuple[Any, Any]:
    """A material with the add-on's Principled BSDF made in advance (as a re-Apply finds it)."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:  # Blender 4.x; from 5.0 a new material has its node tree
        material.use_nodes = True
    node = material.node_tree.nodes.new("ShaderNodeBsdfPrincipled")
    node[addon_nodes.TAG] = "principled"
    return material, node


def applied(name: str, configure: Callable[[Any], None]) -> dict[str, str]:
    """Apply to a new material set up by ``configure`` (its settings): each input Apply set, read back (its value,
    or what feeds it)."""
    material, node = new_material(name)
    configure(material.spectral_skin)
    found: dict[str, str] = {}
    for placeholder in range(len(PLACEHOLDERS)):
        before = _fill(node, placeholder)
        assert bpy.ops.spectral_skin.apply(material=material.name) == {"FINISHED"}, name
        after = _snapshot(node)
        for key, value in after.items():
            link = _link(node, key) if key not in NODE_SETTINGS else None
            if link or value != before[key]:
                found[key] = link or fmt(value)
    return found


def parameter_map(folder: Path) -> Any:
    """A small four-channel parameter EXR (the oiliness varies, so every surface map is written), as an image."""
    y, x = np.mgrid[0:4, 0:4].astype(np.float32) / 3
    pixels = np.stack([0.01 + 0.1 * x, 0.5 + 0 * x, 0.005 + 0.02 * y, 0.1 + 0.6 * x * y], axis=2)
    path = folder / "params.exr"
    spec = oiio.ImageSpec(4, 4, 4, "float")
    spec.channelnames = PARAMETERS
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(pixels)), out.geterror()
    out.close()
    return bpy.data.images.load(str(path))


def surfaces() -> list[str]:
    """The core's surface models, the default first."""
    models = sorted(spectral_skin.surface_models(), key=lambda m: not m["default"])
    return [m["name"] for m in models]


def setting(name: str, value: Any) -> Callable[[Any], None]:
    """Sets the add-on's setting ``name`` of a material to ``value``."""
    return lambda props: setattr(props, name, value)


def columns(folder: Path) -> dict[str, dict[str, str]]:
    """Each column of the table: its heading and what Apply set, input by input."""
    default = surfaces()[0]
    found = {}
    for surface in surfaces():
        label = f"{surface.title()} surface" + (" (default)" if surface == default else "")
        found[label] = applied(surface, setting("surface", surface.upper()))
    found["with a parameter map"] = applied("maps", setting("params_map", parameter_map(folder)))
    found["Live mode"] = applied("live", setting("mode", "LIVE"))
    return found


def oiliness_note(name: str) -> str:
    """How an oiliness-dependent input runs from oiliness 0 to 1, per surface (``surface_input_nodes``)."""
    key = OILINESS_INPUTS.get(name)
    if key is None:
        return ""
    runs = []
    for surface in surfaces():
        nodes: dict[str, Any] = dict(spectral_skin.surface_input_nodes(surface, blender=bpy.app.version))
        runs.append(f"{surface} {fmt(nodes[key][0])} → {fmt(nodes[key][-1])}")
    return "; oiliness 0 → 1: " + ", ".join(runs)


def beckmann_m(surface: str) -> float:
    """The broad lobe's Beckmann m of ``surface`` (``evaluate(...)["surface"]``)."""
    return spectral_skin.evaluate(preset=DEFAULT_PRESET, outputs=("albedo",), surface=surface)["surface"]["beckmann_m"]


def roughness_note(name: str) -> str:
    """Roughness as the surface's Beckmann m."""
    if name != "Roughness":
        return ""
    ms = ", ".join(f"{s} {fmt(beckmann_m(s))}" for s in surfaces())
    return f"; √m of the surface's Beckmann m ({ms})"


def rows(found: dict[str, dict[str, str]]) -> Iterable[list[str]]:
    """One row per input any column set, in the Principled node's order, its settings first; the columns after the
    surfaces' say "as Baked" where they set what the default surface's column shows."""
    names = list(NODE_SETTINGS) + [s.name for s in new_material("order")[1].inputs]
    read = list(found.values())
    baked = len(surfaces())
    for name in names:
        if not any(name in column for column in read):
            continue
        cells = [column.get(name, "not set") for column in read]
        cells[baked:] = ["as Baked" if cell == cells[0] else cell for cell in cells[baked:]]
        label = "subsurface method" if name == "subsurface_method" else name
        yield [label, *cells, NOTES.get(name, "") + oiliness_note(name) + roughness_note(name)]


def caption(preset: str) -> str:
    text = (
        f"Read back from the add-on's Principled BSDF after Apply in bpy {bpy.app.version_string}: a new material "
        f"in an empty scene (Cycles, unit scale 1), the default preset ({preset}) and settings, Mode Baked, "
        "once per surface model; then the default surface with a parameter map whose oiliness varies (which "
        "inputs take the texture maps) and in Live mode (which the node group feeds; the other inputs as "
        "Baked). Inputs not listed keep the Principled BSDF's defaults."
    )
    return paragraph(text)


def main() -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    blender_addon.register()
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.unit_settings.scale_length = 1.0
    with tempfile.TemporaryDirectory() as tmp:
        bpy.ops.wm.save_as_mainfile(filepath=str(Path(tmp) / "principled.blend"))
        found = columns(Path(tmp))
    props = bpy.data.materials["measured"].spectral_skin
    preset = f"{props.preset.lower()}, oiliness {props.oiliness:.3g}"
    header = ["input", *found, "notes"]
    body = caption(preset) + "\n\n" + table(header, rows(found))
    write_blocks(DOC, command(__file__, python=PYTHON), {BLOCK: body})
    print(body)


if __name__ == "__main__":
    main()
