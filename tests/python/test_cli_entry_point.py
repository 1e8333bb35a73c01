"""`pip install` of the wheel puts `spectral-skin` on PATH: the wheel's console script (spectral_skin._cli) runs the
core's command line in the Python process, the same program as cargo's binary (docs/cli.md)."""

from __future__ import annotations

import importlib.metadata
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import spectral_skin


def _script() -> Path:
    """The script pip installed beside this interpreter (bin/ on POSIX, Scripts/ on Windows)."""
    folder = Path(sys.executable).parent
    for name in ("spectral-skin", "spectral-skin.exe"):
        if (folder / name).is_file():
            return folder / name
    raise AssertionError(f"no spectral-skin script in {folder}: {sorted(p.name for p in folder.iterdir())}")


def test_the_wheel_declares_the_console_script():
    scripts = {e.name: e.value for e in importlib.metadata.entry_points(group="console_scripts")
               if e.dist is not None and e.dist.name == "spectral-skin"}
    assert scripts == {"spectral-skin": "spectral_skin._cli:main"}, scripts


def test_the_script_runs_the_core_command_line():
    version = subprocess.run([_script(), "--version"], capture_output=True, text=True, check=True).stdout
    assert version.split() == ["spectral-skin", spectral_skin.__version__], version
    out = subprocess.run([_script(), "eval", "--preset", "caucasian", "--json"], capture_output=True, text=True,
                         check=True).stdout
    by_cli = json.loads(out)
    by_python = spectral_skin.evaluate(preset="caucasian")
    got, expected = by_cli["diffuse_reflectance_rgb"], by_python["diffuse_reflectance_rgb"]
    print(f"albedo: script {got}, evaluate() {expected}")
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_the_script_reports_errors_with_the_cli_status():
    # A negative number with an exponent is the option's value, which is out of range: the core's message, status 2.
    run = subprocess.run([_script(), "eval", "--melanin", "-1e-3", "--melanin-blend", "0.5", "--hemoglobin", "0.01",
                          "--oiliness", "0.3"], capture_output=True, text=True)
    print(f"status {run.returncode}, stderr {run.stderr!r}")
    assert run.returncode == 2
    assert "melanin must be in [0, 0.5]" in run.stderr and "got -0.001" in run.stderr
