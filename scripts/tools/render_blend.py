"""Render a saved .blend headless with nothing but ``bpy`` (a render-farm node: neither the Spectral Skin add-on nor
``spectral_skin`` is needed, and this script is not part of the extension).

From Python with bpy (``import bpy`` as a module, or Blender's own Python)::

    python scripts/tools/render_blend.py out.blend --out DIR [--frames 1-3,7] [--samples N] [--resolution 640x480]
        [--engine CYCLES] [--format EXR|PNG] [--seed N] [--allow-missing-textures]

or, imported, :func:`render_frames`. Cycles always on the CPU; the .blend's own settings unless overridden. The
engine is the one Apply computed the skin materials for (stored on them, and the scene's engine at Apply) unless
``--engine`` names another; which one renders, and why, is said on stderr, with a warning when the materials were
computed for another engine. Animated skin materials need nothing here: Apply writes their per-frame values as
F-curves (blender_addon/frame_values.py), which plain Blender evaluates; a material with per-frame values from an
older Apply (a JSON property, no F-curves) is reported: apply again. A texture file that is neither packed nor on
disk is an error before anything renders (Blender would render it magenta). Errors exit with status 2 and one line
on stderr.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Sequence

import bpy

# Render output formats: name accepted here -> (Blender file_format, file extension).
FORMATS = {"EXR": ("OPEN_EXR", ".exr"), "OPEN_EXR": ("OPEN_EXR", ".exr"), "PNG": ("PNG", ".png")}
ENGINES = ("CYCLES", "BLENDER_EEVEE", "BLENDER_WORKBENCH")


class RenderError(ValueError):
    """A render job that cannot run as asked (bad frame range, resolution, engine, ...)."""


# What Apply stores on a material (the add-on's settings, an ID property group readable without the add-on):
# the target it computed for, "Blender 5.3, CYCLES" (props.store_result); and the per-frame values of an Apply from
# before they became F-curves.
SETTINGS_PROPERTY, TARGET_KEY, LEGACY_FRAMES = "spectral_skin", "result_target", "spectral_skin_frames"
# The engine word of a stored target -> the render engine.
TARGET_ENGINES = {"CYCLES": "CYCLES", "EEVEE": "BLENDER_EEVEE"}


def stored_engines() -> dict[str, str]:
    """{material name: render engine} of every material Apply set up, from the target stored on it."""
    found = {}
    for material in bpy.data.materials:
        # Blender 5.0+ keeps properties an add-on registered apart from custom properties (system properties).
        system = material.bl_system_properties_get() if hasattr(material, "bl_system_properties_get") else None
        group = (system or material).get(SETTINGS_PROPERTY)
        target = group.get(TARGET_KEY) if hasattr(group, "get") else None
        if isinstance(target, str) and "," in target:
            word = target.rsplit(",", 1)[1].strip().upper()
            if word in TARGET_ENGINES:
                found[material.name] = TARGET_ENGINES[word]
    return found


def _kind(engine: str) -> str:
    """CYCLES, BLENDER_EEVEE (also for 4.2-4.5's BLENDER_EEVEE_NEXT) or the engine itself."""
    return "BLENDER_EEVEE" if engine.startswith("BLENDER_EEVEE") else engine


def engine_id(engine: str) -> str:
    """The running Blender's identifier of an engine: EEVEE is BLENDER_EEVEE_NEXT in Blender 4.2-4.5."""
    if _kind(engine) == "BLENDER_EEVEE":
        return "BLENDER_EEVEE_NEXT" if bpy.app.version < (5, 0, 0) else "BLENDER_EEVEE"
    return engine


def choose_engine(asked: str | None, scene_engine: str, stored: dict[str, str]) -> tuple[str, str]:
    """The engine to render with (CYCLES, BLENDER_EEVEE or BLENDER_WORKBENCH; :func:`engine_id` names it for the
    running Blender) and the sentence that says why: ``asked`` if given, else the one the skin materials were computed
    for (``stored``: :func:`stored_engines`), else the scene's; with a warning naming each material computed for
    another engine than the one that renders."""
    kinds = sorted(set(stored.values()))
    if asked is not None:
        engine, why = _kind(asked), "as asked (--engine)"
    elif len(kinds) == 1:
        engine, why = kinds[0], "the engine Apply computed the skin materials for"
    else:
        engine, why = _kind(scene_engine), "the .blend's scene engine"
    message = f"render_blend: rendering with {engine}, {why}"
    others = sorted(name for name, kind in stored.items() if kind != engine)
    if others:
        message += (f"; warning: {', '.join(others)} {'was' if len(others) == 1 else 'were'} computed for "
                    f"{' and '.join(k for k in kinds if k != engine)}, which renders it differently: apply again "
                    "for this engine, or render with the one it was computed for")
    return engine, message


def legacy_frame_values() -> list[str]:
    """Materials with per-frame values of an older Apply (a JSON property, no F-curves): not animated here."""
    return sorted(m.name for m in bpy.data.materials if LEGACY_FRAMES in m)


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
                  resolution: Sequence[int] | None = None, engine: str | None = None, file_format: str | None = None,
                  seed: int | None = None, allow_missing_textures: bool = False) -> list[str]:
    """Open ``blend_path`` and render each frame to ``out_dir``; returns the written paths (in frame order).

    - ``frames``: frame numbers; None renders the scene's current frame only.
    - ``samples``: render samples (Cycles ``samples``, EEVEE ``taa_render_samples``); None keeps the .blend's.
    - ``resolution``: (width, height) in pixels at 100 %; None keeps the .blend's.
    - ``engine``: "CYCLES" (always on the CPU), "BLENDER_EEVEE" or "BLENDER_WORKBENCH"; None: the engine Apply
      computed the skin materials for (:func:`choose_engine`; the choice is printed on stderr).
    - ``file_format``: "EXR" (32-bit float, scene-linear) or "PNG" (display-referred, through the view transform);
      None keeps the .blend's when it is one of those, else EXR.
    - ``seed``: Cycles seed (and no animated seed); None keeps the .blend's.

    Files are named ``<blend name>_<frame:04d>.exr|png``. Raises FileNotFoundError for a missing .blend or (unless
    ``allow_missing_textures``) for textures neither packed nor on disk, RenderError (a ValueError) for bad
    arguments, RuntimeError when Blender fails to render.
    """
    if engine is not None:
        engine = engine.upper()
        engine = "BLENDER_EEVEE" if engine == "EEVEE" else _kind(engine)
    if engine is not None and engine not in ENGINES:
        raise RenderError(f"engine must be one of {', '.join(ENGINES)}; got {engine!r}")
    if file_format is not None and file_format.upper() not in FORMATS:
        raise RenderError(f"file format must be EXR or PNG; got {file_format!r}")
    if samples is not None and int(samples) < 1:
        raise RenderError(f"samples must be >= 1; got {samples}")
    if resolution is not None:
        if len(resolution) != 2 or min(int(v) for v in resolution) < 1:
            raise RenderError(f"resolution must be (width, height) >= 1; got {tuple(resolution)}")
    _open(blend_path)
    scene = bpy.context.scene
    engine, message = choose_engine(engine, scene.render.engine, stored_engines())
    print(message, file=sys.stderr)
    legacy = legacy_frame_values()
    if legacy:
        print(f"render_blend: warning: {', '.join(legacy)} keep per-frame values of an older Apply, which plain "
              "Blender does not animate: apply again (the values become F-curves)", file=sys.stderr)
    if scene.camera is None:
        raise RenderError(f"{blend_path}: scene {scene.name!r} has no camera")
    if not allow_missing_textures:
        missing = missing_images()
        if missing:
            raise FileNotFoundError(f"{blend_path}: {len(missing)} texture(s) neither packed nor found on disk: "
                                    + ", ".join(missing))
    render = scene.render
    render.engine = engine = engine_id(engine)
    if engine == "CYCLES":
        scene.cycles.device = "CPU"
        if samples is not None:
            scene.cycles.samples = int(samples)
        if seed is not None:
            scene.cycles.seed = int(seed)
            scene.cycles.use_animated_seed = False
    elif samples is not None and _kind(engine) == "BLENDER_EEVEE":
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
    parser.add_argument("--engine", help="CYCLES (CPU), BLENDER_EEVEE or BLENDER_WORKBENCH (default: the engine "
                        "Apply computed the skin materials for, else the .blend's)")
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
