"""Progressive refinement radiosity on the GPU (dissertation §4.2; Coombe et al. 2004).

Per batch: read the residual's mip level (each patch's unshot power), take the strongest patches
(up to the visibility's capacity, down to `selection.BATCH_POWER_FLOOR` of the strongest), render
their visibility (hemi-cubes in one atlas, one instanced draw), add their ΔB to every receiving
element in one dispatch, clear their residuals, rebuild the residual's mip levels. Emitters first
shoot their own emission (the direct light the lightmaps recompute per texel). Stops when the
unshot power falls under tolerance × emitted power, or at the shot budget.

Energy is booked in float64 on the CPU from the few numbers read back per batch (see
`selection.READBACK`): each shot's power comes from the shooter's mean residual, and the GPU
sums (fixed point) say which fraction of it hit a receiver and which fraction was reflected.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SolveCancelled
from ..gpu import GPU
from ..scene import Patches, Scene, SceneEffects
from ..settings import SolveSettings
from ..shooting import (DirectLightWork, ElementTextures, PatchBuffers, PatchShooters, ShootingPass, ShotVisibility,
                        emitter_pieces, patch_means, shoot_lamps, shoot_sky)
from ..timing import StageTimer
from ..visibility import VARIANTS
from .clusters import ClusteredSelection, build_clusters, cluster_owners
from .ledger import EnergyLedger, ambient_term, remainder_light, remainder_power, time_left
from .selection import READBACK, ResidualReader


REMAINDER_WINDOW = 4.0  # the light gathered after unshot fell to this many tolerances shapes the remainder


@dataclass
class ProgressiveWork:
    """What progressive refinement ran (the report's `effects`, with the scene analysis)."""
    visibility_maps: int
    shots: int
    batches: int
    channels_solved: int
    texel_bytes: int
    residual_updates: bool
    direct: DirectLightWork
    shooter_clusters: int = 0  # clusters the patches were grouped into (0: none)
    cluster_shots: int = 0  # shots of a whole cluster (counted in `shots`)

    def entries(self) -> dict:
        return {k: v for k, v in asdict(self).items() if k != "direct"} | asdict(self.direct)


@dataclass
class ProgressiveDetails:
    """Progressive refinement's part of the report."""
    shots: int
    stop_reason: str  # "tolerance" or "max_shots"
    unshot_fraction: float
    energy: dict  # the ledger (EnergyLedger.as_dict) and the GPU's own unshot sum
    visibility: dict  # variant, resolution, tessellation, search radius, occluder margin, shooting point
    kernel: str
    elements_per_patch: int
    shots_per_second: float | None
    work: ProgressiveWork
    readback_per_shot: str = READBACK

    @property
    def iterations(self) -> None:
        return None

    def entries(self) -> dict:
        return {"shots": self.shots, "stop_reason": self.stop_reason, "unshot_fraction": self.unshot_fraction,
                "energy": self.energy, "readback_per_shot": self.readback_per_shot, "visibility": self.visibility,
                "kernel": self.kernel, "elements_per_patch": self.elements_per_patch,
                "shots_per_second": self.shots_per_second}


def solve_progressive(gpu: GPU, scene: Scene, patches: Patches, settings: SolveSettings, effects: SceneEffects,
                      timer: StageTimer, progress=None, should_cancel=None, preview=None, preview_interval=2.0):
    """(patch radiosity (P, 3), element radiosity (P, S, S, 3), element light H (P, S, S, 3), its
    direct part (lamps and emitters, not the sky), its part straight from the sky,
    ProgressiveDetails), with B = E + ρH.
    `effects` (the scene analysis) may switch off visibility maps (nothing occludes) and
    residual updates (no interreflection: only emitters and lamps ever shoot).
    `preview(element radiosity, element light)` is called every `preview_interval` seconds with
    the radiosity so far plus the ambient term ρ · Ambient, and the light so far plus Ambient
    (for display only)."""
    started = time.perf_counter()
    variant = VARIANTS[settings.visibility]
    tolerance = settings.effective_tolerance
    max_shots = settings.max_shots if settings.max_shots is not None else 1_000_000

    emitted = (patches.area[:, None] * patches.emission).sum(axis=0)
    ledger = EnergyLedger(emitted)
    ambient = ambient_term(patches)
    shooters = PatchShooters(patches)
    clusters = None
    if 0 < settings.shooter_clusters < len(patches) and effects.interreflection:
        with timer.stage("clusters"):
            clusters = build_clusters(patches, settings.shooter_clusters, owner=cluster_owners(scene, patches))
    with gpu.resources() as res:
        with timer.stage("setup"):
            # the emitters' own emission is not in the residual: their pieces below shoot it
            textures = ElementTextures(res, patches, settings.elements, channels=effects.channels,
                                       unshot_emission=False)
            buffers = PatchBuffers(res, patches, textures,
                                   None if clusters is None else np.stack([c.of_patch for c in clusters], axis=1))
            visibility = ShotVisibility(res, patches, settings.visibility_res, settings.visibility, scene.diameter,
                                        effects.occlusion, capacity=settings.batch_shots)
            shooting = ShootingPass(res, textures, buffers, settings.kernel, visibility,
                                    interreflection=effects.interreflection)
            reader = ResidualReader(textures, patches.area)
        with timer.stage("direct_light"):
            direct = shoot_lamps(scene, shooting)
            lamp_light = textures.read_light()
            shoot_sky(res, scene, patches, settings.elements, shooting, direct)
            before_emitters = textures.read_light()
            shooting.read_energy(1)  # the lamps' sums: lamps are booked by their first bounce below
            textures.build_mipmaps()
            first = reader.read()
        # lamps and the sky enter the ledger as the power their first bounce adds to the unshot
        lamp_first_bounce = np.maximum(first.unshot, 0.0)
        ledger.emitted = ledger.emitted + lamp_first_bounce
        emitted_total = float(ledger.emitted.sum())
        # a cluster shoots as one while its power is under CLUSTER_POWER mean clusters' shares of the light
        # (clusters.ClusteredSelection)
        selection = None if clusters is None else ClusteredSelection(patches, clusters, emitted_total, tolerance)
        cluster_shots = 0

        shots = batches = 0
        # (seconds since the emitters shot, unshot fraction) for the estimate of time left: the
        # emitters' pieces take the unshot down linearly, the bounces after them geometrically
        history = []
        bounces_from = None
        last_preview = time.perf_counter()
        unshot_gpu = emitted.copy()
        stop_reason = "tolerance"
        # every emitter shoots its own emission first, in pieces (and keeps what it received): the
        # light after those shots, less the sky's, is the direct light the lightmaps recompute per texel
        forced = emitter_pieces(scene, patches, effects.occlusion)
        forced_power = sum((piece.power for piece in forced), np.zeros(3))  # emission not yet shot
        direct_light = recent_from = None
        completing = settings.complete_remainder and effects.interreflection and emitted_total > 0
        while True:
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            with timer.stage("select"):
                residuals = reader.read()
            unshot_gpu = residuals.unshot + forced_power
            fraction_left = float(unshot_gpu.sum()) / emitted_total if emitted_total > 0 else 0.0
            elapsed = time.perf_counter() - started
            if not forced:
                bounces_from = elapsed if bounces_from is None else bounces_from
                history.append((elapsed - bounces_from, fraction_left))
            if progress is not None:
                eta = time_left(history, tolerance) if not forced else None
                progress(min(1.0, max(0.0, 1.0 - fraction_left)),
                         f"shot {shots}, unshot {fraction_left:.2e} of emitted"
                         + (f", ~{eta:.0f} s left" if eta is not None else ""),
                         {"shots": shots, "elapsed": elapsed, "eta": eta, "unshot_fraction": fraction_left,
                          "phase": "emitters" if forced else "bounces",
                          "ambient": ambient(unshot_gpu).tolist()})
            if preview is not None and time.perf_counter() - last_preview >= preview_interval:
                with timer.stage("preview"):
                    extra = ambient(unshot_gpu)
                    preview(textures.read_radiosity() + patches.reflectance[:, None, None, :] * extra,
                            textures.read_light() + extra)
                last_preview = time.perf_counter()
            if not forced and direct_light is None:
                direct_light = lamp_light + textures.read_light() - before_emitters
            if completing and recent_from is None and direct_light is not None \
                    and fraction_left <= REMAINDER_WINDOW * tolerance:
                recent_from = textures.read_light()  # what is gathered from here on shapes the remainder
            room = min(visibility.capacity, max_shots - shots)
            grouped = []
            if forced:
                chosen = None
            elif selection is not None:
                chosen, grouped = selection.choose(residuals, room)
            else:
                chosen = residuals.strongest(room)
            done = fraction_left <= tolerance or emitted_total <= 0 or not residuals.power.max() > 0
            if not forced and done:
                break
            if room <= 0:
                stop_reason = "max_shots"
                break
            bounce = not forced  # emitters' own emission sends no reflected light
            if forced:
                batch, forced = forced[:room], forced[room:]
                forced_power = forced_power - sum((piece.power for piece in batch), np.zeros(3))
            else:
                centroid = settings.shoot_from == "centroid"
                batch = [shooters.shooter(int(p), residuals.mean[p], residuals.centroid[p] if centroid else None)
                         for p in chosen] + grouped
                cluster_shots += len(grouped)
            ledger.pending = np.array([shooter.power for shooter in batch])
            ledger.pending_bounce = bounce
            with timer.stage("visibility"):
                uniforms = visibility.prepare(batch)
            with timer.stage("shoot"):
                shooting.gather(uniforms)
                ledger.settle(shooting.read_energy(len(batch)))
            with timer.stage("mipmap"):
                textures.build_mipmaps()
            shots += len(batch)
            batches += 1

        with timer.stage("readback"):
            light = textures.read_light()
        if direct_light is None:  # stopped by the shot budget among the emitters
            direct_light = lamp_light + light - before_emitters
        remainder = np.zeros(3)
        if completing:
            remainder = remainder_power(ledger, patches, unshot_gpu)
            recent = light - (recent_from if recent_from is not None else direct_light)
            light = light + remainder_light(remainder, recent, textures.areas)
        elements = textures.radiosity(light)
        areas = textures.areas

    patch_radiosity = patch_means(areas, elements)
    solve_seconds = time.perf_counter() - started
    details = ProgressiveDetails(
        shots=shots, stop_reason=stop_reason,
        unshot_fraction=float(unshot_gpu.sum()) / emitted_total if emitted_total > 0 else 0.0,
        energy={**ledger.as_dict(), "unshot_gpu_sum": float(unshot_gpu.sum()), "remainder_delivered": remainder.tolist()},
        visibility={"variant": settings.visibility, "resolution": settings.visibility_res,
                    "batch_capacity": visibility.capacity,
                    "tessellation": variant.tessellation, "search_radius": variant.search_radius,
                    "occluder_margin": variant.occluder_margin, "from": settings.shoot_from},
        kernel=settings.kernel, elements_per_patch=settings.elements,
        shots_per_second=shots / solve_seconds if solve_seconds > 0 else None,
        work=ProgressiveWork(visibility_maps=visibility.maps_rendered, shots=shots, batches=batches, channels_solved=effects.channels,
                             texel_bytes=16 if effects.channels == 3 else 4,
                             residual_updates=bool(effects.interreflection), direct=direct,
                             shooter_clusters=0 if clusters is None else len(clusters[-1]),
                             cluster_shots=cluster_shots),
    )
    return patch_radiosity, elements, light, direct_light, before_emitters - lamp_light, details
