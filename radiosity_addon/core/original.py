"""The original method (dissertation §4.1): hemi-cube form factors, then a linear solve."""

from __future__ import annotations

from . import hemicube, linear_solvers
from .patches import Patches
from .solution import SolveSettings, StageTimer


def scaled(progress, start: float, end: float):
    """A progress callback mapping [0, 1] of one stage onto [start, end] of the whole."""
    if progress is None:
        return None
    return lambda fraction, message, details: progress(start + (end - start) * fraction, message, details)


def solve_original(ctx, patches: Patches, scene_diameter: float, settings: SolveSettings,
                   timer: StageTimer, progress=None, should_cancel=None):
    """Patch radiosity (P x 3) and the report entries of the original method."""
    hemicube.check_memory(len(patches), settings.memory_limit_bytes)
    with timer.stage("form_factors"):
        form_factors = hemicube.form_factor_matrix(
            ctx, patches, settings.hemicube_res, scene_diameter, scaled(progress, 0.0, 0.8), should_cancel
        )
    monitor = linear_solvers.Convergence(
        settings.solver, settings.effective_tolerance, settings.max_iterations,
        should_cancel, scaled(progress, 0.8, 1.0),
    )
    with timer.stage("linear_solve"):
        radiosity = linear_solvers.solve_linear(
            ctx, settings.solver, form_factors, patches.reflectance, patches.emission, monitor
        )
    row_sums = form_factors.sum(axis=1, dtype="f8")
    details = {
        **monitor.summary(),
        "iterations": monitor.iterations,
        "residual": monitor.relative_change,
        "hemicube_resolution": settings.hemicube_res,
        "form_factor_row_sum": {"min": float(row_sums.min()), "max": float(row_sums.max())},
        "readback_bytes_per_batch": "rows of F: hemicubes x patches x 4",
    }
    return radiosity, details, form_factors
