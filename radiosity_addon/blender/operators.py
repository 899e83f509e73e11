"""Operators: `radiosity.bake` (modal from the UI, blocking from scripts) and `radiosity.remove_bake`."""

from __future__ import annotations

import traceback

import bpy

from ..core import SolveCancelled
from . import apply, ui_bake
from .bake import USER_ERRORS, bake_blocking, choose_objects, prepare_steps
from .errors import BakeError
from .progress import BakeClock

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


def refusal(context) -> str | None:
    """Why the Bake button is disabled right now (the tooltip and the panel say it), or None."""
    if ui_bake.running is not None:
        return ui_bake.BUSY
    if context.scene is None:
        return "no scene to bake"
    try:
        choose_objects(context)
    except BakeError as error:
        return str(error)
    return None


class RADIOSITY_OT_bake(bpy.types.Operator):
    """Bake diffuse global illumination of the selected meshes into lightmaps by radiosity"""

    bl_idname = "radiosity.bake"
    bl_label = "Bake Radiosity"
    # one undo step for the whole bake (pushed when it finishes, none when cancelled); not REGISTER:
    # Repeat Last or Adjust Last Operation would re-run a whole bake as a blocking script call
    bl_options = {"UNDO"}

    @classmethod
    def poll(cls, context):
        reason = refusal(context)
        if reason is not None:
            cls.poll_message_set(reason)
        return reason is None

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
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            objects = choose_objects(context)
            clock = BakeClock()
            steps = prepare_steps(context, context.scene.radiosity.bake_options(objects), objects,
                                  preview_interval=ui_bake.PREVIEW_INTERVAL, clock=clock)
            clock.preparing(next(steps))  # the checks: a refusal is reported at once
            self._bake = ui_bake.begin_preparing(context, steps, clock)
        except Exception as error:
            return _report_failure(self, error)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        bake = self._bake
        if ui_bake.running is not bake:  # interrupted from outside (a file loaded, the add-on disabled)
            return {"CANCELLED"}
        if event.type == "ESC" and event.value == "PRESS":
            if bake.plan is None:  # still preparing: nothing runs yet to cancel
                ui_bake.abandon(bake)
                self.report({"INFO"}, "Radiosity bake: cancelled; nothing was changed")
                return {"CANCELLED"}
            bake.plan.worker.cancel()
        if event.type == "TIMER":
            preparing = bake.plan is None
            try:
                over = ui_bake.advance(bake)
            except Exception as error:  # a step of the preparation failed, or the solver did not start
                ui_bake.abandon(bake)
                return _report_failure(self, error)
            if preparing and bake.plan is not None:
                for line in bake.plan.warnings:
                    self.report({"WARNING"}, line)
            if not over:
                return {"RUNNING_MODAL"}
            try:
                summary = ui_bake.end(bake)
            except Exception as error:
                return _report_failure(self, error)
            self.report({"INFO"}, f"Radiosity bake: {summary}")
            return {"FINISHED"}
        return {"PASS_THROUGH"} if event.type in NAVIGATION_EVENTS else {"RUNNING_MODAL"}

    def cancel(self, context):
        """Blender drops the modal handler (a file is loaded, the window closes, Blender quits)."""
        if ui_bake.running is getattr(self, "_bake", None):
            ui_bake.interrupt("Blender ended the bake's operator")


class RADIOSITY_OT_remove_bake(bpy.types.Operator):
    """Remove the radiosity lightmaps of the selected objects (all baked objects if none is selected)
    and restore their original shading"""

    bl_idname = "radiosity.remove_bake"
    bl_label = "Remove Radiosity Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if ui_bake.running is not None:
            cls.poll_message_set(ui_bake.BUSY)
            return False
        return True

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
    ui_bake.unregister()
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)


