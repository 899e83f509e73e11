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

import numpy as np

from ..core import gl
from ..core.scene import Scene
from ..core.solution import SolveCancelled, SolveError, SolveSettings


@dataclass
class LightmapOptions:
    texel_density: float = 64.0  # texels per metre
    max_size: int = 1024
    resolution_overrides: dict = field(default_factory=dict)  # object name -> int (0 = from density)


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


def lightmap_images(scene: Scene, solution, objects: list[str], options: LightmapOptions, ctx) -> dict:
    """object name -> float32 (H, W, 4) linear RGBA, alpha = coverage, for `objects` only."""
    try:
        from ..core.lightmap import bake_lightmaps
    except ImportError:
        raise SolveError("the lightmap stage is not available in this build") from None
    overrides = {name: size for name, size in options.resolution_overrides.items()
                 if size > 0 and name in objects}
    # objects that only occlude get no image
    lightmaps = bake_lightmaps(scene, solution, texel_density=options.texel_density,
                               resolution_overrides=overrides or None, max_size=options.max_size, ctx=ctx,
                               objects=list(objects))
    images = {}
    for name in objects:
        if name not in lightmaps:
            raise SolveError(f"object '{name}': no lightmap was produced")
        images[name] = filled_image(lightmaps[name].levels)
    return images


def filled_image(levels: list) -> np.ndarray:
    """Level 0 of a coverage-aware mip chain with every uncovered texel filled from the finest
    level that covers it (push-pull); alpha keeps the coverage.

    Blender builds its own mipmaps by plain averaging, so texels outside the charts and their
    gutters must hold nearby values, not black, or distant mips darken the chart borders."""
    coarsest = levels[-1]
    rgb = coarsest[..., :3].astype(np.float32)
    covered = coarsest[..., 3] > 0
    rgb[~covered] = rgb[covered].mean(axis=0) if covered.any() else 0.0
    for level in reversed(levels[:-1]):
        height, width = level.shape[:2]
        coarse = np.repeat(np.repeat(rgb, 2, axis=0), 2, axis=1)[:height, :width]
        coarse = np.pad(coarse, ((0, height - coarse.shape[0]), (0, width - coarse.shape[1]), (0, 0)), mode="edge")
        rgb = np.where((level[..., 3] > 0)[..., None], level[..., :3], coarse)
    return np.ascontiguousarray(np.concatenate([rgb, levels[0][..., 3:4]], axis=2), dtype=np.float32)


class BakeWorker:
    """Runs solve + lightmaps on its own thread. Poll `progress`, `done`; read `result` or `error`."""

    def __init__(self, scene: Scene, settings: SolveSettings, objects: list[str], options: LightmapOptions):
        self.scene, self.settings, self.objects, self.options = scene, settings, objects, options
        self.progress = Progress()
        self.result: tuple[dict, dict] | None = None  # (images, solve report)
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
        from ..core.solve import solve

        try:
            ctx = gl.create_context()
            try:
                with ctx:
                    # the solve takes 95 % of the bar, the lightmap layout the rest
                    solution = solve(self.scene, self.settings,
                                     progress=lambda f, m, d=None: self._report(0.95 * f, m, d),
                                     should_cancel=self._cancel.is_set, ctx=ctx)
                    if self._cancel.is_set():
                        raise SolveCancelled("cancelled")
                    self._report(0.95, "writing lightmaps")
                    images = lightmap_images(self.scene, solution, self.objects, self.options, ctx)
            finally:
                ctx.release()
            if self._cancel.is_set():
                raise SolveCancelled("cancelled")
            self._report(1.0, "done")
            self.result = (images, solution.report)
        except BaseException as error:  # handed to the main thread, which reports it
            self.error = error
