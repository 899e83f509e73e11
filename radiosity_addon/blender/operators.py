"""Operators: `radiosity.bake` (modal from the UI, blocking from scripts) and `radiosity.remove_bake`."""

from __future__ import annotations

import traceback

import bpy

from ..core import SolveCancelled
from . import apply
from .bake import USER_ERRORS, BakePlan, bake_blocking, choose_objects, finish, prepare

# The one bake running in the UI (the panel draws its progress); None when idle.
running: BakePlan | None = None

# events that may reach the UI during a modal bake (looking around is fine, editing is not)
NAVIGATION_EVENTS = {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "MOUSEMOVE", "INBETWEEN_MOUSEMOVE",
                     "TRACKPADPAN", "TRACKPADZOOM", "MOUSEROTATE", "NDOF_MOTION"}


def _one_line(error: BaseException) -> str:
    text = str(error).strip() or type(error).__name__
    return text.splitlines()[0]


def _report_failure(operator, error: BaseException) -> set:
    if isinstance(error, SolveCancelled):
        operator.report({"WARNING"}, _one_line(error))
    elif isinstance(error, USER_ERRORS):
        operator.report({"ERROR"}, f"Radiosity bake: {_one_line(error)}")
    else:  # a bug: keep the details on the console, give the user one line
        traceback.print_exception(error)
        operator.report({"ERROR"}, f"Radiosity bake failed unexpectedly ({type(error).__name__}:"
                                   f" {_one_line(error)}); nothing was changed, details on the console")
    return {"CANCELLED"}


def _redraw_properties(context) -> None:
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type in {"PROPERTIES", "STATUSBAR"}:
                area.tag_redraw()


class RADIOSITY_OT_bake(bpy.types.Operator):
    """Bake diffuse global illumination of the selected meshes into lightmaps by radiosity"""

    bl_idname = "radiosity.bake"
    bl_label = "Bake Radiosity"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        if running is not None:
            cls.poll_message_set("a radiosity bake is already running")
            return False
        return context.scene is not None

    def execute(self, context):
        try:
            objects = choose_objects(context)
            plan = bake_blocking(context, context.scene.radiosity.bake_options(objects), objects)
        except Exception as error:
            return _report_failure(self, error)
        for line in plan.warnings:
            self.report({"WARNING"}, line)
        self.report({"INFO"}, f"Radiosity bake: {plan.summary}")
        return {"FINISHED"}

    def invoke(self, context, event):
        global running
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            objects = choose_objects(context)
            plan = prepare(context, context.scene.radiosity.bake_options(objects), objects)
        except Exception as error:
            return _report_failure(self, error)
        for line in plan.warnings:
            self.report({"WARNING"}, line)
        running = plan
        plan.worker.start()
        window_manager = context.window_manager
        self._timer = window_manager.event_timer_add(0.2, window=context.window)
        window_manager.progress_begin(0.0, 1.0)
        window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        plan = running
        if plan is None:
            return {"CANCELLED"}
        if event.type == "ESC" and event.value == "PRESS":
            plan.worker.cancel()
        if event.type == "TIMER":
            progress = plan.worker.snapshot()
            context.window_manager.progress_update(progress.fraction)
            status = "Radiosity bake: cancelling..." if plan.worker.cancelled else progress.status_line()
            context.workspace.status_text_set(status)
            _redraw_properties(context)
            if plan.worker.done:
                return self._end(context, plan)
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"} if event.type in NAVIGATION_EVENTS else {"RUNNING_MODAL"}

    def _end(self, context, plan):
        global running
        window_manager = context.window_manager
        window_manager.event_timer_remove(self._timer)
        window_manager.progress_end()
        context.workspace.status_text_set(None)
        running = None
        _redraw_properties(context)
        try:
            summary = finish(plan)
        except Exception as error:
            return _report_failure(self, error)
        self.report({"INFO"}, f"Radiosity bake: {summary}")
        return {"FINISHED"}


class RADIOSITY_OT_remove_bake(bpy.types.Operator):
    """Remove the radiosity lightmaps of the selected objects (all baked objects if none is selected)
    and restore their original shading"""

    bl_idname = "radiosity.remove_bake"
    bl_label = "Remove Radiosity Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return running is None

    def execute(self, context):
        objects = [obj for obj in context.selected_objects if obj.type == "MESH"] \
            or [obj for obj in context.scene.objects if obj.type == "MESH"]
        restored = sum(1 for obj in objects if apply.remove_bake(obj))
        if restored == 0:
            self.report({"WARNING"}, "Radiosity bake: no baked object to restore")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Radiosity bake: restored the original shading of {restored} object(s)")
        return {"FINISHED"}


CLASSES = (RADIOSITY_OT_bake, RADIOSITY_OT_remove_bake)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    global running
    if running is not None:
        running.worker.cancel()
        running = None
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)


