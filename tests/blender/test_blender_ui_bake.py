"""The bake as the Bake button runs it (modal, the solve in a child process), driven tick by tick as
Blender's event loop would: Esc, the live preview, and every way a bake can be interrupted from
outside (a file opened, a save, the add-on disabled). The real Blender runs the same in
tests/real_blender/."""

from __future__ import annotations

import time
from types import SimpleNamespace

import blender_support as support
import bpy
import numpy as np
import pytest

from radiosity_addon.blender import operators, ui_bake
from radiosity_addon.blender.bake import prepare_steps
from radiosity_addon.blender.progress import BakeClock
from radiosity_addon.blender.live_preview import PREVIEW_SUFFIX

WAIT_FOR_ESC = """
import time
import radiosity_addon.core as core
def solve_until_cancelled(scene, settings, progress=None, **kwargs):
    # Esc kills this child process: it gets no should_cancel, so it just waits to be killed
    progress(0.25, "waiting for Esc", {})
    time.sleep(60)
    raise core.SolveCancelled("not killed within 60 s")
core.solve = solve_until_cancelled
"""


class FakeWindowManager:
    """One window with one 3D viewport in the given shading; records timers and progress."""

    def __init__(self, shading="MATERIAL"):
        self.progress, self.timers, self.progress_ended, self.redraws = [], [], False, 0
        space = SimpleNamespace(type="VIEW_3D", shading=SimpleNamespace(type=shading))
        area = SimpleNamespace(type="VIEW_3D", spaces=[space], tag_redraw=self.redrawn)
        self.windows = [SimpleNamespace(screen=SimpleNamespace(areas=[area]))]

    def redrawn(self):
        self.redraws += 1

    def event_timer_add(self, interval, window=None):
        self.timers.append(object())
        return self.timers[-1]

    def event_timer_remove(self, timer):
        self.timers.remove(timer)

    def progress_begin(self, low, high):
        pass

    def progress_update(self, value):
        self.progress.append(value)

    def progress_end(self):
        self.progress_ended = True


class ButtonBake:
    """The operator's invoke and modal with a stand-in window manager and status bar: the bake is
    prepared a step a tick (the export, each Cycles pass), then solved."""

    def __init__(self, context, preview_interval=None, shading="MATERIAL"):
        self.status, self.reports = [], []
        self.ui = SimpleNamespace(window_manager=FakeWindowManager(shading), window=None,
                                  workspace=SimpleNamespace(status_text_set=self.status.append))
        clock = BakeClock()
        steps = prepare_steps(context, context.scene.radiosity.bake_options(context.selected_objects),
                              preview_interval=preview_interval, clock=clock)
        clock.preparing(next(steps))
        self.baking = ui_bake.begin_preparing(self.ui, steps, clock)
        # the operator as Blender gives it to `modal`: its reports, and the bake `invoke` began
        self.operator = SimpleNamespace(report=lambda kind, text: self.reports.append((kind, text)),
                                        _bake=self.baking)
        self.result = {"RUNNING_MODAL"}

    @property
    def plan(self):
        return self.baking.plan

    def tick(self, event_type="TIMER"):
        event = SimpleNamespace(type=event_type, value="PRESS")
        self.result = operators.RADIOSITY_OT_bake.modal(self.operator, self.ui, event)
        return self.result

    def run_until(self, condition=lambda: False, timeout=300.0):
        deadline = time.monotonic() + timeout
        while self.result == {"RUNNING_MODAL"} and (self.plan is None or not condition()):  # prepared first
            assert time.monotonic() < deadline, "the bake never got there"
            self.tick()
            time.sleep(0.02)
        return self.result

    def assert_ui_given_back(self):
        assert ui_bake.running is None
        assert self.ui.window_manager.timers == [] and self.ui.window_manager.progress_ended
        assert self.status[-1] is None  # the status bar's own text is back
        assert not any(handler in handlers for handlers, handler in ui_bake.HANDLERS)
        # the solver process has ended and its files are gone (after a bake that succeeded, a
        # thread reaps it and removes them: within moments)
        assert support.gone_within(lambda: self.plan.worker.process.poll() is not None
                                   and not self.plan.worker.directory.exists(), 10)
        assert bpy.ops.radiosity.bake.poll()


@pytest.fixture(autouse=True)
def no_bake_left():
    yield
    ui_bake.interrupt("the test ended")
    support.ensure_addon()


