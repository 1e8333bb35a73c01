"""scripts/check_imports.py (run by lint.sh) finds what it is meant to: a circle between two Rust files, one through
a Python package, and a module taking a name from the crate root; and passes a one-way tree."""

import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "check_imports.py"


def run(root: pathlib.Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), str(root)], capture_output=True, text=True, timeout=60)


def write(root: pathlib.Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")


ONE_WAY = {
    "src/lib.rs": "pub mod a;\npub mod b;\npub use a::Thing;\n",
    "src/a.rs": "use crate::b::Base;\npub struct Thing(Base);\n",
    "src/b.rs": "pub struct Base;\n#[cfg(test)]\nmod tests {\n    use crate::a::Thing;\n}\n",
    "blender_addon/__init__.py": "from . import ops\n",
    "blender_addon/ops.py": "from .props import Settings\n",
    "blender_addon/props.py": "Settings = dict\n",
}


def test_a_one_way_tree_passes(tmp_path):
    write(tmp_path, ONE_WAY)
    result = run(tmp_path)
    assert result.returncode == 0, result.stdout
    assert "one-way" in result.stdout


def test_a_rust_circle_is_named_with_its_names(tmp_path):
    write(tmp_path, {**ONE_WAY, "src/b.rs": "use crate::a::Thing;\npub struct Base;\n// crate::a in a comment\n"})
    result = run(tmp_path)
    assert result.returncode == 1
    assert "circle: src/a.rs, src/b.rs" in result.stdout and "src/b.rs -> src/a.rs: Thing" in result.stdout


def test_a_python_circle_is_named(tmp_path):
    write(tmp_path, {**ONE_WAY, "blender_addon/props.py": "from .ops import something\nSettings = dict\n"})
    result = run(tmp_path)
    assert result.returncode == 1
    assert "blender_addon/ops.py" in result.stdout and "blender_addon/props.py" in result.stdout


def test_a_name_taken_from_the_crate_root_is_refused(tmp_path):
    write(tmp_path, {**ONE_WAY, "src/b.rs": "use crate::Thing;\npub struct Base;\n"})
    result = run(tmp_path)
    assert result.returncode == 1
    assert "src/b.rs takes Thing from the crate root" in result.stdout
