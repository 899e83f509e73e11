"""Helpers for the scripts that run inside a real Blender (tests/real_blender/in_blender/*.py).

RIG_OUT names the folder where a script leaves results.json (rewritten after every step, so a
crash still leaves what was seen) and its screenshots. Screenshots are taken with xwd from a
helper thread: Blender's own screenshot operators give black images under Xvfb, and the main
thread must stay free, since the UI's responsiveness is what is measured.
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

import bpy

OUT = Path(os.environ.get("RIG_OUT", "/tmp/rig-out"))
OUT.mkdir(parents=True, exist_ok=True)
ADDON = "bl_ext.user_default.radiosity_baker"
T0 = time.monotonic()


def log(message: str) -> None:
    print(f"[rig {time.monotonic() - T0:6.1f}s] {message}", flush=True)


def addon(module: str):
    """A module of the installed extension, e.g. addon('blender.ui_bake')."""
    return sys.modules[f"{ADDON}.radiosity_addon.{module}"]


class Results(dict):
    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        (OUT / "results.json").write_text(json.dumps(self, indent=1, default=str))


results = Results()


def window():
    return bpy.context.window_manager.windows[0]


def area(kind: str):
    return next((a for a in window().screen.areas if a.type == kind), None)


def region(found_area, kind: str = "WINDOW"):
    return next(r for r in found_area.regions if r.type == kind)


def override(kind: str | None = None):
    """A context as if the mouse were over an area of that kind (None: the window only)."""
    if kind is None:
        return bpy.context.temp_override(window=window())
    found = area(kind)
    return bpy.context.temp_override(window=window(), area=found, region=region(found))


def crop_of(found_area) -> str:
    top = window().height - (found_area.y + found_area.height)
    return f"{found_area.width}x{found_area.height}+{found_area.x}+{top}"


_shots: queue.Queue = queue.Queue()


def _take_shots() -> None:
    while True:
        name, crop = _shots.get()
        path = OUT / name
        convert = ["convert", "xwd:-"] + (["-crop", crop, "+repage"] if crop else ["-resize", "50%"])
        xwd = subprocess.run(["xwd", "-root", "-silent"], capture_output=True)
        subprocess.run(convert + ["-strip", str(path)], input=xwd.stdout, capture_output=True)
        _shots.task_done()


threading.Thread(target=_take_shots, daemon=True).start()


def status_bar_crop() -> str:
    """The status bar is a global area of the window, not one of the screen's areas."""
    height = round(26 * bpy.context.preferences.system.ui_scale)
    return f"{window().width}x{height}+0+{window().height - height}"


def shot(name: str, kind: str | None = None) -> None:
    """Queue a screenshot of the whole screen (half size), of one area or of the status bar."""
    crop = None if kind is None else status_bar_crop() if kind == "STATUSBAR" else crop_of(area(kind))
    _shots.put((name, crop))
    log(f"screenshot {name}")


def shots_done() -> None:
    _shots.join()


def redraw_all() -> None:
    for found in window().screen.areas:
        found.tag_redraw()


def file_state() -> dict:
    """What a bake may change, as plain data: equal states mean an unchanged file."""
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    return {
        "images": sorted(i.name for i in bpy.data.images),
        "materials": sorted(m.name for m in bpy.data.materials),
        "nodes": sorted(f"{m.name}/{n.name}" for m in bpy.data.materials if m.node_tree for n in m.node_tree.nodes),
        "active_outputs": sorted(f"{m.name}/{n.name}" for m in bpy.data.materials if m.node_tree
                                 for n in m.node_tree.nodes
                                 if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output),
        "uv_maps": sorted(f"{o.data.name}/{uv.name}" for o in meshes for uv in o.data.uv_layers),
        "slots": sorted(f"{o.name}/{s.link}/{s.material.name if s.material else ''}"
                        for o in meshes for s in o.material_slots),
        # None once the add-on is disabled (Blender 5 keeps registered properties out of reach)
        "last_bake": getattr(getattr(bpy.context.scene, "radiosity", None), "last_bake", None),
    }


def timed_calls(module, name: str, seconds: list):
    """Wrap `module.name` so each call appends its seconds to `seconds` (the add-on's own main-thread
    time, e.g. ui_bake.advance per modal tick); returns what puts the original back."""
    original = getattr(module, name)

    def timed(*args, **kwargs):
        began = time.monotonic()
        try:
            return original(*args, **kwargs)
        finally:
            seconds.append(time.monotonic() - began)
    setattr(module, name, timed)
    return lambda: setattr(module, name, original)


