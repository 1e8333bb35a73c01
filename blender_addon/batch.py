"""Headless batch use, without the UI: apply Spectral Skin to named materials of a .blend and save it, and render a
saved .blend (a render-farm node needs only ``bpy``, not the add-on nor ``spectral_skin``).

From Python with bpy (``import bpy`` as a module, or Blender's own Python)::

    from blender_addon.batch import apply_to_materials, render_frames
    from blender_addon.core import SkinSettings
    apply_to_materials("in.blend", ["Skin"], SkinSettings.from_preset("asian"), "out.blend")
    render_frames("out.blend", "renders", frames=[1, 2], samples=64)

or as a script::

    python blender_addon/batch.py apply in.blend out.blend --material Skin --preset asian [--melanin-map m.exr]
        [--params-map face.exr] [--clamp] [--pack]
    python blender_addon/batch.py render in.blend --out DIR [--frames 1-3,7] [--samples N] [--resolution 640x480]

(``batch.py in.blend out.blend --material ...`` without a subcommand still means ``apply``.)

Apply: the scene decides which effects each material needs (blender_addon/core/scene.py: subsurface scattering
no camera can resolve is dropped, zero oiliness writes no specular map, ...), as the operator does; the decisions
are printed, one line each, and stored on the material. A parameter keyframed or driven on a material's Spectral
Skin settings follows that animation (the value given here for it is not used): a constant-parameter material gets
its values per frame, which the render sets at each frame change (frame_values.py). Every material's plan is computed (and its maps written) before any material changes; on an error nothing
is saved. The saved .blend refers to the textures by paths relative to itself, or packs them with ``pack=True``.

Render: Cycles on the CPU (or the engine named), the .blend's own settings unless overridden; the frame-change
handler of animated materials is installed (from frame_values.py, bpy only); a texture file that
is neither packed nor on disk is an error before anything renders (Blender would render it magenta). Errors exit
with status 2 and one line on stderr.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Iterable, Sequence
from typing import Any

import bpy

_HERE = os.path.dirname(os.path.abspath(__file__))

# Render output formats: name accepted here -> (Blender file_format, file extension).
FORMATS = {"EXR": ("OPEN_EXR", ".exr"), "OPEN_EXR": ("OPEN_EXR", ".exr"), "PNG": ("PNG", ".png")}
ENGINES = ("CYCLES", "BLENDER_EEVEE", "BLENDER_WORKBENCH")


class BatchError(ValueError):
    """A batch job that cannot run as asked (missing file, bad frame range, missing textures, ...)."""


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


def _frame_values() -> Any:
    """frame_values.py (bpy only): from the package when batch.py is part of it, else loaded from its file, so that a
    render node needs neither the add-on registered nor ``spectral_skin``."""
    if __package__:
        return importlib.import_module(f"{__package__}.frame_values")
    from importlib import util

    spec = util.spec_from_file_location("spectral_skin_frame_values", os.path.join(_HERE, "frame_values.py"))
    assert spec is not None and spec.loader is not None
    module = util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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
    props = _addon_module("props")
    core = _addon_module("core")
    _open(blend_path)
    _ensure_registered()
    missing = [name for name in material_names if name not in bpy.data.materials]
    if missing:
        raise ValueError(f"no material named {', '.join(map(repr, missing))} in {blend_path}")
    scene = bpy.context.scene
    output_dir = bpy.path.abspath(settings.output_dir or "//skin_maps")
    plans = {}
    scene_facts = _addon_module("scene_facts")
    analysis = _addon_module("core.scene")
    for name in material_names:
        material_settings = settings.replace(
            file_prefix=core.texture_prefix(blend_path, name), output_dir=output_dir, scale_length=scene.unit_settings.scale_length,
            working_space=nodes.scene_working_space(), **nodes.scene_target(scene))
        # What the scene calls for (the operator's path: scene_facts.scene_plan); the decisions go to the log.
        plans[name] = scene_facts.scene_plan(bpy.data.materials[name], scene, material_settings)
        for line in analysis.describe(plans[name]["effects"]):
            print(f"spectral-skin batch: {name}: {line}", flush=True)
    for plan in plans.values():
        core.write_textures(plan)
    for name, plan in plans.items():
        material = bpy.data.materials[name]
        nodes.apply_plan(material, plan)
        props.store_result(material, plan)
        if pack:
            for node in nodes.tagged_nodes(material.node_tree):
                if node.type == "TEX_IMAGE" and node.image is not None:
                    node.image.pack()
    out_blend = os.path.abspath(out_blend)
    os.makedirs(os.path.dirname(out_blend), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=out_blend, relative_remap=True)
    _write_sidecar(out_blend, plans)
    return plans


def sidecar_path(out_blend: str) -> str:
    """The JSON written next to the saved .blend: ``<out>.spectral_skin.json``."""
    return os.path.splitext(os.path.abspath(out_blend))[0] + ".spectral_skin.json"


def _write_sidecar(out_blend: str, plans: dict[str, dict[str, Any]]) -> None:
    """Per material: the target, the decisions (``effects``), the texture files and the per-frame values of an
    animated constant material (``animation``, or null), as JSON next to the .blend."""
    import json

    content = {name: {"target": plan["target"], "method": plan["method"], "effects": plan["effects"],
                      "textures": plan["textures"], "animation": plan.get("animation")}
               for name, plan in plans.items()}
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
# Rendering: needs bpy only (no add-on, no spectral_skin), as on a render-farm node.

def missing_images() -> list[str]:
    """Images in use whose file is neither packed nor on disk: ``"name (path)"`` for each."""
    missing = []
    for image in bpy.data.images:
        if image.users == 0 or image.source not in {"FILE", "SEQUENCE", "TILED"} or image.packed_file is not None:
            continue
        if image.source == "FILE" and not os.path.isfile(bpy.path.abspath(image.filepath, library=image.library)):
            missing.append(f"{image.name} ({image.filepath})")
    return missing


def parse_frames(text: str) -> list[int]:
    """``"1-3,7"`` -> [1, 2, 3, 7]."""
    frames: list[int] = []
    try:
        for part in text.split(","):
            part = part.strip()
            if "-" in part[1:]:
                cut = part.index("-", 1)
                first, last = int(part[:cut]), int(part[cut + 1:])
                if last < first:
                    raise BatchError(f"frame range {part!r} ends before it starts")
                frames.extend(range(first, last + 1))
            else:
                frames.append(int(part))
    except ValueError as error:
        if isinstance(error, BatchError):
            raise
        raise BatchError(f"frames must look like 1-3,7; got {text!r}") from None
    return frames


def _parse_resolution(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise BatchError(f"resolution must look like 640x480; got {text!r}") from None
    return width, height


def render_frames(blend_path: str, out_dir: str, frames: Iterable[int] | None = None, samples: int | None = None,
                  resolution: Sequence[int] | None = None, engine: str = "CYCLES", file_format: str | None = None,
                  seed: int | None = None, allow_missing_textures: bool = False) -> list[str]:
    """Open ``blend_path`` and render each frame to ``out_dir``; returns the written paths (in frame order).

    - ``frames``: frame numbers; None renders the scene's current frame only.
    - ``samples``: render samples (Cycles ``samples``, EEVEE ``taa_render_samples``); None keeps the .blend's.
    - ``resolution``: (width, height) in pixels at 100 %; None keeps the .blend's.
    - ``engine``: "CYCLES" (always on the CPU), "BLENDER_EEVEE" or "BLENDER_WORKBENCH".
    - ``file_format``: "EXR" (32-bit float, scene-linear) or "PNG" (display-referred, through the view transform);
      None keeps the .blend's when it is one of those, else EXR.
    - ``seed``: Cycles seed (and no animated seed); None keeps the .blend's.

    Files are named ``<blend name>_<frame:04d>.exr|png``. Raises FileNotFoundError for a missing .blend or (unless
    ``allow_missing_textures``) for textures neither packed nor on disk, BatchError (a ValueError) for bad
    arguments, RuntimeError when Blender fails to render.
    """
    engine = engine.upper()
    if engine == "EEVEE":
        engine = "BLENDER_EEVEE"
    if engine not in ENGINES:
        raise BatchError(f"engine must be one of {', '.join(ENGINES)}; got {engine!r}")
    if file_format is not None and file_format.upper() not in FORMATS:
        raise BatchError(f"file format must be EXR or PNG; got {file_format!r}")
    if samples is not None and int(samples) < 1:
        raise BatchError(f"samples must be >= 1; got {samples}")
    if resolution is not None:
        if len(resolution) != 2 or min(int(v) for v in resolution) < 1:
            raise BatchError(f"resolution must be (width, height) >= 1; got {tuple(resolution)}")
    _open(blend_path)
    # Animated constant materials: their per-frame values are set at each frame change (frame_values.py).
    _frame_values().install()
    scene = bpy.context.scene
    if scene.camera is None:
        raise BatchError(f"{blend_path}: scene {scene.name!r} has no camera")
    if not allow_missing_textures:
        missing = missing_images()
        if missing:
            raise FileNotFoundError(f"{blend_path}: {len(missing)} texture(s) neither packed nor found on disk: "
                                    + ", ".join(missing))
    render = scene.render
    render.engine = engine
    if engine == "CYCLES":
        scene.cycles.device = "CPU"
        if samples is not None:
            scene.cycles.samples = int(samples)
        if seed is not None:
            scene.cycles.seed = int(seed)
            scene.cycles.use_animated_seed = False
    elif samples is not None and engine == "BLENDER_EEVEE":
        scene.eevee.taa_render_samples = int(samples)
    if resolution is not None:
        render.resolution_x, render.resolution_y = (int(v) for v in resolution)
        render.resolution_percentage = 100
    settings = render.image_settings
    if file_format is None:
        file_format = settings.file_format if settings.file_format in {"OPEN_EXR", "PNG"} else "EXR"
    blender_format, extension = FORMATS[file_format.upper()]
    if settings.file_format != blender_format:
        settings.file_format = blender_format
        if blender_format == "OPEN_EXR":
            settings.color_depth = "32"
    render.use_file_extension = False

    out_dir = os.path.abspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.splitext(os.path.basename(blend_path))[0]
    frame_list = [scene.frame_current] if frames is None else [int(f) for f in frames]
    paths = []
    for frame in frame_list:
        scene.frame_set(frame)
        path = os.path.join(out_dir, f"{stem}_{frame:04d}{extension}")
        render.filepath = path
        bpy.ops.render.render(write_still=True, scene=scene.name)
        if not os.path.isfile(path):
            raise RuntimeError(f"Blender did not write {path} (frame {frame})")
        paths.append(path)
    return paths


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
    parser.add_argument("--preset", default="caucasian")
    for name in core.PARAMETERS:
        flag = name.replace("_", "-")
        parser.add_argument(f"--{flag}", type=float, help=f"{name} (overrides the preset)")
        parser.add_argument(f"--{flag}-map", help=f"image of {name} per texel")
    parser.add_argument("--params-map", help="four-channel parameter EXR (channels melanin, melanin_blend, hemoglobin, "
                        "oiliness); a parameter's own map replaces its channel")
    parser.add_argument("--clamp", action="store_true", help="clamp out-of-range texels of the maps into range")
    parser.add_argument("--method", choices=[m["blender_id"] for m in core.methods(bpy.app.version)], default="BURLEY",
                        help="subsurface method (those of this Blender); the mapping follows the scene's engine")
    parser.add_argument("--accuracy", choices=list(core.ACCURACY_LEVELS), default="DEFAULT",
                        help="accuracy level of the spectral computation")
    parser.add_argument("--out-dir", default="", help="texture folder ('//' = next to the input .blend)")
    parser.add_argument("--pack", action="store_true", help="pack the textures into the .blend")
    args = parser.parse_args(argv)
    try:
        overrides = {n: getattr(args, n) for n in core.PARAMETERS if getattr(args, n) is not None}
        settings = core.SkinSettings.from_preset(args.preset, **overrides).replace(
            method=args.method, accuracy=args.accuracy, output_dir=args.out_dir, clamp=args.clamp)
        maps = _read_map(args.params_map, None) if args.params_map else {}
        for n in core.PARAMETERS:
            if getattr(args, f"{n}_map"):
                maps.update(_read_map(getattr(args, f"{n}_map"), n))
        settings = settings.replace(maps=maps)
        apply_to_materials(args.blend, args.material, settings, args.out_blend, pack=args.pack)
    except (spectral_skin.SpectralSkinError, ValueError, OSError) as error:
        print(f"spectral-skin batch: {core.describe_error(error)}", file=sys.stderr)
        return 2
    return 0


def _render_main(argv: list[str]) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="batch.py render",
                                     description="Render a saved .blend headless (Cycles CPU by default).")
    parser.add_argument("blend")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--frames", help="frames, e.g. 1-3,7 (default: the scene's current frame)")
    parser.add_argument("--samples", type=int, help="render samples (default: the .blend's)")
    parser.add_argument("--resolution", help="WIDTHxHEIGHT in pixels (default: the .blend's)")
    parser.add_argument("--engine", default="CYCLES", help="CYCLES (CPU), BLENDER_EEVEE or BLENDER_WORKBENCH")
    parser.add_argument("--format", dest="file_format", choices=["EXR", "PNG"], type=str.upper,
                        help="output format (default: the .blend's if EXR or PNG, else EXR)")
    parser.add_argument("--seed", type=int, help="Cycles seed")
    parser.add_argument("--allow-missing-textures", action="store_true",
                        help="render even if texture files are missing (they render magenta)")
    args = parser.parse_args(argv)
    try:
        frames = parse_frames(args.frames) if args.frames else None
        resolution = _parse_resolution(args.resolution) if args.resolution else None
        paths = render_frames(args.blend, args.out, frames=frames, samples=args.samples, resolution=resolution,
                              engine=args.engine, file_format=args.file_format, seed=args.seed,
                              allow_missing_textures=args.allow_missing_textures)
    except (ValueError, OSError, RuntimeError) as error:
        print(f"spectral-skin batch: {error}", file=sys.stderr)
        return 2
    for path in paths:
        print(path)
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "render":
        return _render_main(argv[1:])
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
