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
from ..shooting import DirectLightWork, direct_light_on_patches, element_areas, has_direct_light, patch_means
from ..timing import StageTimer, scaled_progress
from . import linear_solvers
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
    """(patch radiosity B (P, 3), element radiosity (P, S, S, 3), element light H with B = E + ρH,
    its direct part (lamps and emitters), HemicubeDetails, patch F). Receivers are the S x S
    elements of every patch (S = hemicube_elements), shooters the patches: H_e = H_lamps + H_sky
    + F_e B on every element; a patch that reflects nothing gets no rows (with skips on), so its H
    holds only the lamps' and sky's."""
    size = settings.hemicube_elements
    check_memory(len(patches), settings.memory_limit_bytes, size)
    own_emission = np.asarray(patches.emission, dtype=np.float64)
    lamp_light = sky_light = np.zeros((len(patches), size, size, 3))
    direct_work = None
    if has_direct_light(scene):  # lamps and sky: B = E + ρ (H_lamps + H_sky) + ρ F B
        with timer.stage("direct_light"), gpu.resources() as res:
            lamp_light, sky_light, direct_work = direct_light_on_patches(
                res, scene, patches, settings.visibility, settings.visibility_res, effects.occlusion, size)
    areas = element_areas(patches, size)
    emission = own_emission + patches.reflectance * patch_means(areas, lamp_light + sky_light)
    reflective = np.flatnonzero(patches.reflectance.max(axis=1) > 0)
    rows = reflective if settings.skip_unneeded else np.arange(len(patches))
    with timer.stage("form_factors"):
        element_rows = element_form_factors(gpu, patches, size, settings.hemicube_res, scene.diameter, rows,
                                            effects.occlusion, scaled_progress(progress, 0.0, 0.8), should_cancel)
        form_factors = patch_rows(element_rows, patches, rows, size)
        hemicubes = len(element_rows) if effects.occlusion else 0
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
    radiosity = as_rgb(radiosity)
    light, direct = lamp_light + sky_light, lamp_light.copy()
    gathered = element_rows.astype(np.float64)
    light[rows] += (gathered @ radiosity).reshape(len(rows), size, size, 3)
    direct[rows] += (gathered @ own_emission).reshape(len(rows), size, size, 3)
    elements = own_emission[:, None, None, :] + patches.reflectance[:, None, None, :] * light
    row_sums = form_factors[rows].sum(axis=1, dtype="f8") if len(rows) else np.zeros(1)
    details = HemicubeDetails(
        solver=monitor.name, iterations=monitor.iterations, relative_change=float(monitor.relative_change),
        residual=float(monitor.relative_change) if effects.interreflection else 0.0,
        hemicube_resolution=settings.hemicube_res,
        form_factor_row_sum={"min": float(row_sums.min()), "max": float(row_sums.max())},
        work=HemicubeWork(hemicubes=hemicubes, form_factor_rows=int(len(rows)), channels_solved=effects.channels,
                          linear_solve=bool(effects.interreflection), direct=direct_work),
    )
    return radiosity, elements, light, direct, details, form_factors
