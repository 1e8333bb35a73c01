"""Render a saved .blend headless with nothing but ``bpy`` (a render-farm node: neither the Spectral Skin add-on nor
``spectral_skin`` is needed, and this script is not part of the extension).

From Python with bpy (``import bpy`` as a module, or Blender's own Python)::

    python scripts/render_blend.py out.blend --out DIR [--frames 1-3,7] [--samples N] [--resolution 640x480]
        [--engine CYCLES] [--format EXR|PNG] [--seed N] [--allow-missing-textures]

or, imported, :func:`render_frames`. Cycles on the CPU (or the engine named), the .blend's own settings unless
overridden. Animated constant-parameter materials (Apply stores their per-frame values on the material) get those
values at each frame change from the add-on's frame-change handler, loaded from the file
``blender_addon/frame_values.py`` (bpy only; found next to this script, else in the repository's ``blender_addon/``:
copy it along with this script onto a render node), never by importing the add-on. A texture file that is neither
packed nor on disk is an error before anything renders (Blender would render it magenta). Errors exit with status 2
and one line on stderr.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Sequence
from importlib import util
from types import ModuleType

import bpy

_HERE = os.path.dirname(os.path.abspath(__file__))
# Where frame_values.py is looked for, in this order.
FRAME_VALUES_PATHS = (os.path.join(_HERE, "frame_values.py"),
                      os.path.join(os.path.dirname(_HERE), "blender_addon", "frame_values.py"))

# Render output formats: name accepted here -> (Blender file_format, file extension).
FORMATS = {"EXR": ("OPEN_EXR", ".exr"), "OPEN_EXR": ("OPEN_EXR", ".exr"), "PNG": ("PNG", ".png")}
ENGINES = ("CYCLES", "BLENDER_EEVEE", "BLENDER_WORKBENCH")


class RenderError(ValueError):
    """A render job that cannot run as asked (bad frame range, resolution, engine, ...)."""


def frame_values() -> ModuleType:
    """The add-on's frame_values.py (bpy only) loaded from its file under its own module name: the add-on package,
    which needs ``spectral_skin``, is never imported."""
    for path in FRAME_VALUES_PATHS:
        if os.path.isfile(path):
            spec = util.spec_from_file_location("spectral_skin_frame_values", path)
            assert spec is not None and spec.loader is not None
            module = util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return module
    raise FileNotFoundError("frame_values.py (the add-on's frame-change handler) not found at "
                            + " nor ".join(FRAME_VALUES_PATHS))


def _open(blend_path: str) -> None:
    path = os.path.abspath(blend_path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such .blend file: {path}")
    bpy.ops.wm.open_mainfile(filepath=path)


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
                    raise RenderError(f"frame range {part!r} ends before it starts")
                frames.extend(range(first, last + 1))
            else:
                frames.append(int(part))
    except ValueError as error:
        if isinstance(error, RenderError):
            raise
        raise RenderError(f"frames must look like 1-3,7; got {text!r}") from None
    return frames


def _parse_resolution(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise RenderError(f"resolution must look like 640x480; got {text!r}") from None
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
    ``allow_missing_textures``) for textures neither packed nor on disk, RenderError (a ValueError) for bad
    arguments, RuntimeError when Blender fails to render.
    """
    engine = engine.upper()
    if engine == "EEVEE":
        engine = "BLENDER_EEVEE"
    if engine not in ENGINES:
        raise RenderError(f"engine must be one of {', '.join(ENGINES)}; got {engine!r}")
    if file_format is not None and file_format.upper() not in FORMATS:
        raise RenderError(f"file format must be EXR or PNG; got {file_format!r}")
    if samples is not None and int(samples) < 1:
        raise RenderError(f"samples must be >= 1; got {samples}")
    if resolution is not None:
        if len(resolution) != 2 or min(int(v) for v in resolution) < 1:
            raise RenderError(f"resolution must be (width, height) >= 1; got {tuple(resolution)}")
    _open(blend_path)
    # Animated constant materials: their per-frame values are set at each frame change (frame_values.py).
    frame_values().install()
    scene = bpy.context.scene
    if scene.camera is None:
        raise RenderError(f"{blend_path}: scene {scene.name!r} has no camera")
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


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="render_blend.py",
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
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        frames = parse_frames(args.frames) if args.frames else None
        resolution = _parse_resolution(args.resolution) if args.resolution else None
        paths = render_frames(args.blend, args.out, frames=frames, samples=args.samples, resolution=resolution,
                              engine=args.engine, file_format=args.file_format, seed=args.seed,
                              allow_missing_textures=args.allow_missing_textures)
    except (ValueError, OSError, RuntimeError) as error:
        print(f"render_blend: {error}", file=sys.stderr)
        return 2
    for path in paths:
        print(path)
    return 0


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)  # without the interpreter's teardown of bpy (see blender_addon/batch.py)
