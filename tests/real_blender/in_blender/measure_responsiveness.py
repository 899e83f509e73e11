"""How responsive Blender's UI stays while the add-on bakes, in a real Blender under Xvfb:

    RIG_OUT=out/ui BLENDER_RIG_PASSENV=RIG_OUT BLENDER_USER_RESOURCES=<where the zip is installed> \
      tools/blender_rig.sh run --gui -- --window-geometry 0 0 1280 800 FILE.blend \
      --python tests/real_blender/in_blender/measure_responsiveness.py

A first bake warms up (Blender compiles shaders for what it draws the first time, on llvmpipe a
stall of its own, and reacts to the new Lightmap UV maps), then 4 s idle, then the measured
re-bake, both as the Bake button runs them (the selected meshes, the file's settings), then quit.
results.json in RIG_OUT holds the 50 ms timer's gaps and the Properties editor's redraw
intervals, idle and during the bake, and the first bake's too. Any version of the add-on can be
measured: a bake's end is its modal operator leaving the window.
"""

import sys
import time
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import rig_lib as rig  # noqa: E402

recorder = rig.Recorder()
ticks_of_the_addon: list[float] = []  # seconds each modal tick of the add-on took (this version's)


def time_the_addons_ticks() -> None:
    try:
        ui_bake = rig.addon("blender.ui_bake")
    except KeyError:  # an add-on from before ui_bake: only the UI's side is measured
        return
    rig.timed_calls(ui_bake, "advance", ticks_of_the_addon)


def baking() -> bool:
    return any(name.lower() in {"radiosity_ot_bake", "radiosity.bake"} for name in rig.modal_operators())


def bake():
    """Steps: one bake as the button runs it; returns (started, the last tick while it ran, ended,
    invoke's result). After that last tick the add-on writes the result into the file."""
    with rig.override("PROPERTIES"):
        invoked = bpy.ops.radiosity.bake("INVOKE_DEFAULT", True)
    started = last = time.monotonic()
    while baking():
        last = time.monotonic()
        yield 0.05
    return started, last, time.monotonic(), sorted(invoked)


def steps():
    bpy.context.scene.radiosity.method = "progressive"  # the longer solve, as the README's numbers were measured
    rig.open_panel_first()
    time_the_addons_ticks()
    yield 1.0
    rig.scroll_to_panel()
    yield 8.0  # Blender's own start-up work
    first_started, _, first_ended, _ = yield from bake()
    rig.results["first_bake"] = recorder.stats(first_started, first_ended)
    ticks_of_the_addon.clear()
    yield 4.0
    idle_end = time.monotonic()
    started, solving, ended, invoked = yield from bake()
    yield 0.3
    rig.results["invoked"] = invoked
    rig.results["blender"] = bpy.app.version_string
    rig.results["invoke_seconds"] = round(started - idle_end, 3)  # the export, on the main thread
    rig.results["idle"] = recorder.stats(idle_end - 3.0, idle_end)
    rig.results["bake"] = recorder.stats(started, solving)
    rig.results["applying"] = recorder.stats(solving, ended + 0.3)
    rig.results["long_gaps"] = recorder.long_gaps(started, ended + 0.3)
    if ticks_of_the_addon:
        rig.results["addon_tick_max"] = round(max(ticks_of_the_addon), 3)
        rig.results["addon_ticks_longest"] = [round(s, 3) for s in sorted(ticks_of_the_addon)[-5:]]
    rig.results["images"] = sorted(i.name for i in bpy.data.images)
    rig.log(f"idle {rig.results['idle']}")
    rig.log(f"bake {rig.results['bake']}")
    yield 0.5
    recorder.stop()
    rig.quit_blender()


rig.run_steps(steps(), recorder)
