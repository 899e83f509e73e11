"""The hemi-cube method (the dissertation's original method, §4.1): hemi-cube form factors,
then a linear solve.

The direct light — lamps, the sun, the emitters' own emission and the sky — is measured on every
element as the mean over DIRECT_POINTS x DIRECT_POINTS points of each patch (the emitters in pieces,
each with its own visibility: `shooting.direct_light_at_elements`), and the hemi-cubes carry only
the light reflected: H = D + F R with R = B − E, so (I − ρF) R = ρ D. A hemi-cube's centre sees an
emitter as a point sample of its patch: a ceiling patch whose centre lies above a light 5 mm under
it saw the light's back fill its hemisphere, and sent that into the room (such patches made the
Cornell box's walls many times too bright); the reflected light is smooth, so coarse hemi-cubes
carry it well.

Scene analysis (`effects`) trims the work: no hemi-cube for patches that reflect nothing,
analytic unoccluded form factors instead of hemi-cubes when nothing can occlude, one
channel for grey scenes, and one gather instead of a linear solve without interreflection.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import SolveCancelled
from ..gpu import GPU
from ..scene import Patches, Scene, SceneEffects
from ..settings import SolveSettings
from ..shooting.sky import SKY_DIRECTIONS
from ..shooting import (DirectLightWork, MeasuredDirectLight, direct_light_at_elements, element_areas,
                        lamps_as_shooters, patch_means, patch_scale_shots, same_shots)
from ..timing import StageTimer, scaled_progress
from . import linear_solvers
from .bright_columns import shoot_bright_columns
from .form_factors import check_memory, element_form_factors, patch_rows

READBACK = ("one block of F rows (hemi-cubes in the batch x patches, uint32) per batch;"
            " the solver reads back two floats every 16 Jacobi sweeps")


@dataclass
class HemicubeWork:
    """What the hemi-cube method ran (the report's `effects`, with the scene analysis)."""
    hemicubes: int
    form_factor_rows: int
    channels_solved: int
    linear_solve: bool
    bright_columns: int = 0  # columns of F shot instead of rasterized (bright_columns.py)
    direct: DirectLightWork | None = None  # lamps and sky, when the scene has them

    def entries(self) -> dict:
        entries = {k: v for k, v in asdict(self).items() if k != "direct"}
        return entries | (asdict(self.direct) if self.direct is not None else {})


@dataclass
class HemicubeDetails:
    """The hemi-cube method's part of the report."""
    solver: str
    iterations: int
    relative_change: float
    residual: float
    hemicube_resolution: int
    form_factor_row_sum: dict  # {"min": ..., "max": ...}
    work: HemicubeWork
    readback: str = field(default=READBACK)

    @property
    def shots(self) -> None:
        return None

    def entries(self) -> dict:
        return {"solver": self.solver, "iterations": self.iterations, "relative_change": self.relative_change,
                "residual": self.residual, "hemicube_resolution": self.hemicube_resolution,
                "form_factor_row_sum": self.form_factor_row_sum, "readback": self.readback}


def solved_channels(array: np.ndarray, channels: int) -> np.ndarray:
    """The channels a solve works on: the first one of a grey scene (all equal), else all."""
    return np.asarray(array, dtype=np.float64)[:, :channels]


def as_rgb(radiosity: np.ndarray) -> np.ndarray:
    return np.repeat(radiosity, 3, axis=1) if radiosity.shape[1] == 1 else radiosity


DIRECT_POINTS = 4  # points per patch side the direct light is measured at (at least, per element side one)


def element_means(values: np.ndarray, areas: np.ndarray, size: int) -> np.ndarray:
    """(P, S, S, 3) area-weighted means of `values` (P, S k, S k, 3) over k x k blocks (`areas` (P, S k, S k))."""
    count, k = len(values), values.shape[1] // size
    weights = areas.reshape(count, size, k, size, k)
    blocks = values.reshape(count, size, k, size, k, 3)
    return (blocks * weights[..., None]).sum(axis=(2, 4)) / weights.sum(axis=(2, 4))[..., None]


def direct_light(gpu: GPU, scene: Scene, patches: Patches, settings: SolveSettings, effects: SceneEffects,
                 size: int, measured: MeasuredDirectLight | None = None) -> tuple[np.ndarray, np.ndarray, DirectLightWork]:
    """(P, S, S, 3) the light each element gets straight from the lamps, the sun and the emitters,
    and (the same shape) from the sky: each the mean over the element's share of DIRECT_POINTS x
    DIRECT_POINTS points of its patch (at least one per element). What refinement `measured` at
    those points with these shots is taken, and only the rest measured."""
    k = -(-DIRECT_POINTS // size)
    shots = patch_scale_shots(scene, patches, effects.occlusion, settings.probe_pieces)
    rows, light, sky = np.arange(len(patches)), None, None
    if (measured is not None and measured.elements == size * k and len(measured.known) == len(patches)
            and same_shots(measured.shooters, shots)):
        rows, light, sky = np.flatnonzero(~measured.known), measured.shots.copy(), measured.sky.copy()
    if len(rows):
        with gpu.resources() as res:
            more = direct_light_at_elements(res, scene, patches, rows, shots, settings.visibility,
                                            settings.visibility_res, effects.occlusion, size * k,
                                            capacity=settings.batch_shots)
        if light is None:
            light, sky = more
        else:
            light[rows], sky[rows] = more
    areas = element_areas(patches, size * k)
    lamp_shots = len(lamps_as_shooters(scene, settings.probe_pieces))
    work = DirectLightWork(lamps=len(scene.lamps), lamp_visibility_maps=lamp_shots if effects.occlusion else 0,
                           sky_maps=SKY_DIRECTIONS if np.any(scene.world_color > 0) else 0,
                           emitter_pieces=len(shots) - lamp_shots)
    return element_means(light, areas, size), element_means(sky, areas, size), work


def solve_hemicube(gpu: GPU, scene: Scene, patches: Patches, settings: SolveSettings, effects: SceneEffects,
                   timer: StageTimer, progress=None, should_cancel=None, measured: MeasuredDirectLight | None = None):
    """(patch radiosity B (P, 3), element radiosity (P, S, S, 3), element light H with B = E + ρH,
    its direct part (lamps and emitters), its part straight from the sky, HemicubeDetails, patch F). Receivers are the S x S
    elements of every patch (S = hemicube_elements), shooters the patches: H_e = D_e + F_e R on
    every element (D: `direct_light`, R = B − E the light the patches reflect); a patch that
    reflects nothing gets no rows (with skips on), so its H is its direct light alone. `measured`:
    refinement's probe of the direct light (`direct_light`)."""
    size = settings.hemicube_elements
    check_memory(len(patches), settings.memory_limit_bytes, size)
    own_emission = np.asarray(patches.emission, dtype=np.float64)
    with timer.stage("direct_light"):
        direct, sky_light, direct_work = direct_light(gpu, scene, patches, settings, effects, size, measured)
    areas = element_areas(patches, size)
    emission = patches.reflectance * patch_means(areas, direct + sky_light)  # ρ D: the source of R
    reflective = np.flatnonzero(patches.reflectance.max(axis=1) > 0)
    rows = reflective if settings.skip_unneeded else np.arange(len(patches))
    with timer.stage("form_factors"):
        element_rows = element_form_factors(gpu, patches, size, settings.hemicube_res, scene.diameter, rows,
                                            effects.occlusion, scaled_progress(progress, 0.0, 0.8), should_cancel)
        bright = rows[:0]
        if effects.occlusion:  # unoccluded factors are analytic: nothing to alias
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            bright = shoot_bright_columns(gpu, scene, patches, element_rows, rows, size, emission, settings)
        form_factors = patch_rows(element_rows, patches, rows, size)
        hemicubes = len(element_rows) if effects.occlusion else 0
    reflectance = solved_channels(patches.reflectance, effects.channels)
    emission = solved_channels(emission, effects.channels)
    monitor = linear_solvers.Convergence(
        settings.solver, settings.effective_tolerance, settings.max_iterations,
        should_cancel, scaled_progress(progress, 0.8, 1.0),
    )
    with timer.stage("linear_solve"):  # R = B − E: (I − ρF) R = ρ D
        if effects.interreflection:
            reflected = linear_solvers.solve_linear(gpu, settings.solver, form_factors, reflectance, emission,
                                                    monitor)
        else:  # one bounce: light reflected once reaches nothing that reflects again
            reflected = emission + reflectance * (form_factors.astype(np.float64) @ emission)
    reflected = as_rgb(reflected)
    radiosity = own_emission + reflected
    light = direct + sky_light
    light[rows] += linear_solvers.widened_product(element_rows, reflected).reshape(len(rows), size, size, 3)
    elements = own_emission[:, None, None, :] + patches.reflectance[:, None, None, :] * light
    row_sums = form_factors.sum(axis=1, dtype="f8")[rows] if len(rows) else np.zeros(1)  # no P x P copy
    details = HemicubeDetails(
        solver=monitor.name, iterations=monitor.iterations, relative_change=float(monitor.relative_change),
        residual=float(monitor.relative_change) if effects.interreflection else 0.0,
        hemicube_resolution=settings.hemicube_res,
        form_factor_row_sum={"min": float(row_sums.min()), "max": float(row_sums.max())},
        work=HemicubeWork(hemicubes=hemicubes, form_factor_rows=int(len(rows)), channels_solved=effects.channels,
                          linear_solve=bool(effects.interreflection), bright_columns=len(bright),
                          direct=direct_work),
    )
    return radiosity, elements, light, direct, sky_light, details, form_factors
