"""The hemi-cube method (the dissertation's original method, §4.1): hemi-cube form factors,
then a linear solve.

Scene analysis (`effects`) trims the work: no hemi-cube for patches that reflect nothing,
analytic unoccluded form factors instead of hemi-cubes when nothing can occlude, one
channel for grey scenes, and one gather instead of a linear solve without interreflection.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from ..gpu import GPU
from ..scene import Patches, Scene, SceneEffects
from ..settings import SolveSettings
from ..shooting import DirectLightWork, direct_light_on_patches, has_direct_light
from ..timing import StageTimer, scaled_progress
from . import linear_solvers
from .analytic import unoccluded_form_factor_matrix
from .form_factors import check_memory, form_factor_matrix

READBACK = ("one block of F rows (hemi-cubes in the batch x patches, uint32) per batch;"
            " the solver reads back two floats every 16 Jacobi sweeps")


@dataclass
class HemicubeWork:
    """What the hemi-cube method ran (the report's `effects`, with the scene analysis)."""
    hemicubes: int
    form_factor_rows: int
    channels_solved: int
    linear_solve: bool
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


def solve_hemicube(gpu: GPU, scene: Scene, patches: Patches, settings: SolveSettings, effects: SceneEffects,
                   timer: StageTimer, progress=None, should_cancel=None):
    """(patch radiosity B (P, 3), patch light H (P, 3) with B = E + ρH, its direct part (lamps and
    emitters, P x 3), HemicubeDetails, F). H = H_lamps + H_sky + F B on every row F has; a patch
    that reflects nothing gets no row (with skips on), so its H holds only the lamps' and sky's."""
    check_memory(len(patches), settings.memory_limit_bytes)
    own_emission = np.asarray(patches.emission, dtype=np.float64)
    lamp_light = sky_light = np.zeros_like(own_emission)
    direct_work = None
    if has_direct_light(scene):  # lamps and sky: B = E + ρ (H_lamps + H_sky) + ρ F B
        with timer.stage("direct_light"), gpu.resources() as res:
            lamp_light, sky_light, direct_work = direct_light_on_patches(
                res, scene, patches, settings.visibility, settings.visibility_res, effects.occlusion)
    emission = own_emission + patches.reflectance * (lamp_light + sky_light)
    reflective = np.flatnonzero(patches.reflectance.max(axis=1) > 0)
    rows = reflective if settings.skip_unneeded else np.arange(len(patches))
    with timer.stage("form_factors"):
        if effects.occlusion:
            form_factors = form_factor_matrix(gpu, patches, settings.hemicube_res, scene.diameter,
                                              scaled_progress(progress, 0.0, 0.8), should_cancel, rows)
            hemicubes = len(rows)
        else:
            form_factors = unoccluded_form_factor_matrix(patches.center, patches.normal, patches.corners, rows)
            hemicubes = 0
    reflectance = solved_channels(patches.reflectance, effects.channels)
    emission = solved_channels(emission, effects.channels)
    monitor = linear_solvers.Convergence(
        settings.solver, settings.effective_tolerance, settings.max_iterations,
        should_cancel, scaled_progress(progress, 0.8, 1.0),
    )
    with timer.stage("linear_solve"):
        if effects.interreflection:
            radiosity = linear_solvers.solve_linear(gpu, settings.solver, form_factors, reflectance, emission,
                                                    monitor)
        else:  # one bounce: light reflected once reaches nothing that reflects again
            radiosity = emission + reflectance * (form_factors.astype(np.float64) @ emission)
    gathered = form_factors.astype(np.float64)
    light = lamp_light + sky_light + gathered @ as_rgb(radiosity)
    direct = lamp_light + gathered @ own_emission
    row_sums = form_factors[rows].sum(axis=1, dtype="f8") if len(rows) else np.zeros(1)
    details = HemicubeDetails(
        solver=monitor.name, iterations=monitor.iterations, relative_change=float(monitor.relative_change),
        residual=float(monitor.relative_change) if effects.interreflection else 0.0,
        hemicube_resolution=settings.hemicube_res,
        form_factor_row_sum={"min": float(row_sums.min()), "max": float(row_sums.max())},
        work=HemicubeWork(hemicubes=hemicubes, form_factor_rows=int(len(rows)), channels_solved=effects.channels,
                          linear_solve=bool(effects.interreflection), direct=direct_work),
    )
    return as_rgb(radiosity), light, direct, details, form_factors
