"""The add-on as a user meets it, in a real Blender under Xvfb (run by tests/real_blender/):

    blender --enable-event-simulate --window-geometry 0 0 1280 800 cornell_box.blend --python gui_bake.py

RIG_CASES (comma-separated, in this order): bake (an edit, then a bake as the Bake button does,
in Material Preview: progress, the live preview, the text's fit, screenshots), responsive (a
re-bake in the Solid viewport: the UI's timer gaps and redraws), undo (Ctrl+Z three times), esc,
crash (a SIGSEGV in the solver process), revert and disable (during a bake), quit (during a bake:
ends the session). results.json in RIG_OUT records
what each case saw; the tests assert on it.
"""

import os
import sys
import time
from pathlib import Path

import blf
import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import rig_lib as rig  # noqa: E402

CASES = os.environ.get("RIG_CASES", "bake,responsive,undo,esc,crash,revert,disable").split(",")
MOVED = "tall_block"  # the object the undo case moves before the bake
recorder = rig.Recorder()
status_texts: list = []  # every status text the add-on set, in order
results = rig.results
shared: dict = {}  # what one case leaves the next (the undo case: the state before the bake)
# seconds after the Bake button in which Blender's loop slows whatever the solver does: in 4.3 under
# Xvfb its ticks came 0.11-0.16 s apart for 1.1 s with the child held asleep for 2 s (0.2-0.27 s with
# it solving, for up to 2 s)
BAKE_START = 2.0


def ui_bake():
    return rig.addon("blender.ui_bake")


def watch_status_text() -> None:
    module = ui_bake()
    original = module.set_status

    def recording(workspace, text):
        status_texts.append(text)
        original(workspace, text)
    module.set_status = recording


def invoke_bake() -> set:
    """As the Bake button does: in the Properties editor, allowed to push an undo step. Every case
    watches a progressive bake (its live preview, its progress, Esc mid-way); auto would pick the
    hemi-cube method for the Cornell sample (no preview, done in seconds), and `good`'s progressive
    bake is over in a few seconds, most of them the solver's start-up: `final` gives a bake of
    about half a minute to watch. Set at each bake: an undo takes the file back to before any
    setting made from Python."""
    bpy.context.scene.radiosity.method = "progressive"
    bpy.context.scene.radiosity.quality = "final"
    with rig.override("PROPERTIES"):
        return bpy.ops.radiosity.bake("INVOKE_DEFAULT", True)


def bake_is_modal() -> bool:
    return "RADIOSITY_OT_bake" in rig.modal_operators()


def label_fits(text: str, margin: float) -> dict:
    """The text's width in the UI font (blf), against what the Properties editor leaves a label."""
    scale = bpy.context.preferences.system.ui_scale
    blf.size(0, 11 * scale)
    width = blf.dimensions(0, text)[0]
    room = rig.region(rig.area("PROPERTIES")).width - margin * scale
    return {"text": text, "width": round(width, 1), "room": round(room, 1)}


def drawn_texts(bake) -> list:
    clock = bake.worker_clock
    panel = rig.addon("blender.panel")
    return [label_fits(clock.bar_text(), 30), label_fits(panel.sentence(clock.stage), panel.LABEL_MARGIN),
            label_fits("Esc cancels", panel.LABEL_MARGIN)]


def the_end_of_the_bake(module, bake, started: float) -> dict:
    """What a bake left behind once it ended (`module`: ui_bake as it was when the bake began)."""
    worker = bake.plan.worker
    registered = hasattr(bpy.types, "RADIOSITY_OT_bake")
    return {"seconds": round(time.monotonic() - started, 2), "running_after": module.running is not None,
            "modal_after": bake_is_modal(), "status_last": status_texts[-1] if status_texts else "none set",
            "child_ended": worker._process.poll() is not None, "files_removed": not worker.directory.exists(),
            "registered_after": registered, "poll_after": registered and bpy.ops.radiosity.bake.poll()}


