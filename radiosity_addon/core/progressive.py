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

from .direct_light import shoot_direct_light
from .effects import SceneEffects
from .element_textures import ElementTextures
from .patches import Patches
from .scene import Scene
from .shooting import READBACK, Gatherer, PatchBuffers, PatchShooters, Selector
from .solution import SolveCancelled, SolveSettings, StageTimer
from .visibility import VARIANTS, VisibilityMap


class EnergyLedger:
    """Power accounts in float64 (RGB): emitted + surplus = absorbed + escaped + unshot.

    A shot's hit fraction is the shooter's form-factor row sum over all elements. In a closed
    scene it should be 1; point-sampled factors make it a little more (near corners) or less
    (along shared edges). The shortfall is booked as escaped, the excess as `surplus`
    (energy the discretization created), so the accounts balance exactly either way.
    """

    def __init__(self, emitted: np.ndarray):
        self.emitted = np.asarray(emitted, dtype=np.float64)
        self.shot = np.zeros(3)
        self.absorbed = np.zeros(3)
        self.reflected = np.zeros(3)
        self.escaped = np.zeros(3)
        self.surplus = np.zeros(3)
        self.pending = None  # power of the shot whose fractions are not yet read back

    def settle(self, fractions: np.ndarray) -> None:
        """Book the pending shot with its (hit, reflected RGB) fractions."""
        if self.pending is None:
            return
        power, self.pending = self.pending, None
        hit = float(fractions[0])
        reflected = np.minimum(fractions[1:4], hit)
        self.shot += power
        self.reflected += reflected * power
        self.absorbed += (hit - reflected) * power
        self.escaped += max(1.0 - hit, 0.0) * power
        self.surplus += max(hit - 1.0, 0.0) * power

    @property
    def unshot(self) -> np.ndarray:
        return self.emitted + self.reflected - self.shot

    def as_dict(self) -> dict:
        total = lambda v: float(np.sum(v))  # noqa: E731
        return {
            "emitted": total(self.emitted), "absorbed": total(self.absorbed), "escaped": total(self.escaped),
            "surplus": total(self.surplus),
            "unshot": total(self.unshot), "shot": total(self.shot), "reflected": total(self.reflected),
            "rgb": {k: v.tolist() for k, v in (("emitted", self.emitted), ("absorbed", self.absorbed),
                                                 ("escaped", self.escaped), ("unshot", self.unshot))},
        }


def ambient_term(patches: Patches):
    """Cohen et al. 1988: Ambient = R Σ A ΔB / Σ A, R = 1/(1 − ρ̄), as a function of the unshot
    power Σ A ΔB (RGB). For previews only: a preview shows B + ρ · Ambient; the result never
    includes it."""
    area = patches.area
    mean_reflectance = (area[:, None] * patches.reflectance).sum(axis=0) / area.sum()
    scale = 1.0 / (area.sum() * np.maximum(1.0 - mean_reflectance, 1e-6))
    return lambda unshot_power: np.asarray(unshot_power) * scale


def solve_progressive(ctx, scene: Scene, patches: Patches, settings: SolveSettings, effects: SceneEffects,
                      timer: StageTimer, progress=None, should_cancel=None):
    """(patch radiosity (P, 3), element radiosity (P, S, S, 3), report details).
    `effects` (the scene analysis) may switch off visibility maps (nothing occludes) and
    residual updates (no interreflection: only emitters and lamps ever shoot)."""
    started = time.perf_counter()
    variant = settings.visibility
    resolution = settings.visibility_res
    tolerance = settings.effective_tolerance
    max_shots = settings.max_shots if settings.max_shots is not None else 1_000_000

    emitted = (patches.area[:, None] * patches.emission).sum(axis=0)
    ledger = EnergyLedger(emitted)
    ambient = ambient_term(patches)
    shooters = PatchShooters(patches)
    objects = []
    try:
        with timer.stage("setup"):
            textures = ElementTextures(ctx, patches, settings.elements, channels=effects.channels)
            objects.append(textures)
            buffers = PatchBuffers(ctx, patches, textures)
            objects.append(buffers)
            selector = Selector(ctx, textures, buffers)
            objects.append(selector)
            visibility_map = VisibilityMap(ctx, patches, resolution, variant, scene.diameter)
            objects.append(visibility_map)
            gatherer = Gatherer(ctx, textures, buffers, settings.kernel, VARIANTS[variant].search_radius,
                                occluder_margin=VARIANTS[variant].occluder_margin, occlusion=effects.occlusion,
                                interreflection=effects.interreflection)
            objects.append(gatherer)
        with timer.stage("direct_light"):
            direct = shoot_direct_light(ctx, scene, patches, settings.elements, gatherer, visibility_map,
                                        effects.occlusion)
            textures.build_mipmaps()
            first = selector.select()  # also drops the lamp shots' energy sums: they are booked here
        # lamps and the sky enter the ledger as the power their first bounce adds to the unshot
        lamp_first_bounce = np.maximum(first.unshot - emitted, 0.0)
        ledger.emitted = ledger.emitted + lamp_first_bounce
        emitted_total = float(ledger.emitted.sum())

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
            fraction_left = float(unshot_gpu.sum()) / emitted_total if emitted_total > 0 else 0.0
            elapsed = time.perf_counter() - started
            history.append((elapsed, fraction_left))
            if progress is not None:
                eta = _time_left(history, tolerance)
                progress(min(1.0, max(0.0, 1.0 - fraction_left)),
                         f"shot {shots}, unshot {fraction_left:.2e} of emitted"
                         + (f", ~{eta:.0f} s left" if eta is not None else ""),
                         {"shots": shots, "elapsed": elapsed, "eta": eta, "unshot_fraction": fraction_left,
                          "ambient": ambient(unshot_gpu).tolist()})
            if fraction_left <= tolerance or selection.patch < 0 or emitted_total <= 0:
                break
            if shots >= max_shots:
                stop_reason = "max_shots"
                break
            shooter = shooters.shooter(selection.patch, selection.residual,
                                       selection.centroid if settings.shoot_from == "centroid" else None)
            ledger.pending = shooter.power
            if effects.occlusion:
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
        "unshot_fraction": float(unshot_gpu.sum()) / emitted_total if emitted_total > 0 else 0.0,
        "energy": {**ledger.as_dict(), "unshot_gpu_sum": float(unshot_gpu.sum())},
        "readback_per_shot": READBACK,
        "visibility": {"variant": variant, "resolution": resolution,
                       "tessellation": VARIANTS[variant].tessellation,
                       "search_radius": VARIANTS[variant].search_radius,
                       "occluder_margin": VARIANTS[variant].occluder_margin, "from": settings.shoot_from},
        "kernel": settings.kernel,
        "elements_per_patch": settings.elements,
        "shots_per_second": shots / solve_seconds if solve_seconds > 0 else None,
        # what was actually run (the report's effects)
        "work": {"visibility_maps": (shots if effects.occlusion else 0) + direct["lamp_visibility_maps"],
                 "shots": shots, "channels_solved": effects.channels,
                 "texel_bytes": 16 if effects.channels == 3 else 4, "residual_updates": bool(effects.interreflection),
                 **direct},
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
