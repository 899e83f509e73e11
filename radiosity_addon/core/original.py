"""The original method (dissertation §4.1): hemi-cube form factors, then a linear solve.

Scene analysis (`effects`) trims the work: no hemi-cube for patches that reflect nothing,
analytic unoccluded form factors instead of hemi-cubes when nothing can occlude, one
channel for grey scenes, and one gather instead of a linear solve without interreflection.
"""

from __future__ import annotations

import numpy as np

from . import hemicube, linear_solvers
from .effects import SceneEffects
from .form_factor_kernels import unoccluded_form_factor_matrix
from .patches import Patches
from .solution import SolveSettings, StageTimer


def scaled(progress, start: float, end: float):
    """A progress callback mapping [0, 1] of one stage onto [start, end] of the whole."""
    if progress is None:
        return None
    return lambda fraction, message, details: progress(start + (end - start) * fraction, message, details)


def solved_channels(array: np.ndarray, channels: int) -> np.ndarray:
    """The channels a solve works on: the first one of a grey scene (all equal), else all."""
    return np.asarray(array, dtype=np.float64)[:, :channels]


def as_rgb(radiosity: np.ndarray) -> np.ndarray:
    return np.repeat(radiosity, 3, axis=1) if radiosity.shape[1] == 1 else radiosity


def solve_original(ctx, patches: Patches, scene_diameter: float, settings: SolveSettings,
                   effects: SceneEffects, timer: StageTimer, progress=None, should_cancel=None):
    """Patch radiosity (P x 3), the report entries of the original method, and F."""
    hemicube.check_memory(len(patches), settings.memory_limit_bytes)
    reflective = np.flatnonzero(patches.reflectance.max(axis=1) > 0)
    rows = reflective if settings.skip_unneeded else np.arange(len(patches))
    with timer.stage("form_factors"):
        if effects.occlusion:
            form_factors = hemicube.form_factor_matrix(ctx, patches, settings.hemicube_res, scene_diameter,
                                                       scaled(progress, 0.0, 0.8), should_cancel, rows)
            hemicubes = len(rows)
        else:
            form_factors = unoccluded_form_factor_matrix(patches.center, patches.normal, patches.corners, rows)
            hemicubes = 0
    reflectance = solved_channels(patches.reflectance, effects.channels)
    emission = solved_channels(patches.emission, effects.channels)
    monitor = linear_solvers.Convergence(
        settings.solver, settings.effective_tolerance, settings.max_iterations,
        should_cancel, scaled(progress, 0.8, 1.0),
    )
    with timer.stage("linear_solve"):
        if effects.interreflection:
            radiosity = linear_solvers.solve_linear(ctx, settings.solver, form_factors, reflectance, emission,
                                                    monitor)
        else:  # one bounce: light reflected once reaches nothing that reflects again
            radiosity = emission + reflectance * (form_factors.astype(np.float64) @ emission)
    row_sums = form_factors[rows].sum(axis=1, dtype="f8") if len(rows) else np.zeros(1)
    details = {
        **monitor.summary(),
        "residual": monitor.relative_change if effects.interreflection else 0.0,
        "hemicube_resolution": settings.hemicube_res,
        "form_factor_row_sum": {"min": float(row_sums.min()), "max": float(row_sums.max())},
        "readback": "one block of F rows (hemi-cubes in the batch x patches, uint32) per batch;"
                    " the solver reads back two floats every 16 Jacobi sweeps",
        "work": {"hemicubes": hemicubes, "form_factor_rows": int(len(rows)),
                 "channels_solved": effects.channels,
                 "linear_solve": bool(effects.interreflection)},
    }
    return as_rgb(radiosity), details, form_factors