def test_escape_in_the_modal_loop_cancels_and_leaves_the_file_unchanged(monkeypatch):
    support.inject_into_solver(monkeypatch, WAIT_FOR_ESC)
    context = support.open_blend(support.CORNELL, method="progressive", subdivision=4)
    before = support.blend_state()
    bake = ButtonBake(context)
    assert support.blend_state() != before  # prepare made the Lightmap UV maps
    bake.run_until(lambda: bake.plan.worker.clock.stage == "waiting for Esc")
    assert not bpy.ops.radiosity.bake.poll() and operators.refusal(context) == ui_bake.BUSY
    assert bake.tick() == {"RUNNING_MODAL"}
    assert "Esc cancels" in bake.status[-1]
    bake.tick("ESC")
    assert bake.run_until() == {"CANCELLED"}
    assert bake.reports[-1][0] == {"WARNING"} and "cancelled" in bake.reports[-1][1]
    bake.assert_ui_given_back()
    assert support.blend_state() == before


def test_the_preparation_runs_a_step_a_tick_and_escape_during_it_changes_nothing():
    """The export and each Cycles pass of the materials are steps of their own: the status bar says
    which runs, and the UI answers between them; Esc before the solver starts leaves the file as it
    was (the sample has its Lightmap UV maps; the Cornell box's made then are taken back: the Esc test)."""
    context = support.open_blend(support.SAMPLES / "textured.blend", method="progressive", subdivision=2)
    bake = ButtonBake(context)
    assert bake.plan is None and bake.baking.clock.stage.startswith("exporting")  # what the next tick does
    stages = []
    while bake.plan is None:
        bake.tick()
        stages.append(bake.status[-1])
    assert any("with Cycles" in stage for stage in stages)  # the textured floor's material maps
    bake.run_until()
    assert bake.result == {"FINISHED"}
    context = support.open_blend(support.SAMPLES / "textured.blend", method="progressive", subdivision=2)
    before = support.blend_state()
    bake = ButtonBake(context)
    bake.tick()
    assert bake.tick("ESC") == {"CANCELLED"} and bake.plan is None
    context = support.open_blend(support.CORNELL, method="progressive", subdivision=2)
    before = support.blend_state()
    bake = ButtonBake(context)
    assert support.blend_state() != before  # the first step made the Lightmap UV maps
    assert bake.tick("ESC") == {"CANCELLED"}
    assert ui_bake.running is None and bake.ui.window_manager.timers == [] and bake.status[-1] is None
    assert support.blend_state() == before


def quick_progressive(context) -> None:
    """Fewer elements and a loose tolerance: previews still come every 0.2 s, the bake ends sooner."""
    context.scene.radiosity.elements = "2"
    context.scene.radiosity.tolerance = 0.05


def preview_images():
    return sorted(image.name for image in bpy.data.images if image.name.endswith(PREVIEW_SUFFIX))


def test_live_preview_shows_the_light_building_up_then_the_final_images_replace_it():
    context = support.open_blend(support.CORNELL, method="progressive", subdivision=3)
    quick_progressive(context)
    objects = sorted(obj.name for obj in context.selected_objects)
    bake = ButtonBake(context, preview_interval=0.2)
    snapshots = []

    def record():
        if bake.plan.preview is not None and bake.plan.preview.images:
            floor = support.image_rgba(bpy.data.images["floor_lightmap" + PREVIEW_SUFFIX])
            if not snapshots or not np.array_equal(floor, snapshots[-1]):
                snapshots.append(floor)
        return len(snapshots) >= 2

    bake.run_until(record)
    assert preview_images() == [f"{name}_lightmap{PREVIEW_SUFFIX}" for name in objects]
    for obj in context.selected_objects:  # every object shows its preview, on the Lightmap UV map
        for slot in obj.material_slots:
            assert support.lightmap_wiring(slot.material)["image"] == f"{obj.name}_lightmap{PREVIEW_SUFFIX}"
    lit = [rgba[..., :3][rgba[..., 3] > 0].mean() for rgba in snapshots]
    assert lit[0] > 0 and lit[1] != lit[0]  # light so far, and it changes as the solve goes on
    assert bake.run_until() == {"FINISHED"}
    assert preview_images() == []
    for obj in context.selected_objects:
        for slot in obj.material_slots:
            assert support.lightmap_wiring(slot.material)["image"] == f"{obj.name}_lightmap"
    bake.assert_ui_given_back()


