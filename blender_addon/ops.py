"""Apply (compute the material plan with the core, write its maps, then edit the material and store the plan:
:func:`apply_skins`, the one path of the operator and of ``batch.py apply``), the operators Apply and Remove, and
From Albedo Texture (:func:`from_albedo_texture`: a parameter map fitted to the material's Base Color image by the
core, core/albedo.py).

Apply with parameter maps and From Albedo Texture, started from the UI, run their computing step in a worker thread
(:class:`_Work`; the core releases the GIL) while a modal timer shows the progress and Esc cancels with nothing
changed (:class:`_ModalWork`); the material is edited on Blender's main thread once everything is computed and
written. From a script (or without maps) it runs synchronously, the same
steps. In Live mode (core/live.py, live.py) the computing step is the plan of the panel's constants and, unless the
blend file has it, the shader table; the last step wires the live node group.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import bpy
import spectral_skin

from . import live, nodes, props, scene_facts
from .core import MaterialPlan, SkinSettings, describe_error, texture_prefix, write_textures
from .core import albedo as core_albedo
from .core import live as core_live
from .core import scene as analysis
from .nodes import scene_target, scene_working_space

ERRORS = (spectral_skin.SpectralSkinError, ValueError, OSError)


@dataclass(frozen=True)
class Job:
    """What Apply computes a material's plan from, gathered from bpy on the main thread: the settings for the scene's
    target and working space, the scene's facts for the material (:mod:`scene_facts`) and the material's overrides."""

    settings: SkinSettings
    facts: analysis.SceneFacts | None
    overrides: dict[str, str]
    # Live mode: whether the shader table must be computed (the blend file has no node group for its key).
    table_needed: bool = True


def prepare(material: bpy.types.Material, settings: SkinSettings, scene: bpy.types.Scene) -> Job:
    """Apply's first step (main thread): the plan is computed in the scene's working space
    (:func:`scene_working_space`) and for the running Blender and the scene's engine (:func:`scene_target`), whatever
    ``settings`` says."""
    settings = settings.replace(working_space=scene_working_space(), **scene_target(scene))
    overrides = scene_facts.overrides(material)
    needed = settings.mode != "LIVE" or not live.has_group(core_live.table_name(settings, overrides))
    return Job(settings, scene_facts.gather(scene, material), overrides, needed)


def compute(jobs: Sequence[Job], progress: Any = None, before_write: Callable[[], bool] | None = None) -> list[MaterialPlan]:
    """Apply's second step, which needs no bpy data (safe in a worker thread): every job's plan (the scene decides
    which effects are simulated: ``plan.effects``), then, only once all are computed, every plan's maps written.

    ``progress(done, total)`` is the core's callback (False cancels). ``before_write()`` is called between the two;
    when it returns False nothing is written and the result is empty (a cancel)."""
    plans = [core_live.live_plan(job.settings, job.facts, job.overrides, job.table_needed, progress)
             if job.settings.mode == "LIVE" else analysis.scene_plan(job.settings, job.facts, job.overrides, progress)
             for job in jobs]
    if before_write is not None and not before_write():
        return []
    for plan in plans:
        write_textures(plan)
    return plans


def finish(material: bpy.types.Material, plan: MaterialPlan) -> None:
    """Apply's last step, on Blender's data (main thread only): the material's nodes (in Live mode with the live
    node group wired in: live.py; in Baked mode without it), then the plan stored on it."""
    nodes.apply_plan(material, plan)
    if plan.live is not None:
        live.wire(material, plan)
    else:
        live.remove_nodes(material.node_tree)
    props.store_result(material, plan)


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
    plans = compute(jobs)
    for (material, _), plan in zip(items, plans, strict=True):
        finish(material, plan)
    return plans


def apply_skin(material: bpy.types.Material, settings: SkinSettings) -> MaterialPlan:
    """:func:`apply_skins` for one material in the context's scene; returns its plan."""
    return apply_skins([(material, settings)])[0]


