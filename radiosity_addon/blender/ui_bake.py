"""The one bake running in Blender's UI, and every way it ends.

Started by the Bake button (the operator's invoke), advanced by the operator's modal timer, and
ended exactly once: finished, cancelled with Esc, failed (the solver's error, crash or hang), or
interrupted from outside — a file opened, reverted or saved, an undo or redo, the add-on disabled,
Blender quitting. Every way leaves no timer, status text or progress behind, and every way but
a finish leaves the file as it was (a save during a bake saves it so, too).
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass

import bpy
from bpy.app.handlers import persistent

from .bake import BakePlan, finish, rollback, show_preview, start
from .progress import BakeClock
from .worker import end_spare

TIMER_INTERVAL = 0.1  # seconds between the modal timer's ticks
REDRAW_INTERVAL = 0.25  # at most four redraws of the panel and status bar a second (a redraw is slow on llvmpipe)
PREVIEW_INTERVAL = 2.0  # seconds between live previews of a progressive bake
BUSY = "a radiosity bake is running (Esc cancels it)"


@dataclass
class UIBake:
    plan: BakePlan | None  # None while the bake is being prepared (`steps`)
    window_manager: object
    workspace: object  # its status text
    timer: object  # the modal operator's
    status: str | None = None  # the status text shown; the UI is redrawn only when it changes
    redrawn_at: float = 0.0
    steps: object = None  # the preparation's steps while they run (bake.prepare_steps)
    clock: BakeClock | None = None  # the bake's, from the export on (the solver's worker reports to it)

    @property
    def worker_clock(self) -> BakeClock:
        return self.clock if self.clock is not None else self.plan.worker.clock


running: UIBake | None = None


def redraw(window_manager, viewport: bool = True) -> None:
    """The panel and the status bar; the 3D views only when they have something new to show (a
    Material Preview redraw costs far more than the panel's)."""
    kinds = {"PROPERTIES", "STATUSBAR", "VIEW_3D"} if viewport else {"PROPERTIES", "STATUSBAR"}
    for window in window_manager.windows:
        for area in window.screen.areas:
            if area.type in kinds:
                area.tag_redraw()


def previews_visible(window_manager) -> bool:
    """A 3D viewport shows materials (Material Preview or Rendered): the Solid view cannot show a
    lightmap, so a preview for it would only cost the UI time."""
    return any(space.type == "VIEW_3D" and space.shading.type in {"MATERIAL", "RENDERED"}
               for window in window_manager.windows for area in window.screen.areas for space in area.spaces)


def set_status(workspace, text: str | None) -> None:
    """The status bar's text (None: Blender's own again); one place, so the tests can watch it."""
    workspace.status_text_set(text)


def begin(context, plan: BakePlan) -> UIBake:
    """Start the solver and the UI's part: the modal timer, progress, status text, the handlers."""
    start(plan)
    return _begin(context, UIBake(plan, context.window_manager, context.workspace, None))


def begin_preparing(context, steps, clock: BakeClock) -> UIBake:
    """The UI's part of a bake whose preparation (`bake.prepare_steps`) the timer's ticks run a step
    at a time, then its solver."""
    return _begin(context, UIBake(None, context.window_manager, context.workspace, None, steps=steps, clock=clock))


def _begin(context, bake: UIBake) -> UIBake:
    global running
    bake.timer = bake.window_manager.event_timer_add(TIMER_INTERVAL, window=context.window)
    bake.window_manager.progress_begin(0.0, 1.0)
    running = bake
    for handlers, handler in HANDLERS:
        if handler not in handlers:
            handlers.append(handler)
    return bake


def advance(bake: UIBake) -> bool:
    """One timer tick: a step of the preparation, or the solver's news, the live preview; progress
    and status. True once it ended. A step's fault is raised (the operator reports it)."""
    if bake.plan is None:
        try:
            bake.clock.preparing(next(bake.steps))
        except StopIteration as prepared:
            bake.plan, bake.steps = prepared.value, None
            start(bake.plan)
        _show(bake, bake.clock.status_line(), False)
        return False
    plan = bake.plan
    over = plan.worker.poll()
    shown = (not over and not plan.worker.cancelled and previews_visible(bake.window_manager)
             and show_preview(plan))
    clock = plan.worker.clock
    _show(bake, "Radiosity bake: cancelling..." if plan.worker.cancelled else clock.status_line(), shown)
    return over


def _show(bake: UIBake, status: str, shown: bool) -> None:
    bake.window_manager.progress_update(bake.worker_clock.fraction())
    now = time.monotonic()
    if shown or (status != bake.status and now - bake.redrawn_at >= REDRAW_INTERVAL):
        bake.status, bake.redrawn_at = status, now  # the panel shows the same numbers as the status bar
        set_status(bake.workspace, status)
        redraw(bake.window_manager, viewport=shown)


def abandon(bake: UIBake) -> None:
    """End a bake whose preparation or solver failed or was cancelled: the UI given back, the
    preparation closed (it takes back what it added) or the plan rolled back."""
    release(bake)
    if bake.plan is None:
        bake.steps.close()
    else:
        rollback(bake.plan)


def release(bake: UIBake) -> None:
    """Give the UI back: no timer, progress, status text or handlers stay."""
    global running
    if running is bake:
        running = None
    try:
        bake.window_manager.event_timer_remove(bake.timer)
        bake.window_manager.progress_end()
        set_status(bake.workspace, None)
    except ReferenceError:  # the window manager or workspace went with a file load
        pass
    for handlers, handler in HANDLERS:
        while handler in handlers:
            handlers.remove(handler)
    try:
        redraw(bake.window_manager)
    except ReferenceError:
        pass


def end(bake: UIBake) -> str:
    """The solver ended: apply its result (the summary line) or raise its error, the file unchanged."""
    release(bake)
    return finish(bake.plan)


def interrupt(why: str, keep_data: bool = True) -> None:
    """End the running bake from outside its operator. keep_data: take its changes back (the file
    stays open); else only end the solver (the file is about to be replaced)."""
    bake = running
    if bake is None:
        return
    release(bake)
    try:
        if bake.plan is None:
            bake.steps.close()  # the preparation takes back what it added
        elif keep_data:
            rollback(bake.plan)
    except Exception:  # a bug: say so on the console, but never leave the add-on stuck
        traceback.print_exc()
    finally:
        if bake.plan is not None:
            bake.plan.worker.discard()
    print(f"Radiosity bake: cancelled ({why}); nothing was changed")


@persistent
def _on_load_pre(*_args):
    interrupt("another file was opened or the file was reloaded", keep_data=False)


@persistent
def _on_save_pre(*_args):
    interrupt("the file was saved during the bake")


@persistent
def _on_undo_pre(*_args):
    interrupt("undo or redo during the bake")


HANDLERS = ((bpy.app.handlers.load_pre, _on_load_pre), (bpy.app.handlers.save_pre, _on_save_pre),
            (bpy.app.handlers.undo_pre, _on_undo_pre), (bpy.app.handlers.redo_pre, _on_undo_pre))


def unregister() -> None:
    interrupt("the add-on was disabled")
    end_spare()  # after the interrupt: its rollback may have started one