def test_a_solid_viewport_gets_no_preview_it_could_not_show():
    context = support.open_blend(support.CORNELL, method="progressive", subdivision=4)
    bake = ButtonBake(context, preview_interval=0.2, shading="SOLID")
    bake.run_until(lambda: bake.plan.worker.preview_waiting)  # a snapshot came, and waits unshown
    assert bake.plan.preview is None and preview_images() == []
    assert bake.ui.window_manager.redraws == 0  # nor was the viewport redrawn for it
    bake.tick("ESC")
    assert bake.run_until() == {"CANCELLED"}


def test_cancel_after_a_preview_restores_an_earlier_bake_and_unbaked_objects_exactly():
    context = support.open_blend(support.CORNELL, method="progressive", subdivision=3)
    quick_progressive(context)
    meshes = list(context.selected_objects)
    support.select_only([bpy.data.objects["floor"]])
    assert bpy.ops.radiosity.bake() == {"FINISHED"}  # the floor shows an earlier bake, the rest none
    support.select_only(meshes)
    before = support.blend_state()
    bake = ButtonBake(context, preview_interval=0.2)
    bake.run_until(lambda: bake.plan.preview is not None)
    floor_material = bpy.data.objects["floor"].material_slots[0].material
    assert support.lightmap_wiring(floor_material)["image"] == "floor_lightmap" + PREVIEW_SUFFIX
    bake.tick("ESC")
    assert bake.run_until() == {"CANCELLED"}
    bake.assert_ui_given_back()
    assert support.blend_state() == before


def test_opening_a_file_during_a_bake_ends_it_without_a_stuck_state(monkeypatch):
    support.inject_into_solver(monkeypatch, WAIT_FOR_ESC)
    context = support.open_blend(support.CORNELL)
    bake = ButtonBake(context)
    bake.run_until(lambda: bake.plan.worker.clock.stage == "waiting for Esc")
    bpy.ops.wm.open_mainfile(filepath=str(support.ROOM), load_ui=False)
    assert bake.tick() == {"CANCELLED"}  # the operator sees it ended and leaves
    bake.assert_ui_given_back()


def test_saving_during_a_bake_cancels_it_and_saves_the_file_as_it_was(monkeypatch, tmp_path):
    support.inject_into_solver(monkeypatch, WAIT_FOR_ESC)
    context = support.open_blend(support.CORNELL)
    before = support.blend_state()
    bake = ButtonBake(context)
    bake.run_until(lambda: bake.plan.worker.clock.stage == "waiting for Esc")
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "saved.blend"))
    assert bake.tick() == {"CANCELLED"}
    bake.assert_ui_given_back()
    assert support.blend_state() == before
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "saved.blend"), load_ui=False)
    assert support.blend_state() == before


def test_disabling_the_addon_during_a_bake_takes_everything_back(monkeypatch):
    from radiosity_addon import blender

    support.inject_into_solver(monkeypatch, WAIT_FOR_ESC)
    context = support.open_blend(support.CORNELL)
    before = support.blend_state()
    bake = ButtonBake(context)
    bake.run_until(lambda: bake.plan.worker.clock.stage == "waiting for Esc")
    blender.unregister()
    try:
        assert not hasattr(bpy.types, "RADIOSITY_OT_bake")
        assert ui_bake.running is None and bake.status[-1] is None and bake.ui.window_manager.timers == []
        assert bake.plan.worker.process.poll() is not None
        assert support.blend_state() == before  # no Lightmap UV map stays behind
    finally:
        blender.register()


def test_the_bake_button_says_why_it_is_disabled():
    context = support.open_blend(support.CORNELL)
    assert bpy.ops.radiosity.bake.poll() and operators.refusal(context) is None
    support.select_only([])
    assert not bpy.ops.radiosity.bake.poll()
    assert operators.refusal(context) == "select the mesh objects to bake first"
    support.select_only([bpy.data.objects["floor"]])
    bpy.ops.object.mode_set(mode="EDIT")
    assert not bpy.ops.radiosity.bake.poll()
    assert operators.refusal(bpy.context) == "switch to Object Mode to bake"
    bpy.ops.object.mode_set(mode="OBJECT")
    assert bpy.ops.radiosity.bake.poll()
