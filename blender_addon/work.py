"""A computing step in a worker thread, and what the operators that start one from the UI share (no numerics
here): :class:`Work` runs the step (Apply's ``apply.compute``, From Albedo Texture's ``core.albedo.fit_and_write``;
the core releases the GIL) with its progress and a cancel flag; :class:`ModalWork`, the operators' mixin, shows the
progress with a modal timer, cancels on Esc (until the step starts writing) and changes Blender's data only once
the step succeeded (its ``_succeed``), on the main thread; on a cancel or an error nothing is changed.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import bpy

from .core import describe_error

# A computing step for a worker: task(progress, before_write) -> its result, None when cancelled before writing.
# (Work is not a typing.Generic: a Generic class in the add-on made bpy 4.2 crash at interpreter exit.)
Task = Callable[[Callable[[int, int], bool], Callable[[], bool]], Any]


class Work:
    """A computing step in a worker thread (Apply's ``apply.compute``, From Albedo Texture's
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


class ModalWork:
    """What Apply and From Albedo Texture share when started from the UI: the computing step in a :class:`Work`
    while a modal timer shows its progress (the progress bar and the status text) and Esc cancels it (until it starts
    writing); once it has succeeded, :meth:`_succeed` changes Blender's data on the main thread, and on a cancel or an
    error nothing is changed. A mixin of the two operators (before bpy.types.Operator in their bases)."""

    if TYPE_CHECKING:
        def report(self, kind: set[str], message: str) -> None: ...

    _work: Work | None = None
    _timer: Any = None
    _writing_state = "writing the maps"

    def _start(self, context: bpy.types.Context, work: Work) -> set[str]:
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
