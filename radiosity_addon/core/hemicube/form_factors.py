"""The form-factor matrix of the hemi-cube method: one hemi-cube per receiving patch (batched
on the GPU), or the analytic unoccluded kernel when nothing can occlude. Memory is P x P
float32, so the guard refuses before any work."""

from __future__ import annotations

import numpy as np

from ..errors import SolveCancelled, SolveError
from ..gpu import GPU
from ..scene import Patches
from ..visibility import HemicubeRenderer


def matrix_bytes(patch_count: int) -> int:
    return patch_count * patch_count * 4


def check_memory(patch_count: int, limit_bytes: int) -> None:
    need = matrix_bytes(patch_count)
    if need > limit_bytes:
        raise SolveError(
            f"the hemi-cube method needs a {patch_count}x{patch_count} form-factor matrix"
            f" ({need / 2**30:.1f} GiB, limit {limit_bytes / 2**30:.1f} GiB);"
            " use --method progressive or a larger --patch-size"
        )


def form_factor_matrix(gpu: GPU, patches: Patches, resolution: int, scene_diameter: float,
                       progress=None, should_cancel=None, rows: np.ndarray | None = None) -> np.ndarray:
    """F (P x P, float32): F[i, j] = fraction of patch i's hemisphere covered by patch j.
    Only the hemi-cubes of `rows` (default: all patches) are rendered; other rows stay 0."""
    count = len(patches)
    rows = np.arange(count) if rows is None else np.asarray(rows)
    matrix = np.zeros((count, count), dtype=np.float32)
    if len(rows) == 0:
        return matrix
    with gpu.resources() as res:
        renderer = HemicubeRenderer(res, patches, resolution, scene_diameter)
        for first in range(0, len(rows), renderer.slots):
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            batch = rows[first:first + renderer.slots]
            matrix[batch] = renderer.rows(batch)
            if progress is not None:
                done = first + len(batch)
                progress(done / len(rows), f"hemi-cubes {done}/{len(rows)}", {"hemicubes": done})
    return matrix
