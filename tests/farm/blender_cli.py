"""A stand-in for the ``blender`` executable on a render node, built from bpy (Blender as a Python module), for the
farm tests where no Blender binary is installed: the subset of Blender's command line that farm jobs use, processed
in order as Blender does (docs.blender.org/manual/en/latest/advanced/command_line/arguments.html):

    -b/--background, FILE.blend (opened), -o/--render-output PATH (# -> frame digits), -F/--render-format FORMAT,
    -E/--engine ENGINE, -s/--frame-start N, -e/--frame-end N, -f/--render-frame 1,3..5 (renders), -a/--render-anim
    (renders), -Y/--disable-autoexec (the default here), --  (the rest is for scripts: ignored)

Like a plain render node it has no add-on and cannot import ``spectral_skin``, and Python auto-run is off (drivers
with Python expressions would not run; simple expressions do). Anything else is an error (status 2). Run it as
``python -I tests/farm/blender_cli.py ARGS``.
"""

from __future__ import annotations

import os
import sys

sys.modules["spectral_skin"] = None  # type: ignore[assignment]  # any `import spectral_skin` fails, as on a node

import bpy  # noqa: E402


def _frames(text: str) -> list[int]:
    frames: list[int] = []
    for part in text.split(","):
        first, _, last = part.partition("..")
        frames.extend(range(int(first), int(last or first) + 1))
    return frames


def _render(scene: bpy.types.Scene, frames: list[int]) -> None:
    for frame in frames:
        scene.frame_set(frame)
        path = scene.render.frame_path(frame=frame)
        previous = scene.render.filepath
        scene.render.filepath = path
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)
        scene.render.filepath = previous
        scene.render.use_file_extension = True
        print(f"Saved: '{path}'", flush=True)


def main(argv: list[str]) -> int:
    bpy.context.preferences.filepaths.use_scripts_auto_execute = False
    args = list(argv)
    while args:
        arg = args.pop(0)
        scene = bpy.context.scene
        if arg in {"-b", "--background", "-Y", "--disable-autoexec"}:
            continue
        if arg == "--":
            break
        if arg.endswith(".blend") and not arg.startswith("-"):
            bpy.ops.wm.open_mainfile(filepath=os.path.abspath(arg))
        elif arg in {"-o", "--render-output"}:
            scene.render.filepath = args.pop(0)
        elif arg in {"-F", "--render-format"}:
            scene.render.image_settings.file_format = args.pop(0)
        elif arg in {"-E", "--engine"}:
            scene.render.engine = args.pop(0)
        elif arg in {"-s", "--frame-start"}:
            scene.frame_start = int(args.pop(0))
        elif arg in {"-e", "--frame-end"}:
            scene.frame_end = int(args.pop(0))
        elif arg in {"-f", "--render-frame"}:
            _render(scene, _frames(args.pop(0)))
        elif arg in {"-a", "--render-anim"}:
            _render(scene, list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step)))
        else:
            print(f"blender_cli: argument {arg!r} is not in this stand-in's subset", file=sys.stderr)
            return 2
    if bpy.app.autoexec_fail:  # a script or a Python driver wanted to run
        print(f"Python auto-run is off: {bpy.app.autoexec_fail_message}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    status = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
