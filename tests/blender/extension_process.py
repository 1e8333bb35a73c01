"""Python processes of their own for the installed-extension tests (test_addon.py, test_install.py): run a script
with a Blender user folder of its own, and the snippet that applies a skin there and prints what it got."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

# Applies the extension's operator to a new material and prints, as the last line, a JSON report: the operator's
# result, the Principled Base Color and the module the operator came from.
APPLY_AND_REPORT = textwrap.dedent("""
    import json
    mat = bpy.data.materials.new("Skin")
    result = bpy.ops.spectral_skin.apply(material="Skin")
    node = [n for n in mat.node_tree.nodes if n.get("spectral_skin") == "principled"][0]
    print(json.dumps({"result": sorted(result), "base_color": list(node.inputs["Base Color"].default_value)[:3],
                      "module": bpy.types.SPECTRAL_SKIN_OT_apply.__module__}))
""")


def run_python(script: str, user: Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``script`` in a new Python process (this one's interpreter, without PYTHONPATH) whose Blender user folder is
    ``user`` (BLENDER_USER_RESOURCES)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["BLENDER_USER_RESOURCES"] = str(user)
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=cwd, env=env,
                          timeout=180)


def report(run: subprocess.CompletedProcess[str]) -> dict[str, Any]:
    """The JSON report :data:`APPLY_AND_REPORT` printed (the process must have succeeded)."""
    assert run.returncode == 0, run.stdout + run.stderr
    return json.loads(run.stdout.strip().splitlines()[-1])
