"""The solver process: solve a job folder, lay out the lightmaps, write them, say how it went.

Started by the Blender side (`blender/worker.py`) as

    python -I -c BOOTSTRAP SYS_PATH_JSON JOB_DIR

so it imports numpy, moderngl and this package exactly as Blender would. Nothing here touches a
.blend: the worst a crash or a hung OpenGL driver can do is end this process.

With JOB_DIR `-` it is a spare, started ahead of the bake that will use it: it does its imports
and opens its OpenGL context, then waits for the job folder on stdin (one JSON string and a
newline). That takes the start of a process off every bake but the first of a Blender session.
Before it says it is ready it warms its context with a small solve (`warm_up`): a job's first
use of each program in a process costs it compiling that program and llvmpipe its shader
variants, and numpy its first calls. It still solves one job and ends: a crash or a cancel costs
only itself.
"""

from __future__ import annotations

import dataclasses
import json
import os
import queue
import sys
import threading
import time
import traceback
from pathlib import Path

from .. import core
from . import protocol

PROGRESS_INTERVAL = 0.1  # seconds between progress messages (the solver reports every shot)
SPARE = "-"  # the job folder argument of a spare: it reads its folder from stdin
SPARE_IDLE = 600.0  # seconds a spare waits for a job before it ends on its own


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


def watch_parent(jobs: queue.Queue) -> None:
    """A line on stdin is a spare's job folder; stdin closing means the parent is gone (Blender quit
    or crashed): end at once, whatever the solver is doing. (A cancel simply kills this process: it
    writes nothing outside its folder.)"""
    for line in sys.stdin:
        try:
            jobs.put(json.loads(line))
        except ValueError:  # not a job: never stop watching for the parent's end over it
            continue
    os._exit(3)


WARM_UP_SCENE = "cornell-box"  # bundled with the package (core/scene/scenes)
WARM_UP_QUALITY = "draft"  # the cheapest preset compiles the same programs; a dearer one warms no better


def ready_gpu():
    """A spare's OpenGL context, opened before its job comes; None when there is none (the job
    then tries again, and reports why it cannot as every bake does)."""
    try:
        return core.GPU()
    except Exception:
        return None


def warm_up(gpu) -> bool:
    """Solve and bake the bundled Cornell box on `gpu` and drop what it made but the compiled
    programs: the hemi-cube method's and the lightmaps' programs are then compiled (with llvmpipe,
    their shader variants too) and numpy's first calls made before a job comes, not in it. True
    if it ran; a failure leaves the spare as it was (the job then meets and reports the same problem)."""
    try:
        with core.open_gpu(gpu):
            scene = core.load_scene(WARM_UP_SCENE)
            solution = core.solve(scene, core.SolveSettings.preset(WARM_UP_QUALITY), gpu=gpu)
            core.bake_lightmaps(scene, solution, core.LightmapSettings.preset(WARM_UP_QUALITY), gpu=gpu)
        return True
    except Exception:
        return False
    finally:
        try:
            gpu.release_targets()
        except Exception:
            pass


def heartbeat(pipe: Pipe) -> None:
    while True:
        time.sleep(protocol.HEARTBEAT)
        pipe.send("alive")


def one_line(error: BaseException) -> str:
    text = str(error).strip() or type(error).__name__
    return text.splitlines()[0]


def lightmap_images(scene, solution, objects: list[str], settings, gpu, progress=None) -> dict:
    """object name -> float32 (H, W, 4) linear RGBA, alpha = coverage, for `objects` only."""
    lightmaps = core.bake_lightmaps(scene, solution, settings, gpu=gpu, objects=list(objects),  # occluders get none
                                    progress=progress)
    missing = [name for name in objects if name not in lightmaps]
    if missing:
        raise core.SolveError(f"object '{missing[0]}': no lightmap was produced")
    return {name: lightmaps[name].filled_image() for name in objects}


class Solve:
    """One job: the solve with throttled progress, previews as files, the result as a file."""

    def __init__(self, directory: Path, pipe: Pipe, gpu=None):
        self.directory, self.pipe, self.gpu = directory, pipe, gpu
        self.last_progress = 0.0
        self.previews = 0
        self.lightmap_seconds = 0.0  # predicted for the lightmaps, after the solve

    def progress(self, fraction, message, details=None, after: float = 0.0) -> None:
        """A stage's report (core.timing.StagePlan): its "eta" the solve's or the lightmaps' time left,
        plus `after` seconds predicted for what follows: the job's time left, what the bar shows."""
        now = time.monotonic()
        if now - self.last_progress >= PROGRESS_INTERVAL or fraction >= 1.0:
            self.last_progress = now
            eta = (details or {}).get("eta")
            self.pipe.send("progress", fraction=float(fraction), message=str(message),
                           eta=None if eta is None else float(eta) + after, own_estimate=True)

    def solving(self, fraction, message, details=None) -> None:
        self.progress(fraction, message, details, after=self.lightmap_seconds)

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
        self.lightmap_seconds = core.lightmap_seconds(scene, core.lightmap_sizes(scene, lightmap_settings, objects),
                                                      lightmap_settings)
        own = self.gpu or core.GPU()
        with own, core.open_gpu(own) as gpu:
            preview = (self.preview(scene, lightmap_settings, objects, gpu)
                       if preview_interval and solve_settings.method != "hemicube" else None)
            solution = core.solve(scene, solve_settings, progress=self.solving, gpu=gpu, preview=preview,
                                  preview_interval=preview_interval or 2.0)
            self.pipe.send("stage", name="lightmaps")
            images = lightmap_images(scene, solution, objects, lightmap_settings, gpu, progress=self.progress)
            # the result before the context's release: the parent takes it and ends this process
            protocol.save_images(self.directory / protocol.RESULT_FILE, images)
            report = solution.report
            density = core.chosen_texel_density(scene, lightmap_settings, objects)
            automatic = " · auto density" if lightmap_settings.texel_density == 0 else ""  # pieces the panel wraps at
            self.pipe.send("result", file=protocol.RESULT_FILE, report=report.to_dict() | {"texel_density": density},
                           summary=f"{report.summary_line()} · {density:.0f} texels/m{automatic}")


def main(job_dir: str) -> int:
    pipe = Pipe()
    jobs: queue.Queue = queue.Queue()
    threading.Thread(target=watch_parent, args=(jobs,), name="watch-parent", daemon=True).start()
    gpu = None
    if job_dir == SPARE:
        gpu = ready_gpu()
        if gpu is not None:
            warm_up(gpu)
        pipe.send("ready")
        try:
            job_dir = jobs.get(timeout=SPARE_IDLE)
        except queue.Empty:  # no bake came: give its memory back
            return 0
    threading.Thread(target=heartbeat, args=(pipe,), name="heartbeat", daemon=True).start()
    try:
        Solve(Path(job_dir), pipe, gpu).run()
    except core.USER_ERRORS as error:
        pipe.send("error", user=True, message=one_line(error))
    except Exception as error:  # a bug: the details on stderr (Blender's console), one line for the user
        traceback.print_exc()
        pipe.send("error", user=False, message=f"{type(error).__name__}: {one_line(error)}")
    return 0
