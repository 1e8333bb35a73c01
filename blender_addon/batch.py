"""Headless batch apply, without the UI: apply Spectral Skin to named materials of a .blend and save it.

From Python with bpy (``import bpy`` as a module, or Blender's own Python)::

    from blender_addon.batch import apply_to_materials
    from blender_addon.core import SkinSettings
    apply_to_materials("in.blend", ["Skin"], SkinSettings.from_preset("asian"), "out.blend")

or as a script::

    python blender_addon/batch.py apply in.blend out.blend --material Skin --preset asian [--melanin-map m.exr]
        [--params-map face.exr] [--epidermis-thickness-mm 0.1] [--clamp] [--pack]

(one flag per parameter of the core's table: the four, each with a ``-map``, and the extended physiology, one value
per material; a flag overrides the preset's value).

(``batch.py in.blend out.blend --material ...`` without a subcommand still means ``apply``.)

Apply is the operator's own path (apply.apply_skins): the scene decides which effects each material needs
(blender_addon/core/scene.py: subsurface scattering no camera can resolve is dropped, zero oiliness writes no specular
map, ...); the decisions are printed, one line each, and stored on the material. A parameter keyframed or driven on a
material's Spectral Skin settings follows that animation (the value given here for it is not used): a
constant-parameter material gets its values per frame as F-curves (frame_values.py), which plain Blender renders.
Every material's plan is computed, then every map written, before any material changes; on an error nothing is
saved. The saved .blend refers to the textures by paths relative to itself, or packs them with ``pack=True``.

Rendering the saved .blend needs only bpy, not the add-on nor ``spectral_skin``: ``scripts/tools/render_blend.py``,
which is not part of the extension.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

import bpy

_HERE = os.path.dirname(os.path.abspath(__file__))


def _addon_module(name: str = "") -> Any:
    """The add-on package (or one of its modules), imported only when needed: it requires ``spectral_skin``.

    Run as a script, the add-on's parent folder goes on sys.path and the package is imported by its folder name.
    """
    package = __package__
    if not package:
        parent = os.path.dirname(_HERE)
        if parent not in sys.path:
            sys.path.insert(0, parent)
        package = os.path.basename(_HERE)
    return importlib.import_module(f"{package}.{name}" if name else package)


def _ensure_registered() -> None:
    if not hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply"):
        _addon_module().register()


def _open(blend_path: str) -> None:
    path = os.path.abspath(blend_path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such .blend file: {path}")
    bpy.ops.wm.open_mainfile(filepath=path)


def apply_to_materials(blend_path: str, material_names: list[str], settings: Any, out_blend: str,
                       pack: bool = False) -> dict[str, dict[str, Any]]:
    """Open ``blend_path``, apply ``settings`` (a core.SkinSettings) to each named material, save as ``out_blend``;
    returns the plans.

    ``settings.output_dir`` (used only with maps) may start with ``//``: relative to ``blend_path``'s folder; empty
    means ``//skin_maps``. ``settings.file_prefix`` is replaced by ``<blend_path's name>_<material name>`` and
    ``settings.scale_length`` by the scene's unit scale. Raises spectral_skin.SpectralSkinError / ValueError / OSError; nothing is saved then.
    """
    nodes = _addon_module("nodes")
    apply = _addon_module("apply")
    core = _addon_module("core")
    analysis = _addon_module("core.scene")
    _open(blend_path)
    _ensure_registered()
    missing = [name for name in material_names if name not in bpy.data.materials]
    if missing:
        raise ValueError(f"no material named {', '.join(map(repr, missing))} in {blend_path}")
    scene = bpy.context.scene
    output_dir = bpy.path.abspath(settings.output_dir or "//skin_maps")
    items = [(bpy.data.materials[name],
              settings.replace(file_prefix=core.texture_prefix(blend_path, name), output_dir=output_dir,
                               scale_length=scene.unit_settings.scale_length)) for name in material_names]
    plans = dict(zip(material_names, apply.apply_skins(items, scene), strict=True))
    for name, plan in plans.items():
        for line in analysis.describe(plan.effects):
            print(f"spectral-skin batch: {name}: {line}", flush=True)
        if pack:
            for node in nodes.tagged_nodes(bpy.data.materials[name].node_tree):
                if node.type == "TEX_IMAGE" and node.image is not None:
                    node.image.pack()
    out_blend = os.path.abspath(out_blend)
    os.makedirs(os.path.dirname(out_blend), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out_blend, relative_remap=True)
    stored_textures = _addon_module("props").stored_textures
    _write_sidecar(out_blend, {name: {**plan.as_json(), "textures": stored_textures(bpy.data.materials[name])}
                               for name, plan in plans.items()})
    return plans


def sidecar_path(out_blend: str) -> str:
    """The JSON written next to the saved .blend: ``<out>.spectral_skin.json``."""
    return os.path.splitext(os.path.abspath(out_blend))[0] + ".spectral_skin.json"


def _write_sidecar(out_blend: str, plans: dict[str, dict[str, Any]]) -> None:
    """Per material (``plans``: each plan's JSON, with the texture files the core wrote): the target, the transport
    and the extended physiology computed with (``transport``, ``extended``), the decisions (``effects``), the core's
    work (``work``: what was computed, the counts the operator stores on the material), the texture files
    (``textures``) and the per-frame values of an animated constant material (``animation``, or null), as JSON next
    to the .blend."""
    import json

    keys = ("target", "method", "transport", "extended", "effects", "work", "textures", "animation")
    content = {name: {key: value for key, value in plan.items() if key in keys} for name, plan in plans.items()}
    path = sidecar_path(out_blend)
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w", encoding="utf-8") as file:
        json.dump(content, file, indent=2, default=float)
    os.replace(tmp, path)


def _read_map(path: str, name: str | None) -> Any:
    """A parameter file read by the core (the CLI's rules): ``name``'s map, or the four-channel file (None)."""
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{name or 'parameter'} map: no such file: {path}")
    return _addon_module("core").read_map_file(path, name)


# ---------------------------------------------------------------------------------------------------------------
# Command line

def _apply_main(argv: list[str]) -> int:
    import argparse

    import spectral_skin

    core = _addon_module("core")
    parser = argparse.ArgumentParser(prog="batch.py apply",
                                     description="Apply Spectral Skin to materials of a .blend and save it.")
    parser.add_argument("blend")
    parser.add_argument("out_blend")
    parser.add_argument("--material", action="append", required=True, help="material name (repeatable)")
    parser.add_argument("--preset", default=core.DEFAULT_PRESET,
                        help=f"the values the material starts from: {', '.join(core.PRESETS)} (default {core.DEFAULT_PRESET})")
    for name in core.PARAMETERS:
        flag = name.replace("_", "-")
        parser.add_argument(f"--{flag}", type=float, help=f"{name} (overrides the preset)")
        parser.add_argument(f"--{flag}-map", help=f"image of {name} per texel")
    for name in core.EXTENDED_PARAMETERS:
        low, high, label, _ = core.PARAMETER_INFO[name]
        parser.add_argument(f"--{name.replace('_', '-')}", type=float,
                            help=f"{label}, {low:g} to {high:g}, one value per material (overrides the preset; "
                            f"default {core.EXTENDED_DEFAULTS[name]:g}, the paper's)")
    parser.add_argument("--params-map", help="four-channel parameter EXR (channels melanin, melanin_blend, hemoglobin, "
                        "oiliness); a parameter's own map replaces its channel")
    parser.add_argument("--clamp", action="store_true", help="clamp out-of-range texels of the maps into range")
    parser.add_argument("--method", choices=[m["blender_id"] for m in core.methods(bpy.app.version)], default="BURLEY",
                        help="subsurface method (those of this Blender); the mapping follows the scene's engine")
    parser.add_argument("--accuracy", choices=list(core.ACCURACY_LEVELS), default="DEFAULT",
                        help="accuracy level of the spectral computation")
    parser.add_argument("--transport", choices=list(core.TRANSPORTS), default=core.DEFAULT_TRANSPORT,
                        help="how the totals are computed: " + "; ".join(
                            f"{key}: {text}" for key, text in core.TRANSPORT_DESCRIPTIONS.items()))
    parser.add_argument("--surface", choices=list(core.SURFACES), default=core.DEFAULT_SURFACE,
                        help="the surface reflection the specular inputs stand in for: " + "; ".join(
                            f"{key}: {text}" for key, text in core.SURFACE_DESCRIPTIONS.items()))
    parser.add_argument("--out-dir", default="", help="texture folder ('//' = next to the input .blend)")
    parser.add_argument("--pack", action="store_true", help="pack the textures into the .blend")
    args = parser.parse_args(argv)
    try:
        overrides = {n: getattr(args, n) for n in (*core.PARAMETERS, *core.EXTENDED_PARAMETERS)
                     if getattr(args, n) is not None}
        settings = core.SkinSettings.from_preset(args.preset, **overrides).replace(
            method=args.method, accuracy=args.accuracy, transport=args.transport, surface=args.surface,
            output_dir=args.out_dir,
            clamp=args.clamp)
        maps = _read_map(args.params_map, None) if args.params_map else {}
        for n in core.PARAMETERS:
            if getattr(args, f"{n}_map"):
                maps.update(_read_map(getattr(args, f"{n}_map"), n))
        settings = settings.with_maps(maps)
        apply_to_materials(args.blend, args.material, settings, args.out_blend, pack=args.pack)
    except (spectral_skin.SpectralSkinError, ValueError, OSError) as error:
        print(f"spectral-skin batch: {core.describe_error(error)}", file=sys.stderr)
        return 2
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "render":
        print("spectral-skin batch: rendering moved out of the add-on: python scripts/tools/render_blend.py BLEND "
              "--out DIR (needs only bpy)", file=sys.stderr)
        return 2
    if argv and argv[0] == "apply":
        return _apply_main(argv[1:])
    if not argv or argv[0] in {"-h", "--help"}:
        print(__doc__)
        return 0 if argv else 2
    return _apply_main(argv)  # the original form: batch.py in.blend out.blend --material ...


if __name__ == "__main__":
    status = main()
    # Everything is written (and renamed into place) by now. bpy 4.2 can crash while the interpreter tears the module
    # down after a save (seen: SIGSEGV after "Saved out.blend"), which would turn a finished job into a failure: end
    # the process here, after flushing, without that teardown.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