def watched_bake(name: str, screenshots: bool):
    """Steps: a bake as the button does, sampled every 0.1 s (progress, previews, the UI's timer
    and redraws); with `screenshots`, the panel, viewport and status bar 1.5 s after the first
    preview. Leaves results[name]."""
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj.type == "MESH")
    yield 2.5  # an idle spell to compare with
    before = rig.file_state()
    invoked, started = invoke_bake(), time.monotonic()
    bake = ui_bake().running
    samples, previews, shot_at, counted = [], [], [], []

    def count_previews(worker):
        take_preview = worker.take_preview

        def counting():
            images = take_preview()
            if images is not None:
                previews.append(round(time.monotonic() - started, 2))
            return images
        worker.take_preview = counting
        counted.append(worker)
    # the add-on's own main-thread time per modal tick, apart for the ticks that step the preparation
    # (export, Cycles' passes, and the last one, which starts the solver) from those that take the solve's news
    ticks: list[float] = []
    preparing: list[bool] = []
    advance = ui_bake().advance
    untimed = rig.timed_calls(ui_bake(), "advance", ticks)
    timed = ui_bake().advance

    def advance_noted(running, *args, **kwargs):
        preparing.append(running.plan is None)
        return timed(running, *args, **kwargs)
    ui_bake().advance = advance_noted
    while ui_bake().running is bake:
        if bake.plan is not None and not counted:  # the preparation (export, Cycles' passes) is over
            count_previews(bake.plan.worker)
        clock = bake.worker_clock
        samples.append((round(time.monotonic() - started, 2), round(clock.fraction(), 3), clock.bar_text(),
                        clock.stage))
        if screenshots and previews and not shot_at and samples[-1][0] > previews[0] + 1.5:
            shot_at.append(samples[-1])
            results["texts_during"] = drawn_texts(bake)
            for shot, kind in (("panel_during_bake.png", "PROPERTIES"), ("viewport_during_bake.png", "VIEW_3D"),
                               ("status_bar_during_bake.png", "STATUSBAR")):
                rig.shot(shot, kind)
        yield 0.1
    untimed()
    ui_bake().advance = advance
    yield 0.3
    ended = time.monotonic()
    solving = started + samples[-1][0]  # the last tick before the result is applied
    estimated = next((started + s[0] for s in samples if "left" in s[2]), solving)
    results[name] = {"invoked": sorted(invoked), **the_end_of_the_bake(ui_bake(), bake, started),
                     "changed": rig.file_state() != before, "samples": samples, "previews_at": previews,
                     "shot_at": shot_at, "ui": recorder.stats(started, solving),
                     "ui_starting": recorder.stats(started, started + BAKE_START),
                     "ui_running": recorder.stats(started + BAKE_START, solving),
                     "ui_estimated": recorder.stats(estimated, solving),
                     "ui_applying": recorder.stats(solving, ended),
                     "long_gaps": recorder.long_gaps(started, ended), "idle_ui": recorder.stats(started - 2.0, started),
                     "images": sorted(i.name for i in bpy.data.images),
                     "last_bake": bpy.context.scene.radiosity.last_bake,
                     "tick_work": tick_work([t for t, p in zip(ticks, preparing) if not p]),
                     "preparation_steps": tick_work([t for t, p in zip(ticks, preparing) if p])}


def tick_work(ticks: list[float]) -> dict:
    return {"ticks": len(ticks), "max": round(max(ticks), 4) if ticks else None}


def case_responsive():
    """The UI's responsiveness during a re-bake, in the default Solid viewport. (A first bake adds
    the Lightmap UV maps, and Blender's own reaction to new UV maps stalls its UI for a few
    seconds on llvmpipe with no bake at all: that is measured by the bake case, not asserted.)"""
    shared["first_bake"] = rig.file_state()
    yield from watched_bake("responsive", screenshots=False)


def case_bake():
    """The bake in Material Preview: the light builds up in the viewport; screenshots."""
    rig.camera_view_material_preview()
    bpy.context.scene.eevee.taa_samples = 4  # viewport samples: llvmpipe renders EEVEE on the CPU
    yield 3.0  # Material Preview compiles its shaders
    edit_with_an_undo_step()
    shared["unbaked"] = rig.file_state()
    yield from watched_bake("bake", screenshots=True)
    panel = rig.addon("blender.panel")
    width = rig.region(rig.area("PROPERTIES")).width
    results["summary_lines"] = [label_fits(line, panel.LABEL_MARGIN) for line in
                                panel.fitted(bpy.context.scene.radiosity.last_bake, width,
                                             bpy.context.preferences.system.ui_scale)]
    yield 8.0  # the viewport compiles the final materials
    rig.scroll_to_panel()  # the summary is below the panel's buttons
    rig.redraw_all()
    yield 2.0
    rig.shot("viewport_baked.png", "VIEW_3D")
    rig.shot("panel_baked.png", "PROPERTIES")
    rig.shot("screen_baked.png")
    rig.shots_done()
    rig.area("VIEW_3D").spaces.active.shading.type = "SOLID"  # EEVEE on llvmpipe would slow what follows


def case_undo():
    """Ctrl+Z undoes one bake at a time and only it: the re-bake, then the first bake, then the
    user's edit before them."""
    steps = []
    for _ in range(3):
        with rig.override("VIEW_3D"):
            bpy.ops.ed.undo()
        yield 0.5
        state = rig.file_state()
        steps.append({"is_first_bake": state == shared["first_bake"], "is_unbaked": state == shared["unbaked"],
                      "moved_by": round(bpy.data.objects[MOVED].location.z - shared["start_z"], 4)})
    results["undo"] = steps


def edit_with_an_undo_step() -> None:
    """What a user does before baking: move an object (an undo step of its own)."""
    moved = bpy.data.objects[MOVED]
    shared["start_z"] = moved.location.z
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj == moved)
    with rig.override("VIEW_3D"):
        bpy.ops.transform.translate("EXEC_DEFAULT", True, value=(0.0, 0.0, 0.05))
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj.type == "MESH")


