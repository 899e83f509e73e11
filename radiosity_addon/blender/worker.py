"""The bake's background half: solve and lay out lightmaps on ONE worker thread.

bpy-free on purpose. Inside Blender's UI the main thread owns Blender's OpenGL
context, so our moderngl context is created, used and released on the worker
thread alone; the main thread only reads the progress snapshot and the result.
Scripts and background runs use the same thread and simply wait for it, so
both paths run the same code.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from .. import core
from ..core import GPU, LightmapSettings, Scene, SolveCancelled, SolveError, SolveSettings


@dataclass
class Progress:
    fraction: float = 0.0
    message: str = "starting"
    started: float = field(default_factory=time.monotonic)

    @property
    def seconds_left(self) -> float | None:
        """A linear estimate; None until there is enough progress to extrapolate."""
        elapsed = time.monotonic() - self.started
        if self.fraction < 0.02 or elapsed < 1.0:
            return None
        return elapsed * (1.0 - self.fraction) / self.fraction

    def status_line(self) -> str:
        left = self.seconds_left
        eta = f", about {left:.0f} s left" if left is not None else ""
        return f"Radiosity bake {100 * self.fraction:.0f}%: {self.message}{eta} (Esc cancels)"


def lightmap_images(scene: Scene, solution, objects: list[str], settings: LightmapSettings, gpu: GPU) -> dict:
    """object name -> float32 (H, W, 4) linear RGBA, alpha = coverage, for `objects` only."""
    lightmaps = core.bake_lightmaps(scene, solution, settings, gpu=gpu, objects=list(objects))  # occluders get none
    images = {}
    for name in objects:
        if name not in lightmaps:
            raise SolveError(f"object '{name}': no lightmap was produced")
        images[name] = lightmaps[name].filled_image()
    return images


class BakeWorker:
    """Runs solve + lightmaps on its own thread. Poll `progress`, `done`; read `result` or `error`."""

    def __init__(self, scene: Scene, settings: SolveSettings, objects: list[str], lightmaps: LightmapSettings):
        self.scene, self.settings, self.objects, self.lightmaps = scene, settings, objects, lightmaps
        self.progress = Progress()
        self.result: tuple[dict, core.Report] | None = None  # (images, solve report)
        self.error: BaseException | None = None
        self._cancel = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="radiosity-bake", daemon=True)

    def start(self) -> "BakeWorker":
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()

    def wait(self, timeout: float | None = None) -> bool:
        self._thread.join(timeout)
        return self.done

    def snapshot(self) -> Progress:
        with self._lock:
            return Progress(self.progress.fraction, self.progress.message, self.progress.started)

    def _report(self, fraction, message, details=None):
        with self._lock:
            self.progress.fraction = float(min(max(fraction, 0.0), 1.0))
            self.progress.message = message

    def _run(self) -> None:
        try:
            with core.open_gpu() as gpu:
                # the solve takes 95 % of the bar, the lightmap layout the rest
                solution = core.solve(self.scene, self.settings,
                                      progress=lambda f, m, d=None: self._report(0.95 * f, m, d),
                                      should_cancel=self._cancel.is_set, gpu=gpu)
                if self._cancel.is_set():
                    raise SolveCancelled("cancelled")
                self._report(0.95, "writing lightmaps")
                images = lightmap_images(self.scene, solution, self.objects, self.lightmaps, gpu)
            if self._cancel.is_set():
                raise SolveCancelled("cancelled")
            self._report(1.0, "done")
            self.result = (images, solution.report)
        except BaseException as error:  # handed to the main thread, which reports it
            self.error = error
