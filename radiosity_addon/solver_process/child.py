"""The solver process: solve a job folder, lay out the lightmaps, write them, say how it went.

Started by the Blender side (`blender/worker.py`) as

    python -I -c BOOTSTRAP SYS_PATH_JSON JOB_DIR

so it imports numpy, moderngl and this package exactly as Blender would. Nothing here touches a
.blend: the worst a crash or a hung OpenGL driver can do is end this process.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import threading
import time
import traceback
from pathlib import Path

from .. import core
from . import protocol

PROGRESS_INTERVAL = 0.1  # seconds between progress messages (the solver reports every shot)


class Pipe:
    """Messages to the parent on a private copy of stdout: anything else printed (by a library, or
    a driver through the C runtime) goes to stderr instead, so it can never break a message."""

    def __init__(self):
        self._file = os.fdopen(os.dup(1), "w", buffering=1, encoding="utf-8")
        os.dup2(2, 1)
        sys.stdout = sys.stderr
        self._lock = threading.Lock()

    def send(self, kind: str, **fields) -> None:
        line = protocol.encode(kind, **fields)
        with self._lock:
            self._file.write(line)
            self._file.flush()


def watch_parent() -> None:
    """stdin closing means the parent is gone (Blender quit or crashed): end at once, whatever the
    solver is doing. (A cancel simply kills this process: it writes nothing outside its folder.)"""
    for _line in sys.stdin:
        pass
    os._exit(3)


def heartbeat(pipe: Pipe) -> None:
    while True:
        time.sleep(protocol.HEARTBEAT)
        pipe.send("alive")


def one_line(error: BaseException) -> str:
    text = str(error).strip() or type(error).__name__
    return text.splitlines()[0]


def lightmap_images(scene, solution, objects: list[str], settings, gpu) -> dict:
    """object name -> float32 (H, W, 4) linear RGBA, alpha = coverage, for `objects` only."""
    lightmaps = core.bake_lightmaps(scene, solution, settings, gpu=gpu, objects=list(objects))  # occluders get none
    missing = [name for name in objects if name not in lightmaps]
    if missing:
        raise core.SolveError(f"object '{missing[0]}': no lightmap was produced")
    return {name: lightmaps[name].filled_image() for name in objects}


class Solve:
    """One job: the solve with throttled progress, previews as files, the result as a file."""

    def __init__(self, directory: Path, pipe: Pipe):
        self.directory, self.pipe = directory, pipe
        self.last_progress = 0.0
        self.previews = 0

    def progress(self, fraction, message, details=None) -> None:
        now = time.monotonic()
        if now - self.last_progress >= PROGRESS_INTERVAL or fraction >= 1.0:
            self.last_progress = now
            eta = (details or {}).get("eta")
            # a solver that estimates its own time left (progressive refinement) says so even while
            # it has no estimate yet: its fraction is not linear in time and must not be extrapolated
            self.pipe.send("progress", fraction=float(fraction), message=str(message),
                           eta=None if eta is None else float(eta), own_estimate="eta" in (details or {}))

    def preview(self, scene, settings, objects, gpu):
        def show(snapshot) -> None:
            self.previews += 1
            path = self.directory / f"preview-{self.previews}.npz"
            # no direct light per texel in a snapshot: its light is the solve's, patch by patch
            quick = dataclasses.replace(settings, direct_per_texel=False)
            protocol.save_images(path, lightmap_images(scene, snapshot, objects, quick, gpu))
            self.pipe.send("preview", file=path.name)
        return show

    def run(self) -> None:
        scene, solve_settings, lightmap_settings, objects, preview_interval = protocol.read_job(self.directory)
        with core.open_gpu() as gpu:
            preview = (self.preview(scene, lightmap_settings, objects, gpu)
                       if preview_interval and solve_settings.method != "hemicube" else None)
            solution = core.solve(scene, solve_settings, progress=self.progress, gpu=gpu, preview=preview,
                                  preview_interval=preview_interval or 2.0)
            self.pipe.send("stage", name="lightmaps")
            images = lightmap_images(scene, solution, objects, lightmap_settings, gpu)
        protocol.save_images(self.directory / protocol.RESULT_FILE, images)
        report = solution.report
        self.pipe.send("result", file=protocol.RESULT_FILE, report=report.to_dict(), summary=report.summary_line())


def main(job_dir: str) -> int:
    pipe = Pipe()
    threading.Thread(target=watch_parent, name="watch-parent", daemon=True).start()
    threading.Thread(target=heartbeat, args=(pipe,), name="heartbeat", daemon=True).start()
    try:
        Solve(Path(job_dir), pipe).run()
    except core.USER_ERRORS as error:
        pipe.send("error", user=True, message=one_line(error))
    except Exception as error:  # a bug: the details on stderr (Blender's console), one line for the user
        traceback.print_exc()
        pipe.send("error", user=False, message=f"{type(error).__name__}: {one_line(error)}")
    return 0
