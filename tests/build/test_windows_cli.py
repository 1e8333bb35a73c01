"""The Windows CLI, cross-compiled here (x86_64-pc-windows-gnu), run under wine: the built-in example and its maps
must be the same bytes as the Linux CLI's (the one in the Linux wheel, `.venv/bin/spectral-skin`).

No Windows Python can import the .pyd here, but the .exe runs the same Rust code through the same standard library
for Windows (file system, threads, the cache folder under %LOCALAPPDATA%), so this is what can be run of Windows on
Linux. wine 8.0 lacks bcryptprimitives.dll, whose ProcessPrng Rust's standard library imports: a stand-in
(tests/build/bcryptprimitives.c) is compiled by MinGW beside the .exe. Skipped, saying what to install, without
wine, MinGW-w64 or the Rust target; cargo builds the .exe (up to date after the first time).

Run: .venv/bin/python -m pytest tests/build/test_windows_cli.py -q
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
TARGET = "x86_64-pc-windows-gnu"
LINUX_CLI = REPO / ".venv" / "bin" / "spectral-skin"
# The built-in example at 64x64: 4096 texels with more than 2048 distinct (C_m, beta_m, C_h) tuples, so the maps go
# through the lookup table (built, cached, interpolated with the SIMD row lookup), the path big maps take.
SIZE = "64"


def _missing() -> str | None:
    if not shutil.which("wine"):
        return "no wine: apt-get install wine64 (Debian's wine 8)"
    if not shutil.which("x86_64-w64-mingw32-gcc"):
        return "no x86_64-w64-mingw32-gcc: apt-get install gcc-mingw-w64-x86-64"
    installed = subprocess.run(["rustup", "target", "list", "--installed"], capture_output=True, text=True)
    if TARGET not in installed.stdout.split():
        return f"no Rust target {TARGET}: rustup target add {TARGET}"
    if not LINUX_CLI.exists():
        return f"no {LINUX_CLI.relative_to(REPO)}: bash scripts/setup-python.sh --test"
    return None


pytestmark = pytest.mark.skipif(_missing() is not None, reason=str(_missing()))


@pytest.fixture(scope="module")
def windows_cli(tmp_path_factory: pytest.TempPathFactory) -> pathlib.Path:
    """spectral-skin.exe (cargo build --release --target x86_64-pc-windows-gnu) with the bcryptprimitives stand-in
    beside it, in a folder of their own. Built in the module's target folder (scripts/build-wheel.sh's), where the
    Windows wheel's build leaves the dependencies compiled: a third of a build from scratch."""
    build = subprocess.run(["cargo", "build", "--release", "--target", TARGET, "--features", "cli", "--bin",
                            "spectral-skin", "--target-dir", str(REPO / "target" / "python"),
                            "--message-format", "json-render-diagnostics"],
                           cwd=REPO, capture_output=True, text=True, timeout=3600)
    assert build.returncode == 0, build.stderr[-4000:]
    exe = None
    for line in build.stdout.splitlines():
        message = json.loads(line)
        if message.get("reason") == "compiler-artifact" and message["target"]["name"] == "spectral-skin" \
                and message.get("executable"):
            exe = pathlib.Path(message["executable"])
    assert exe is not None and exe.suffix == ".exe", build.stdout[-2000:]
    folder = tmp_path_factory.mktemp("windows-cli")
    shutil.copy2(exe, folder / exe.name)
    subprocess.run(["x86_64-w64-mingw32-gcc", "-shared", "-O2", "-o", str(folder / "bcryptprimitives.dll"),
                    str(REPO / "tests" / "build" / "bcryptprimitives.c"), "-ladvapi32"], check=True)
    return folder / exe.name


def run_windows(exe: pathlib.Path, args: list[str], cwd: pathlib.Path, prefix: pathlib.Path) -> None:
    # A wine prefix of its own (made on first use), no display, wine's own messages off; the table cache goes to the
    # prefix's %LOCALAPPDATA% as on Windows.
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SPECTRAL_SKIN_CACHE_DIR")}
    env.update(WINEPREFIX=str(prefix), WINEDEBUG="-all", WINEDLLOVERRIDES="mscoree,mshtml=")
    run = subprocess.run(["wine", str(exe), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, f"wine {exe.name} {' '.join(args)}: {run.returncode}\n{run.stdout}\n{run.stderr}"


def run_linux(args: list[str], cwd: pathlib.Path, cache: pathlib.Path) -> None:
    env = {**os.environ, "SPECTRAL_SKIN_CACHE_DIR": str(cache)}
    run = subprocess.run([str(LINUX_CLI), *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, f"spectral-skin {' '.join(args)}: {run.returncode}\n{run.stdout}\n{run.stderr}"


def without_timings(value):
    """The sidecar less its timings ("seconds", "build_seconds"): all else (inputs, channels, accuracy, strategy,
    the table's measured error, the work done) must be equal."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k != "seconds" and not k.endswith("_seconds")}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def test_windows_cli_writes_the_linux_maps(windows_cli, tmp_path):
    linux, windows, prefix = tmp_path / "linux", tmp_path / "windows", tmp_path / "wineprefix"
    for folder in (linux, windows, prefix):
        folder.mkdir()
    example = ["example", "--out", "params.exr", "--size", SIZE]
    maps = ["maps", "--params", "params.exr", "--out", "maps"]
    run_linux(example, linux, tmp_path / "cache")
    run_linux(maps, linux, tmp_path / "cache")
    run_windows(windows_cli, example, windows, prefix)
    run_windows(windows_cli, maps, windows, prefix)
    # The table was built and cached where Windows keeps it (%LOCALAPPDATA%\spectral-skin).
    assert list(prefix.glob("drive_c/users/*/AppData/Local/spectral-skin/*")), "no table in the prefix's cache"

    assert (windows / "params.exr").read_bytes() == (linux / "params.exr").read_bytes()
    linux_files = sorted(p.name for p in (linux / "maps").iterdir())
    windows_files = sorted(p.name for p in (windows / "maps").iterdir())
    assert windows_files == linux_files
    assert {"albedo.exr", "radius.exr", "specular.exr", "skin_maps.json"} <= set(linux_files)
    for name in linux_files:
        if name.endswith(".json"):
            continue
        assert (windows / "maps" / name).read_bytes() == (linux / "maps" / name).read_bytes(), f"{name} differs"
    sidecar_linux = json.loads((linux / "maps" / "skin_maps.json").read_text())
    sidecar_windows = json.loads((windows / "maps" / "skin_maps.json").read_text())
    assert sidecar_windows["report"]["strategy"]["name"] == "table"
    assert without_timings(sidecar_windows) == without_timings(sidecar_linux)
