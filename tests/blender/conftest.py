"""pytest fixtures of the Blender render tests, and their import path. The scene helpers they use (blender_scenes.py)
and the random-walk reference (walk_reference.py) live in scripts/lib/, shared with the measurement scripts: put on
sys.path here, with the repository root, scripts/tools and tests/python (the tests' shared color_difference), before
any test module imports them."""

from __future__ import annotations

import platform
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
# The one place the Blender tests' import path is set: the repository root (blender_addon), scripts/lib (the scene
# helpers), scripts/tools (render_blend) and tests/python's shared helper modules (color_difference: the tests'
# independent CIEDE2000); this folder's helper modules (live_scene, eevee_scene, farm_worker) are on it as pytest
# puts it there.
for _folder in (REPO / "tests" / "python", REPO / "scripts" / "tools", REPO, REPO / "scripts" / "lib"):
    if str(_folder) not in sys.path:
        sys.path.insert(0, str(_folder))

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


class PanelLayout:
    """A stand-in for a panel's layout (headless Blender has no window to draw in): checks that every property and
    operator the panel names exists, and records the properties."""

    def __init__(self, drawn: list[str]) -> None:
        self.drawn = drawn
        self.use_property_split = self.active = self.enabled = False

    def prop(self, data, name, **_kw):
        assert name in data.bl_rna.properties, name
        self.drawn.append(name)

    def operator(self, idname, **_kw):
        category, name = idname.split(".")
        assert hasattr(getattr(_bpy().ops, category), name), idname
        return type("Properties", (), {})()

    def row(self, **_kw):
        return self

    box = column = row

    def label(self, **_kw):
        pass

    def template_ID(self, data, name, **_kw):  # noqa: N802 (Blender's name)
        self.prop(data, name)


@pytest.fixture
def draw_panel():
    """draw(panel, context): draws the panel class headless into a PanelLayout; returns the properties it drew."""

    def draw(panel, context) -> list[str]:
        drawn: list[str] = []
        panel.draw(type("Panel", (), {"layout": PanelLayout(drawn)})(), context)
        return drawn

    return draw


@pytest.fixture
def extension_zip() -> Path:
    """This machine's extension zip from scripts/build_addon.sh (Blender's `--split-platforms` name: the manifest's
    id and version, then the platform); the test is skipped when it has not been built."""
    manifest = tomllib.loads((REPO / "blender_addon" / "blender_manifest.toml").read_text())
    system = {"Linux": "linux", "Darwin": "macos", "Windows": "windows"}.get(platform.system(), platform.system())
    machine = {"x86_64": "x64", "AMD64": "x64", "aarch64": "arm64", "ARM64": "arm64"}.get(platform.machine(),
                                                                                         platform.machine())
    path = REPO / "dist" / f"{manifest['id']}-{manifest['version']}-{system}_{machine}.zip"
    if not path.exists():
        pytest.skip(f"no {path.relative_to(REPO)}: run bash scripts/build_addon.sh")
    return path
