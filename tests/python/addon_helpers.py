"""The add-on's portable core (blender_addon/core, which imports nothing of Blender's) loaded as a top-level package
for the Python tests, and builders of the scene facts its decisions read. Shared by the test_addon_*.py modules."""

from __future__ import annotations

import dataclasses
import importlib
import importlib.util
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def load_core():
    """blender_addon/core as a top-level package: its own __init__ imports nothing of Blender's."""
    if "addon_core" in sys.modules:
        return sys.modules["addon_core"]
    folder = REPO / "blender_addon" / "core"
    spec = importlib.util.spec_from_file_location("addon_core", folder / "__init__.py",
                                                  submodule_search_locations=[str(folder)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["addon_core"] = module
    spec.loader.exec_module(module)
    return module


core = load_core()
scene = importlib.import_module("addon_core.scene")

BOX_AT_ORIGIN = tuple((x, y, z) for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (-0.1, 0.1))


def camera_facts(distance: float, **kw) -> scene.CameraFacts:
    """A camera on -Y at ``distance`` from the origin looking along +Y."""
    return scene.CameraFacts(name=kw.pop("name", "Camera"), type=kw.pop("type", "PERSP"),
                             location=(0.0, -distance, 0.0), forward=(0.0, 1.0, 0.0), **kw)


def scene_facts(distance: float, x: int = 1920, y: int = 1080, pct: int = 100, frame: int = 1, **kw) -> scene.SceneFacts:
    cam = camera_facts(distance, **kw)
    return scene.SceneFacts(resolution_x=x, resolution_y=y, resolution_percentage=pct,
                            views=(scene.View("Head", frame, cam, BOX_AT_ORIGIN),))


def effect_entry(effects, name):
    return next(e for e in effects if e["effect"] == name)


def with_changes(facts, **changes):
    return dataclasses.replace(facts, **changes)


def animation_facts(values: dict[str, tuple[float, ...]], current: int = 1, first: int = 1) -> scene.AnimationFacts:
    frames = tuple(range(first, first + len(next(iter(values.values())))))
    return scene.AnimationFacts({name: "keyframed" for name in values}, frames, values, current)
