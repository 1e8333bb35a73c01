"""Apply, the one path of the operator and of ``batch.py apply``, in three steps: :func:`prepare` gathers what the
plan is computed from (main thread), :func:`compute` builds every plan and has the core write its textures (no bpy
data: safe in a worker thread), :func:`finish` edits the material from its plan and the files written, and stores
the plan on it (main thread). A material changes only once every plan is computed and every texture written.

In Live mode (core/live.py, live.py) the computing step is the plan of the panel's constants and, unless the blend
file has it, the shader table; the last step wires the live node group.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import bpy

from . import live, nodes, props, scene_facts
from .core import MaterialPlan, SkinSettings, write_textures
from .core import live as core_live
from .core import scene as analysis
from .nodes import scene_target, scene_working_space
from .work import Task


@dataclass(frozen=True)
class Job:
    """What Apply computes a material's plan from, gathered from bpy on the main thread: the settings for the scene's
    target and working space, the scene's facts for the material (:mod:`scene_facts`) and the material's overrides."""

    settings: SkinSettings
    facts: analysis.SceneFacts | None
    overrides: dict[str, str]
    # Live mode: whether the shader table must be computed (the blend file has no node group for its key).
    table_needed: bool = True


@dataclass(frozen=True)
class Applied:
    """A material's plan and the files the core wrote for its textures ({map name: path}; empty without maps)."""

    plan: MaterialPlan
    files: Mapping[str, str]


def prepare(material: bpy.types.Material, settings: SkinSettings, scene: bpy.types.Scene) -> Job:
    """Apply's first step (main thread): the plan is computed in the scene's working space
    (:func:`scene_working_space`) and for the running Blender and the scene's engine (:func:`scene_target`), whatever
    ``settings`` says."""
    settings = settings.replace(working_space=scene_working_space(), **scene_target(scene))
    overrides = scene_facts.overrides(material)
    needed = settings.mode != "LIVE" or not live.has_group(core_live.table_name(settings, overrides))
    return Job(settings, scene_facts.gather(scene, material), overrides, needed)


def plan_of(job: Job, progress: Any = None) -> MaterialPlan:
    """A job's plan: Live mode's (core/live.py) or Baked mode's (core/scene.py); the scene decides which effects are
    simulated (``plan.effects``)."""
    if job.settings.mode == "LIVE":
        return core_live.live_plan(job.settings, job.facts, job.overrides, job.table_needed, progress)
    return analysis.scene_plan(job.settings, job.facts, job.overrides, progress)


def compute(jobs: Sequence[Job], progress: Any = None,
            before_write: Callable[[], bool] | None = None) -> list[Applied]:
    """Apply's second step, which needs no bpy data (safe in a worker thread): every job's plan, then, only once all
    are computed, every plan's textures written by the core.

    ``progress(done, total)`` is the core's callback (False cancels). ``before_write()`` is called between the two;
    when it returns False nothing is written and the result is empty (a cancel)."""
    plans = [plan_of(job, progress) for job in jobs]
    if before_write is not None and not before_write():
        return []
    return [Applied(plan, write_textures(plan)) for plan in plans]


def finish(material: bpy.types.Material, applied: Applied) -> MaterialPlan:
    """Apply's last step, on Blender's data (main thread only): the material's nodes (in Live mode with the live
    node group wired in: live.py; in Baked mode without it), then the plan stored on it. Returns the plan."""
    plan = applied.plan
    nodes.apply_plan(material, plan, applied.files)
    if plan.live is not None:
        live.wire(material, plan)
    else:
        live.remove_nodes(material.node_tree)
    props.store_result(material, plan, applied.files)
    return plan


def apply_skins(items: Sequence[tuple[bpy.types.Material, SkinSettings]],
                scene: bpy.types.Scene | None = None) -> list[MaterialPlan]:
    """Apply, the one path of the operator and of the batch apply: for each ``(material, settings)`` the plan for
    ``scene`` (default: the context's), then every plan's maps written, and only then each material edited and its
    plan stored (:func:`prepare`, :func:`compute`, :func:`finish`; the operator started from the panel runs
    :func:`compute` in a worker thread). Returns the plans.

    Raises spectral_skin.SpectralSkinError / ValueError for bad settings, spectral_skin.SpectralSkinIOError (an
    OSError) for a map that cannot be written (the core's writer names the file); no material is then changed.
    """
    scene = scene if scene is not None else bpy.context.scene
    jobs = [prepare(material, settings, scene) for material, settings in items]
    return [finish(material, applied) for (material, _), applied in zip(items, compute(jobs), strict=True)]


def apply_skin(material: bpy.types.Material, settings: SkinSettings) -> MaterialPlan:
    """:func:`apply_skins` for one material in the context's scene; returns its plan."""
    return apply_skins([(material, settings)])[0]


def apply_task(job: Job) -> Task:
    """Apply's :func:`compute` of one job as a worker's task (work.py): its :class:`Applied`, or None when
    cancelled."""
    def task(progress: Callable[[int, int], bool], before_write: Callable[[], bool]) -> Applied | None:
        applied = compute([job], progress, before_write)
        return applied[0] if applied else None
    return task