def modal_operators() -> list[str]:
    """The window's running modal operators ('(freed)': one whose type is unregistered)."""
    def name(op):
        try:
            return op.bl_idname
        except (AttributeError, ValueError):  # 5.x gives None for it, 4.x a struct that cannot be read
            return "(freed)"
    return [name(op) for op in window().modal_operators]


def open_panel_first() -> None:
    """Render Properties with the Radiosity Bake panel open and in view (there is no API to open a
    panel: it is registered again without DEFAULT_CLOSED before the editor first draws it)."""
    panel = bpy.types.RENDER_PT_radiosity_bake
    bpy.utils.unregister_class(panel)
    panel.bl_options = set()
    bpy.utils.register_class(panel)
    area("PROPERTIES").spaces.active.context = "RENDER"


def scroll_to_panel() -> None:
    with override("PROPERTIES"):
        for _ in range(40):
            bpy.ops.view2d.scroll_down(deltay=0, page=True)


def camera_view_material_preview() -> None:
    view3d = area("VIEW_3D")
    space = view3d.spaces.active
    space.region_3d.view_perspective = "CAMERA"
    space.shading.type = "MATERIAL"
    space.overlay.show_overlays = False
    with override("VIEW_3D"):
        bpy.ops.view3d.view_center_camera()


def show_reports() -> None:
    """The timeline becomes an Info editor: the reports show in screenshots and can be read."""
    timeline = area("DOPESHEET_EDITOR") or area("TIMELINE")
    if timeline is not None:
        timeline.type = "INFO"


def reports() -> list[str]:
    """The session's reports so far, through the Info editor (copied as its Copy command does)."""
    if area("INFO") is None:
        return []
    with override("INFO"):
        bpy.ops.info.select_all(action="SELECT")
        bpy.ops.info.report_copy()
        bpy.ops.info.select_all(action="DESELECT")
    return [line for line in bpy.context.window_manager.clipboard.splitlines() if line.strip()]


def quit_blender() -> None:
    bpy.context.preferences.view.use_save_prompt = False
    with override():
        bpy.ops.wm.quit_blender()


class Recorder:
    """The UI's responsiveness: when a 50 ms main-thread timer really ran, when the Properties
    editor really redrew (a draw handler), for statistics over any span of time."""

    def __init__(self):
        self.ticks: list[float] = []
        self.draws: list[float] = []
        self._handle = bpy.types.SpaceProperties.draw_handler_add(lambda: self.draws.append(time.monotonic()), (),
                                                                  "WINDOW", "POST_PIXEL")

    def tick(self) -> None:
        self.ticks.append(time.monotonic())

    def stop(self) -> None:
        bpy.types.SpaceProperties.draw_handler_remove(self._handle, "WINDOW")

    @staticmethod
    def _gaps(times, start, end):
        inside = [t for t in times if start <= t <= end]
        return len(inside), sorted((b - a for a, b in zip(inside, inside[1:])), reverse=True)

    def long_gaps(self, start: float, end: float, longer_than: float = 0.2) -> list:
        """(seconds after start, gap) of the timer's gaps over `longer_than`: where the UI stalled."""
        inside = [t for t in self.ticks if start <= t <= end]
        return [(round(a - start, 2), round(b - a, 3)) for a, b in zip(inside, inside[1:]) if b - a > longer_than]

    def stats(self, start: float, end: float) -> dict:
        ticks, tick_gaps = self._gaps(self.ticks, start, end)
        draws, draw_gaps = self._gaps(self.draws, start, end)
        return {"seconds": round(end - start, 2), "timer_ticks": ticks,
                "timer_gap_max": round(tick_gaps[0], 3) if tick_gaps else None,
                "timer_gaps_largest": [round(g, 3) for g in tick_gaps[:5]],
                "redraws": draws, "redraw_gap_max": round(draw_gaps[0], 3) if draw_gaps else None,
                "redraw_gaps_largest": [round(g, 3) for g in draw_gaps[:5]]}


def run_steps(steps, recorder: Recorder | None = None) -> None:
    """Drive a generator of waits (seconds) from a 50 ms timer that also feeds the recorder; the
    timer survives file loads (persistent), so steps may revert or open files."""
    def tick():
        if recorder is not None:
            recorder.tick()
        now = time.monotonic()
        if now >= tick.due:
            try:
                tick.due = now + next(steps)
            except StopIteration:
                return None
            except Exception:  # noqa: BLE001 - a failed step ends Blender with what it found
                import traceback
                results["script_error"] = traceback.format_exc()
                log(results["script_error"])
                os._exit(3)
        return 0.05

    tick.due = 0.0
    bpy.app.timers.register(tick, first_interval=0.05, persistent=True)


def wait_until(condition, timeout: float, poll: float = 0.05):
    """Steps: wait until condition() (True) or the timeout (False)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        yield poll
    return True