def _find_material(name: str, context: bpy.types.Context) -> bpy.types.Material | None:
    """The material named ``name``, or the context's (the panel's, else the active object's) when empty."""
    if name:
        return bpy.data.materials.get(name)
    material = getattr(context, "material", None)
    if material is None and context.object is not None:
        material = context.object.active_material
    return material


# A computing step for a worker: task(progress, before_write) -> its result, None when cancelled before writing.
# (_Work is not a typing.Generic: a Generic class in the add-on made bpy 4.2 crash at interpreter exit.)
Task = Callable[[Callable[[int, int], bool], Callable[[], bool]], Any]


class _Work:
    """A computing step in a worker thread (Apply's :func:`compute`, From Albedo Texture's
    ``core.albedo.fit_and_write``): its progress, a cancel flag, and its outcome. ``task(progress, before_write)``
    gets the core's callback (``progress(done, total)``, False once cancelled) and the check made before anything is
    written (False when cancelled: the task then writes nothing and returns None)."""

    def __init__(self, task: Task) -> None:
        self.fraction = 0.0
        self.cancel = threading.Event()
        self.writing = False
        self.result: Any = None
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, args=(task,), daemon=True)

    def _progress(self, done: int, total: int) -> bool:
        self.fraction = done / total if total else 1.0
        return not self.cancel.is_set()

    def _start_writing(self) -> bool:
        self.writing = not self.cancel.is_set()
        return self.writing

    def _run(self, task: Task) -> None:
        try:
            self.result = task(self._progress, self._start_writing)
        except BaseException as error:  # reported on the main thread
            self.error = error


def apply_task(job: Job) -> Task:
    """Apply's :func:`compute` of one job as a :class:`_Work` task: its plan, or None when cancelled."""
    def task(progress: Callable[[int, int], bool], before_write: Callable[[], bool]) -> MaterialPlan | None:
        plans = compute([job], progress, before_write)
        return plans[0] if plans else None
    return task


class _ModalWork:
    """What Apply and From Albedo Texture share when started from the UI: the computing step in a :class:`_Work`
    while a modal timer shows its progress (the progress bar and the status text) and Esc cancels it (until it starts
    writing); once it has succeeded, :meth:`_succeed` changes Blender's data on the main thread, and on a cancel or an
    error nothing is changed. A mixin of the two operators (before bpy.types.Operator in their bases)."""

    if TYPE_CHECKING:
        def report(self, kind: set[str], message: str) -> None: ...

    _work: _Work | None = None
    _timer: Any = None
    _writing_state = "writing the maps"

    def _start(self, context: bpy.types.Context, work: _Work) -> set[str]:
        self._work = work
        work.thread.start()
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _end(self, context: bpy.types.Context) -> None:
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def _succeed(self, context: bpy.types.Context, result: Any) -> set[str]:
        raise NotImplementedError

    def modal(self, context: bpy.types.Context, event: bpy.types.Event) -> set[str]:
        work = self._work
        if work is None:
            return {"CANCELLED"}
        if event.type == "ESC" and not work.writing:
            work.cancel.set()
            return {"RUNNING_MODAL"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}  # the rest of Blender stays usable meanwhile
        if work.thread.is_alive():
            context.window_manager.progress_update(int(100 * work.fraction))
            if context.workspace is not None:
                state = self._writing_state if work.writing else (
                    "cancelling" if work.cancel.is_set() else f"{100 * work.fraction:.0f} % (Esc to cancel)")
                context.workspace.status_text_set(f"Spectral Skin: {state}")
            return {"RUNNING_MODAL"}
        self._end(context)
        if work.cancel.is_set() and work.result is None:
            self.report({"WARNING"}, "Spectral Skin: cancelled, nothing changed")
            return {"CANCELLED"}
        if work.error is not None or work.result is None:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(work.error) if work.error else 'no result'}")
            return {"CANCELLED"}
        return self._succeed(context, work.result)


