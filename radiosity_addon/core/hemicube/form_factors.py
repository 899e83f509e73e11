"""The form factors of the hemi-cube method: hemi-cubes at the element centres of every receiving
patch (batched on the GPU), or the analytic unoccluded kernel when nothing can occlude. A patch's
row of F is the area-weighted mean of its elements' rows — the form factor integrated over the
receiver, not only at its centre, which the centre-point factor misses badly where a patch lies
closer to another than its own size (an emitter under a ceiling, a contact). Memory is P x P plus
P·S² x P float32, so the guard refuses before any work."""

from __future__ import annotations

import numpy as np

from ..timing import pulse

from ..errors import SolveCancelled, SolveError
from ..gpu import GPU
from ..scene import Patches
from ..shooting import element_areas, element_centers
from ..scene.geometry import tangent_frames
from ..visibility import HemicubeRenderer
from .analytic import point_to_polygon


def matrix_bytes(patch_count: int, elements: int = 1) -> int:
    """The patch matrix and the element rows (float32), and a float64 copy of the patch matrix."""
    return patch_count * patch_count * 4 * (1 + elements * elements + 2)


def patch_budget(limit_bytes: int, elements: int = 1) -> int:
    """The most patches whose matrices fit in `limit_bytes`."""
    return int((limit_bytes / (4 * (1 + elements * elements + 2))) ** 0.5)


def check_memory(patch_count: int, limit_bytes: int, elements: int = 1) -> None:
    need = matrix_bytes(patch_count, elements)
    if need > limit_bytes:
        raise SolveError(
            f"the hemi-cube method needs {patch_count}x{patch_count} form-factor matrices"
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
            pulse()
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            batch = rows[first:first + renderer.slots]
            matrix[batch] = renderer.rows(batch)
            if progress is not None:
                done = first + len(batch)
                progress(done / len(rows), f"hemi-cubes {done}/{len(rows)}", {"hemicubes": done})
    return matrix


def element_frames(patches: Patches, rows: np.ndarray, elements: int):
    """Hemi-cube frames at the element centres of patches `rows`, in element order [row, j, i]."""
    per_patch = elements * elements
    centres = element_centers(patches, elements)[rows].reshape(-1, 3)
    normals = np.repeat(patches.normal[rows], per_patch, axis=0)
    edges = np.repeat(patches.corners[rows, 1] - patches.corners[rows, 0], per_patch, axis=0)
    return tangent_frames(centres, normals, edges)


def element_form_factors(gpu: GPU, patches: Patches, elements: int, resolution: int, scene_diameter: float,
                         rows: np.ndarray, occlusion: bool = True, progress=None, should_cancel=None) -> np.ndarray:
    """(len(rows) · S², P) float32: the form factors from every element of the patches `rows` to every
    patch, by hemi-cubes at the element centres (or Lambert's unoccluded formula without occlusion)."""
    frames = element_frames(patches, rows, elements)
    count = len(frames[0])
    result = np.zeros((count, len(patches)), dtype=np.float32)
    if count == 0:
        return result
    if not occlusion:
        step = max(1, (1 << 26) // (len(patches) * 4 * 3 * 8 * 6))
        owner = np.repeat(rows, elements * elements)
        for first in range(0, count, step):
            pulse()
            chosen = slice(first, first + step)
            block = point_to_polygon(frames[0][chosen], frames[3][chosen], patches.corners)
            block[np.arange(len(block)), owner[chosen]] = 0.0  # a planar patch cannot see itself
            result[chosen] = block
        return result
    with gpu.resources() as res:
        renderer = HemicubeRenderer(res, patches, resolution, scene_diameter, used_slots=count)
        for first in range(0, count, renderer.slots):
            pulse()
            if should_cancel is not None and should_cancel():
                raise SolveCancelled("cancelled")
            batch = tuple(v[first:first + renderer.slots] for v in frames)
            renderer.coverage(batch, np.float32, out=result[first:first + len(batch[0])])  # the fronts' columns
            if progress is not None:
                done = first + len(batch[0])
                progress(done / count, f"hemi-cubes {done}/{count}", {"hemicubes": done})
    return result


def patch_rows(element_rows: np.ndarray, patches: Patches, rows: np.ndarray, elements: int) -> np.ndarray:
    """(P, P) float32 F: each row in `rows` the area-weighted mean of its elements' rows; others 0.
    One element a patch and every row: `element_rows` itself (a copy would be P² more bytes)."""
    if elements == 1 and len(rows) == len(patches):  # rows are every patch, in order
        return element_rows
    matrix = np.zeros((len(patches), len(patches)), dtype=np.float32)
    if len(rows) == 0:
        return matrix
    if elements == 1:  # each row is its one element's
        matrix[rows] = element_rows
        return matrix
    weights = element_areas(patches, elements)[rows].reshape(len(rows), -1)
    weights = weights / weights.sum(axis=1, keepdims=True)
    matrix[rows] = np.einsum("re,rep->rp", weights, element_rows.reshape(len(rows), elements * elements, -1))
    return matrix
