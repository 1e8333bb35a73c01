"""What the per-engine calibration scripts (scripts/calibration/*) share: their command line (--engine, --out) and the
provenance every JSON they write carries (the engine, the Blender version, the command that regenerates it)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
ENGINES = ("cycles", "eevee")


def engine_and_output(doc: str, data_name: str, argv: list[str] | None) -> tuple[str, Path]:
    """Parse ``--engine cycles|eevee`` and ``--out`` (default docs/data/<data_name>_<engine>.json) for a script whose
    module docstring is ``doc``."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--engine", choices=ENGINES, required=True)
    parser.add_argument("--out", type=Path, default=None, help=f"default: docs/data/{data_name}_<engine>.json")
    args = parser.parse_args(argv)
    return args.engine, args.out or ROOT / "docs" / "data" / f"{data_name}_{args.engine}.json"


def provenance(description: str, script_file: str, engine: str) -> dict[str, Any]:
    """The head of a calibration JSON: what it holds and how to regenerate it (``script_file``: the script's
    ``__file__``), the engine and the running Blender."""
    import bpy

    script = Path(script_file).resolve().relative_to(ROOT).as_posix()
    return {
        "description": f"{description}; regenerate: <venv>/bin/python {script} --engine {engine}",
        "engine": engine,
        "blender": "{}.{}".format(*bpy.app.version[:2]),
        "bpy": bpy.app.version_string,
    }


def run_and_exit(main: Any) -> None:
    """Run a script's ``main()`` and leave the interpreter at once: bpy 4.5 can hang at interpreter exit."""
    import os
    import sys

    main()
    sys.stdout.flush()
    os._exit(0)