def interrupted(name: str, action, wait_for_preview: bool = False, compare_with: dict | None = None):
    """Start a bake, wait until it shows progress (or its first preview), do `action`, and record
    the state a second later against the state before (or `compare_with`)."""
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj.type == "MESH")
    before = rig.file_state()
    invoke_bake()
    module = ui_bake()
    bake = module.running
    yield from rig.wait_until(lambda: bake.plan is not None and (
        bake.plan.preview is not None if wait_for_preview else bake.plan.worker.clock.total is not None), 60)
    record = {"progress_before": round(bake.plan.worker.clock.fraction(), 3),
              "preview_shown": bake.plan.preview is not None}
    cancel, cancelled_at = bake.plan.worker.cancel, []
    bake.plan.worker.cancel = lambda: cancelled_at.append(time.monotonic()) or cancel()
    acted = time.monotonic()
    action()
    ended = yield from rig.wait_until(lambda: module.running is None and not bake_is_modal(), 10)
    record["ended_within"] = round(time.monotonic() - acted, 2) if ended else None
    if cancelled_at:  # Esc: from the operator's cancel to the end, without Blender's own event delay
        record["ended_after_cancel"] = round(time.monotonic() - cancelled_at[0], 2) if ended else None
    yield 1.0
    record.update(the_end_of_the_bake(module, bake, acted))
    record["modal_operators_after"] = rig.modal_operators()
    after, before = rig.file_state(), dict(before if compare_with is None else compare_with)
    if after["last_bake"] is None:  # the add-on is disabled: its settings cannot be read
        before["last_bake"] = None
    record["unchanged"] = after == before
    record["reports"] = rig.reports()[-2:]
    rig.window().event_simulate(type="MOUSEMOVE", value="NOTHING", x=600, y=400)
    yield 0.5  # an event lets Blender drop a modal handler it cleared (an operator unregistered)
    record["modal_operators_after_an_event"] = rig.modal_operators()
    results[name] = record
    rig.shot(f"after_{name}.png")


def press_escape():
    rig.window().event_simulate(type="ESC", value="PRESS")
    rig.window().event_simulate(type="ESC", value="RELEASE")


def case_esc():
    """Esc after the first live preview: the preview is taken back too."""
    rig.area("VIEW_3D").spaces.active.shading.type = "MATERIAL"
    yield from interrupted("esc", press_escape, wait_for_preview=True)
    rig.area("VIEW_3D").spaces.active.shading.type = "SOLID"


def case_crash():
    worker = rig.addon("blender.worker")
    original = worker.BOOTSTRAP
    main = "from radiosity_addon.solver_process.child import main"
    crash = ("import os, signal, radiosity_addon.core as core\n"
             "def crashing(scene, settings, progress=None, **kwargs):\n"
             "    progress(0.1, 'shot 1', {})\n"
             "    os.kill(os.getpid(), signal.SIGSEGV)\n"
             "core.solve = crashing\n")
    worker.BOOTSTRAP = original.replace(main, f"exec({crash!r}); {main}")
    try:
        before = rig.file_state()
        invoke_bake()
        yield from rig.wait_until(lambda: ui_bake().running is None, 60)
        yield 0.5
        results["crash"] = {"unchanged": rig.file_state() == before, "modal_after": bake_is_modal(),
                            "status_last": status_texts[-1] if status_texts else "none set", "blender_alive": True,
                            "reports": rig.reports()[-3:]}
    finally:
        worker.BOOTSTRAP = original


def revert():
    with rig.override():
        bpy.ops.wm.revert_mainfile()


def case_revert():
    """The reverted file is the one on disk, as this session opened it."""
    yield from interrupted("revert", revert, compare_with=shared["opened"])


def case_disable():
    yield from interrupted("disable", lambda: bpy.ops.preferences.addon_disable(module=rig.ADDON))


def case_quit():
    invoke_bake()
    bake = ui_bake().running
    yield from rig.wait_until(lambda: bake.plan is not None and bake.plan.worker.clock.total is not None, 60)
    results["quit"] = {"child_pid": bake.plan.worker._process.pid, "job_folder": str(bake.plan.worker.directory)}
    rig.quit_blender()
    yield 10.0


def steps():
    results["blender"] = bpy.app.version_string
    bpy.context.preferences.use_preferences_save = False  # the disable case must not outlive the session
    shared["opened"] = rig.file_state()
    rig.open_panel_first()
    rig.show_reports()
    watch_status_text()
    yield 1.0
    rig.scroll_to_panel()
    yield 5.0  # Blender's first draws are done
    for case in CASES:
        rig.log(f"case {case}")
        yield from globals()[f"case_{case}"]()
        results["done"] = results.get("done", []) + [case]  # assigned: results.json is written on each
    rig.shots_done()
    recorder.stop()
    rig.quit_blender()


rig.run_steps(steps(), recorder)