class SPECTRAL_SKIN_OT_apply(_ModalWork, bpy.types.Operator):
    """Compute the skin with spectral-skin and set up the material's Principled BSDF (and texture maps)"""

    bl_idname = "spectral_skin.apply"
    bl_label = "Apply Spectral Skin"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material to set up; empty: the active material")

    _material_name = ""

    def _material(self, context: bpy.types.Context) -> bpy.types.Material | None:
        return _find_material(self.material, context)

    def _settings(self, context: bpy.types.Context) -> tuple[bpy.types.Material | None, SkinSettings | None]:
        material = self._material(context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
            return None, None
        try:
            return material, props.settings_from_material(material, context.scene)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return material, None

    def _done(self, plan: MaterialPlan) -> set[str]:
        summary = plan.summary
        self.report({"INFO"}, f"Spectral Skin: {summary.computed} in {summary.seconds:.2f} s")
        for line in analysis.describe(plan.effects):
            self.report({"INFO"}, f"Spectral Skin: {line}")
        for warning in summary.warnings:
            self.report({"WARNING"}, warning)
        return {"FINISHED"}

    def execute(self, context: bpy.types.Context) -> set[str]:
        material, settings = self._settings(context)
        if material is None or settings is None:
            return {"CANCELLED"}
        try:
            plan = apply_skin(material, settings)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return {"CANCELLED"}
        return self._done(plan)

    def invoke(self, context: bpy.types.Context, _event: bpy.types.Event) -> set[str]:
        material, settings = self._settings(context)
        if material is None or settings is None:
            return {"CANCELLED"}
        if (not settings.maps and settings.mode != "LIVE") or context.window is None:
            return self.execute(context)  # one evaluation: no time to show (Live mode may build its shader table)
        self._material_name = material.name
        return self._start(context, _Work(apply_task(prepare(material, settings, context.scene))))

    def _succeed(self, context: bpy.types.Context, result: Any) -> set[str]:
        plan: MaterialPlan = result
        material = bpy.data.materials.get(self._material_name)
        if material is None:
            self.report({"ERROR"}, f"Spectral Skin: the material {self._material_name!r} is gone")
            return {"CANCELLED"}
        try:
            finish(material, plan)
        except ERRORS as error:
            self.report({"ERROR"}, f"Spectral Skin: {describe_error(error)}")
            return {"CANCELLED"}
        return self._done(plan)


class SPECTRAL_SKIN_OT_remove(bpy.types.Operator):
    """Delete the nodes Spectral Skin added and link the material's previous shader back to its output"""

    bl_idname = "spectral_skin.remove"
    bl_label = "Remove Spectral Skin"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material; empty: the active material")

    def execute(self, context: bpy.types.Context) -> set[str]:
        material = _find_material(self.material, context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
            return {"CANCELLED"}
        removed = nodes.remove_skin(material)
        material.spectral_skin.has_result = False
        self.report({"INFO"}, f"Spectral Skin: removed {removed} node{'s' if removed != 1 else ''}")
        return {"FINISHED"}


def base_color_image(material: bpy.types.Material) -> bpy.types.Image:
    """The image of the material's Base Color: an Image Texture (not one the add-on made) linked, directly or
    through reroutes, to a Principled BSDF's Base Color; ValueError when there is none."""
    tree = material.node_tree
    for node in (tree.nodes if tree is not None else ()):
        if node.type != "BSDF_PRINCIPLED":
            continue
        socket = nodes._socket(node.inputs, "Base Color")
        while socket.is_linked:
            source = socket.links[0].from_node
            if source.type == "REROUTE":
                socket = source.inputs[0]
                continue
            if source.type == "TEX_IMAGE" and source.image is not None and nodes.TAG not in source:
                return source.image
            break
    raise ValueError(f"the material {material.name!r} has no image linked to a Principled BSDF's Base Color")


def image_pixels(image: bpy.types.Image) -> Any:
    """An image's pixels as Blender holds them: (H, W, channels) float32, row 0 at the top."""
    import numpy as np

    width, height = image.size
    if width == 0 or height == 0 or image.channels < 3:
        raise ValueError(f"the Base Color image {image.name!r} has no RGB pixels (is its file missing?)")
    flat = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(flat)
    return flat.reshape(height, width, image.channels)[::-1]


def base_color_texels(image: bpy.types.Image, raw: bool = False) -> tuple[Any, str, list[tuple[int, int]]]:
    """The Base Color image's texels as (H, W, 3) linear RGB, their working space, and for a UDIM tile set the
    (tile, rows) of each tile stacked top to bottom (empty for one image). A tile set's tiles are read from their
    files (Blender's pixels of a tiled image are its first tile's), in the tiled image's colour space; they must share
    one width (ValueError naming them). ``raw``: Blender's pixel values as they are, not decoded (a mask's)."""
    import numpy as np

    def texels(single: bpy.types.Image) -> tuple[Any, str]:
        if raw:
            return np.ascontiguousarray(image_pixels(single)[:, :, :3]), scene_working_space()
        return core_albedo.linear_albedo(image_pixels(single), single.colorspace_settings.name, single.is_float,
                                         scene_working_space())

    if image.source != "TILED":
        pixels, space = texels(image)
        return pixels, space, []
    pattern = bpy.path.abspath(image.filepath, library=image.library)
    parts, tiles = [], []
    for tile in sorted(t.number for t in image.tiles):
        single = bpy.data.images.load(pattern.replace(core_albedo.UDIM_TOKEN, str(tile)), check_existing=False)
        try:
            single.colorspace_settings.name = image.colorspace_settings.name
            pixels, space = texels(single)
        finally:
            bpy.data.images.remove(single)
        parts.append(pixels)
        tiles.append((tile, pixels.shape[0]))
    if len({p.shape[1] for p in parts}) != 1:
        raise ValueError(f"the tile set {image.name!r} has tiles of different widths "
                         f"({', '.join(f'{t}: {p.shape[1]}' for (t, _), p in zip(tiles, parts, strict=True))}): they are "
                         "fitted as one texture, so they must share one width")
    return np.ascontiguousarray(np.concatenate(parts, axis=0)), space, tiles


def prepare_albedo(material: bpy.types.Material, hold_thickness: bool = False,
                   auto_gains: bool = False) -> core_albedo.AlbedoJob:
    """From Albedo Texture's first step (main thread; reads Blender's data, changes nothing): the material's Base
    Color image (or UDIM tile set, fitted as one texture) as linear RGB, the material's Skin Mask (if set, of the same
    size or tiles) as the texels that count, the held epidermis thickness (``hold_thickness``; else chosen for the
    texture), ``auto_gains`` (exposure and white balance corrected first), and the parameter and residual EXR paths
    beside the .blend. Raises ValueError for a material it cannot read."""
    image = base_color_image(material)
    pixels, space, tiles = base_color_texels(image)
    settings = material.spectral_skin
    mask = None
    if settings.skin_mask is not None:
        mask_rgb, _, mask_tiles = base_color_texels(settings.skin_mask, raw=True)
        if [t for t, _ in mask_tiles] != [t for t, _ in tiles]:
            raise ValueError(f"the skin mask {settings.skin_mask.name!r} has the tiles {[t for t, _ in mask_tiles]} "
                             f"but the Base Color {image.name!r} has {[t for t, _ in tiles]}: they must be the same")
        mask = core_albedo.skin_mask(mask_rgb, pixels.shape, settings.skin_mask.name, image.name)
    prefix = texture_prefix(bpy.data.filepath, material.name)
    return core_albedo.AlbedoJob(
        image=image.name, albedo=pixels, working_space=space, tiles=tiles,
        epidermis_thickness_mm=float(settings.epidermis_thickness_mm) if hold_thickness else None,
        transport=settings.transport, auto_gains=auto_gains, mask=mask,
        path=core_albedo.parameter_map_path(bpy.data.filepath, prefix, tiled=bool(tiles)),
        residual_path=core_albedo.parameter_map_path(bpy.data.filepath, prefix, tiled=bool(tiles), kind="residual"))


def finish_albedo(material: bpy.types.Material, job: core_albedo.AlbedoJob, result: dict[str, Any]) -> dict[str, Any]:
    """From Albedo Texture's last step, once the fit and its files succeeded (main thread only): the parameter EXR
    set as the material's Parameter Map (a Non-Color image), the residual loaded as an image to inspect, the Advanced
    sliders set to the extended physiology the fit holds for. Returns the fit's summary (``result`` without the fit
    object, plus "path", "residual", "image", "working_space", "tiles")."""
    loaded = nodes.load_image(job.path)
    loaded.reload()
    loaded.colorspace_settings.name = "Non-Color"
    residual_image = nodes.load_image(job.residual_path)
    residual_image.reload()
    residual_image.colorspace_settings.name = "Non-Color"
    settings = material.spectral_skin
    settings.params_map = loaded
    for name, value in result["extended"].items():
        setattr(settings, name, value)
    return {key: value for key, value in result.items() if key != "fit"} | {
        "path": job.path, "residual": residual_image.name, "image": job.image, "working_space": job.working_space,
        "tiles": [t for t, _ in job.tiles]}


def from_albedo_texture(material: bpy.types.Material, hold_thickness: bool = False,
                        auto_gains: bool = False) -> dict[str, Any]:
    """From Albedo Texture at once (:func:`prepare_albedo`, ``core.albedo.fit_and_write``, :func:`finish_albedo`;
    the operator started from the panel runs the middle step in a worker thread): the material's Base Color image fitted
    per texel by the core (core/albedo.py), the parameter and residual EXRs written beside the .blend by the core,
    then the parameter map set on the material. Returns the fit's summary. Raises ValueError / OSError /
    spectral_skin.SpectralSkinError; the material is then unchanged."""
    job = prepare_albedo(material, hold_thickness, auto_gains)
    result = core_albedo.fit_and_write(job)
    if result is None:  # only a cancel (before_write) gives None, and there is none here
        raise RuntimeError("From Albedo Texture: the fit returned no result")
    return finish_albedo(material, job, result)


class SPECTRAL_SKIN_OT_from_albedo_texture(_ModalWork, bpy.types.Operator):
    """Fit the skin parameters per texel to the material's Base Color image (the core's albedo fit) and set the
    result, a parameter EXR written beside the .blend, as the material's Parameter Map"""

    bl_idname = "spectral_skin.from_albedo_texture"
    bl_label = "From Albedo Texture"
    bl_options = {"REGISTER", "UNDO"}

    material: bpy.props.StringProperty(
        name="Material", description="Name of the material; empty: the active material")
    auto_gains: bpy.props.BoolProperty(
        name="Correct Exposure and White Balance", default=False,
        description="Estimate the exposure and white-balance gains that bring the most texels inside skin's colours "
                    "(for a photograph) and apply them before the fit")
    hold_thickness: bpy.props.BoolProperty(
        name="Hold Epidermis Thickness", default=False,
        description="Fit at the material's Epidermis Thickness instead of choosing one for the texture (the "
                    "default: the thickness of 0.05 to 0.5 mm that fits the texture best, never worse than 0.25)")

    _writing_state = "writing the parameter map"
    _material_name = ""
    _job: core_albedo.AlbedoJob | None = None

    @classmethod
    def poll(cls, context: bpy.types.Context) -> bool:
        if not core_albedo.available():
            cls.poll_message_set(f"From Albedo Texture {core_albedo.UNAVAILABLE}")
            return False
        return True

    def _fail(self, error: BaseException) -> set[str]:
        self.report({"ERROR"}, f"Spectral Skin: From Albedo Texture: {describe_error(error)}")
        return {"CANCELLED"}

    def _material_or_report(self, context: bpy.types.Context) -> bpy.types.Material | None:
        material = _find_material(self.material, context)
        if material is None:
            self.report({"ERROR"}, f"no material {self.material!r}" if self.material else "no active material")
        return material

    def execute(self, context: bpy.types.Context) -> set[str]:
        material = self._material_or_report(context)
        if material is None:
            return {"CANCELLED"}
        try:
            summary = from_albedo_texture(material, self.hold_thickness, self.auto_gains)
        except ERRORS as error:
            return self._fail(error)
        return self._done(material, summary)

    def invoke(self, context: bpy.types.Context, _event: bpy.types.Event) -> set[str]:
        if context.window is None:
            return self.execute(context)
        material = self._material_or_report(context)
        if material is None:
            return {"CANCELLED"}
        try:
            job = prepare_albedo(material, self.hold_thickness, self.auto_gains)
        except ERRORS as error:
            return self._fail(error)
        self._material_name, self._job = material.name, job
        return self._start(context, _Work(albedo_task(job)))

    def _succeed(self, context: bpy.types.Context, result: Any) -> set[str]:
        material = bpy.data.materials.get(self._material_name)
        if material is None or self._job is None:
            self.report({"ERROR"}, f"Spectral Skin: the material {self._material_name!r} is gone")
            return {"CANCELLED"}
        try:
            summary = finish_albedo(material, self._job, result)
        except ERRORS as error:
            return self._fail(error)
        return self._done(material, summary)

    def _done(self, material: bpy.types.Material, summary: dict[str, Any]) -> set[str]:
        thickness = summary["extended"]["epidermis_thickness_mm"]
        masked = (f", {summary['masked_out_texels']} outside the skin mask (fitted to their nearest skin colour)"
                  if material.spectral_skin.skin_mask is not None else "")
        self.report({"INFO"}, f"Spectral Skin: fitted {summary['image']!r} ({summary['working_space']}): ΔE00 median "
                    f"{summary['median_delta_e00']:.2f}, max {summary['max_delta_e00']:.2f}, "
                    f"{summary['outside_skin_texels']} texel(s) outside skin's colours{masked}; epidermis thickness "
                    f"{thickness:g} mm ({'held' if summary['thickness'] is None else 'chosen for the texture'}); "
                    f"parameter map {summary['path']} set (Apply to use it); residual ΔE00 in the image "
                    f"{summary['residual']!r}")
        if self.auto_gains and summary["gains"]:
            g = summary["gains"]
            self.report({"INFO"}, "Spectral Skin: exposure and white balance corrected, R G B x "
                        f"{' '.join(f'{v:.3f}' for v in g['rgb_gains'])} ({g['exposure_stops']:+.2f} stops)")
        if summary["diagnosis"]:
            self.report({"WARNING"}, f"Spectral Skin: {summary['diagnosis']}"
                        + ("" if self.auto_gains else " (tick Correct Exposure and White Balance to apply the gains)"))
        return {"FINISHED"}


def albedo_task(job: core_albedo.AlbedoJob) -> Task:
    """From Albedo Texture's ``core.albedo.fit_and_write`` of ``job`` as a :class:`_Work` task."""
    def task(progress: Callable[[int, int], bool], before_write: Callable[[], bool]) -> dict[str, Any] | None:
        return core_albedo.fit_and_write(job, progress, before_write)
    return task


classes = (SPECTRAL_SKIN_OT_apply, SPECTRAL_SKIN_OT_remove, SPECTRAL_SKIN_OT_from_albedo_texture)
