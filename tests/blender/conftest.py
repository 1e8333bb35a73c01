"""pytest fixtures of the Blender render tests. The scene helpers they use (blender_scenes.py) and the random-walk
reference (walk_reference.py) live in scripts/lib/, shared with the measurement scripts: put on sys.path here, before
any test module imports them."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

SCRIPTS_LIB = str(Path(__file__).resolve().parents[2] / "scripts" / "lib")
if SCRIPTS_LIB not in sys.path:
    sys.path.insert(0, SCRIPTS_LIB)

from blender_scenes import _bpy, reset_scene  # noqa: E402


@pytest.fixture
def scene():
    """A fresh factory-empty scene configured for deterministic Cycles CPU renders."""
    pytest.importorskip("bpy")
    pytest.importorskip("OpenImageIO")
    return reset_scene()


@pytest.fixture(autouse=True, scope="session")
def isolated_table_cache(tmp_path_factory: pytest.TempPathFactory):
    """Keep lookup tables that tests build out of the user's cache folder."""
    mp = pytest.MonkeyPatch()
    mp.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path_factory.mktemp("table-cache")))
    yield
    mp.undo()


@pytest.fixture
def addon():
    """An empty factory scene with the add-on registered (and unregistered afterwards if this fixture did it)."""
    repo = str(Path(__file__).resolve().parents[2])
    if repo not in sys.path:
        sys.path.insert(0, repo)
    import blender_addon

    bpy = _bpy()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    registered = lambda: hasattr(bpy.types, "SPECTRAL_SKIN_OT_apply")  # noqa: E731
    registered_here = not registered()
    if registered_here:
        blender_addon.register()
    yield blender_addon
    if registered_here and registered():
        blender_addon.unregister()
