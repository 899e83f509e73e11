"""Progressive refinement radiosity on the GPU (dissertation §4.2; Coombe et al. 2004).

Per shot: select the patch of largest unshot power (residual mip, GPU
reduction), render its hemispherical visibility map, add ΔB to every receiving
element, clear its residual, rebuild the residual's mip levels. Stops when the
unshot power falls under tolerance × emitted power, or at the shot budget.

Energy is booked in float64 on the CPU from the few numbers read back per shot
(see `shooting.READBACK`): each shot's power comes from the shooter's mean
residual, and the GPU sums (fixed point, exact to ~1e-9 per work group) say
which fraction of it hit a receiver and which fraction was reflected.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .element_textures import ElementTextures
from .patches import Patches
from .scene import Scene
from .shooting import READBACK, Gatherer, PatchBuffers, Selector, patch_shooter
from .solution import SolveCancelled, SolveSettings, StageTimer
from .visibility import VARIANTS, VisibilityMap

DEFAULT_VISIBILITY_RESOLUTION = 512


class EnergyLedger:
    """Power accounts in float64 (RGB): emitted = absorbed + escaped + unshot."""

    def __init__(self, emitted: np.ndarray):
        self.emitted = np.asarray(emitted, dtype=np.float64)
        self.shot = np.zeros(3)
        self.absorbed = np.zeros(3)
        self.reflected = np.zeros(3)
        self.escaped = np.zeros(3)
        self.pending = None  # power of the shot whose fractions are not yet read back

    def settle(self, fractions: np.ndarray) -> None:
        """Book the pending shot with its (hit, reflected RGB) fractions."""
        if self.pending is None:
            return
        power, self.pending = self.pending, None
        hit = min(float(fractions[0]), 1.0)
        reflected = np.minimum(fractions[1:4], hit)
        self.shot += power
        self.reflected += reflected * power
        self.absorbed += (hit - reflected) * power
        self.escaped += (1.0 - hit) * power

    @property
    def unshot(self) -> np.ndarray:
        return self.emitted + self.reflected - self.shot

    def as_dict(self) -> dict:
        total = lambda v: float(np.sum(v))  # noqa: E731
        return {
            "emitted": total(self.emitted), "absorbed": total(self.absorbed), "escaped": total(self.escaped),
            "unshot": total(self.unshot), "shot": total(self.shot), "reflected": total(self.reflected),
            "rgb": {k: v.tolist() for k, v in (("emitted", self.emitted), ("absorbed", self.absorbed),
                                                 ("escaped", self.escaped), ("unshot", self.unshot))},
        }


def ambient_term(patches: Patches, unshot_power: np.ndarray) -> np.ndarray:
    """Cohen et al. 1988: Ambient = R Σ A ΔB / Σ A, R = 1/(1 − ρ̄). For previews only:
    a preview shows B + ρ · Ambient; the result never includes it."""
    area = patches.area
    mean_reflectance = (area[:, None] * patches.reflectance).sum(axis=0) / area.sum()
    return np.asarray(unshot_power) / area.sum() / np.maximum(1.0 - mean_reflectance, 1e-6)


def solve_progressive(ctx, scene: Scene, patches: Patches, settings: SolveSettings, timer: StageTimer,
                      progress=None, should_cancel=None):
    """(patch radiosity (P, 3), element radiosity (P, S, S, 3), report details)."""
    started = time.perf_counter()
    variant = settings.visibility
    resolution = getattr(settings, "visibility_res", None) or DEFAULT_VISIBILITY_RESOLUTION
    tolerance = settings.effective_tolerance
    max_shots = settings.max_shots if settings.max_shots is not None else 1_000_000

    emitted = (patches.area[:, None] * patches.emission).sum(axis=0)
    ledger = EnergyLedger(emitted)
    emitted_total = float(emitted.sum())
    objects = []
    try:
        with timer.stage("setup"):
            textures = ElementTextures(ctx, patches, settings.elements)
            objects.append(textures)
            buffers = PatchBuffers(ctx, patches, textures)
            objects.append(buffers)
            selector = Selector(ctx, textures, buffers)
            objects.append(selector)
            visibility_map = VisibilityMap(ctx, patches, resolution, variant, scene.diameter)
            objects.append(visibility_map)
            gatherer = Gatherer(ctx, textures, buffers, settings.kernel, VARIANTS[variant].search_radius)
            objects.append(gatherer)

        shots = 0
        history = []  # (elapsed, unshot fraction) for the estimate of time left
        unshot_gpu = emitted.copy()
        stop_reason = "tolerance"
        while True:
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            with timer.stage("select"):
                selection = selector.select()
            ledger.settle(selection.last_shot)
            unshot_gpu = selection.unshot
            fraction_left = float(unshot_gpu.sum()) / emitted_total
            elapsed = time.perf_counter() - started
            history.append((elapsed, fraction_left))
            if progress is not None:
                eta = _time_left(history, tolerance)
                progress(min(1.0, max(0.0, 1.0 - fraction_left)),
                         f"shot {shots}, unshot {fraction_left:.2e} of emitted"
                         + (f", ~{eta:.0f} s left" if eta is not None else ""),
                         {"shots": shots, "elapsed": elapsed, "eta": eta, "unshot_fraction": fraction_left,
                          "ambient": ambient_term(patches, unshot_gpu).tolist()})
            if fraction_left <= tolerance or selection.patch < 0:
                break
            if shots >= max_shots:
                stop_reason = "max_shots"
                break
            shooter = patch_shooter(patches, selection.patch, selection.residual)
            ledger.pending = shooter.power
            with timer.stage("visibility"):
                visibility_map.render(shooter.position, shooter.axes, skip_patch=shooter.patch)
            with timer.stage("shoot"):
                gatherer.shoot(shooter, visibility_map)
            with timer.stage("mipmap"):
                textures.build_mipmaps()
            shots += 1

        with timer.stage("readback"):
            elements = textures.read_radiosity()
    finally:
        for obj in reversed(objects):
            obj.release()

    areas = textures.areas
    patch_radiosity = (areas[..., None] * elements).sum(axis=(1, 2)) / areas.sum(axis=(1, 2))[:, None]
    solve_seconds = time.perf_counter() - started
    details = {
        "shots": shots,
        "stop_reason": stop_reason,
        "unshot_fraction": float(unshot_gpu.sum()) / emitted_total,
        "energy": {**ledger.as_dict(), "unshot_gpu_sum": float(unshot_gpu.sum())},
        "readback_per_shot": READBACK,
        "visibility": {"variant": variant, "resolution": resolution,
                       "tessellation": VARIANTS[variant].tessellation,
                       "search_radius": VARIANTS[variant].search_radius},
        "kernel": settings.kernel,
        "elements_per_patch": settings.elements,
        "shots_per_second": shots / solve_seconds if solve_seconds > 0 else None,
    }
    return patch_radiosity, elements, details


def _time_left(history, tolerance: float):
    """Seconds to reach the tolerance, from the recent rate of decrease of log(unshot)."""
    if len(history) < 4:
        return None
    recent = history[max(0, len(history) - 50):]
    (t0, u0), (t1, u1) = recent[0], recent[-1]
    if t1 <= t0 or u1 <= 0 or u0 <= u1:
        return None
    rate = (math.log(u0) - math.log(u1)) / (t1 - t0)
    return max(0.0, (math.log(u1) - math.log(tolerance)) / rate)
