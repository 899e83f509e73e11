"""A common texel grid on which every answer is compared: Cycles bakes, exact answers, our solutions.

Each surface has an R x R grid over its own parameters (s, t) in [0, 1]² — bilinear for
quads, barycentric (b1 = s, b2 = t) for triangles — the parameters `core.subdivide`
splits on and `blender.cycles_reference` lays its UVs by. Texel (row, column) covers
s in [column/R, (column+1)/R], t in [row/R, (row+1)/R].

A texel counts ("covered") when the texels within EDGE_TEXELS of it lie inside the polygon:
a bake's texels near an edge mix in samples from past it (its pixel filter is wider than a
texel), so they are not compared.
"""

from __future__ import annotations

import numpy as np

from radiosity_addon.core import Patches, Scene, bilinear

EDGE_TEXELS = 2
SUPERSAMPLES = 4  # per texel side: our piecewise-constant answer is averaged over the texel like a bake


def covered_mask(is_triangle: bool, resolution: int) -> np.ndarray:
    """(R, R) bool: texels at least EDGE_TEXELS texels inside the surface's edges."""
    rows, cols = np.meshgrid(np.arange(resolution), np.arange(resolution), indexing="ij")
    low, high = EDGE_TEXELS, resolution - 1 - EDGE_TEXELS
    inside = (rows >= low) & (cols >= low) & (rows <= high) & (cols <= high)
    if is_triangle:  # the far corner (row + 1, col + 1) plus the margin stays under the hypotenuse s + t = 1
        inside &= (rows + 1 + EDGE_TEXELS) + (cols + 1 + EDGE_TEXELS) <= resolution
    return inside


def texel_weights(scene: Scene, resolution: int) -> np.ndarray:
    """(surfaces, R, R): world area of each covered texel, 0 for texels not compared."""
    weights = np.zeros((len(scene), resolution, resolution))
    for index in range(len(scene)):
        triangle = bool(scene.is_triangle[index])
        uv_area = 0.5 if triangle else 1.0
        weights[index] = covered_mask(triangle, resolution) * scene.area[index] / uv_area / resolution**2
    return weights


def sample_parameters(resolution: int, supersamples: int = SUPERSAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """(s, t) of supersamples² points in every texel: arrays (R, R, k²)."""
    offsets = (np.arange(supersamples) + 0.5) / supersamples
    sub_s, sub_t = np.meshgrid(offsets, offsets, indexing="xy")
    rows, cols = np.meshgrid(np.arange(resolution), np.arange(resolution), indexing="ij")
    s = (cols[..., None] + sub_s.ravel()) / resolution
    t = (rows[..., None] + sub_t.ravel()) / resolution
    return s, t


def surface_points(surface, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """World points at parameters (s, t) of one surface: (*s.shape, 3)."""
    v = np.asarray(surface.vertices, dtype=np.float64)
    if surface.is_triangle:
        return v[0] + s[..., None] * (v[1] - v[0]) + t[..., None] * (v[2] - v[0])
    return bilinear(v[None], s, t)[0]


def _patch_lookup(patches: Patches, surface_count: int) -> np.ndarray:
    """(surfaces, rows, 2 columns) patch index by (surface, grid row, grid column); -1 where none."""
    n = int(patches.split.max())
    lookup = np.full((surface_count, n, 2 * n), -1, dtype=np.int64)
    fronts = np.flatnonzero(~patches.is_back)  # the texels show the front
    keys = np.stack([patches.surface[fronts], patches.grid[fronts, 0], patches.grid[fronts, 1]], axis=1)
    if len(np.unique(keys, axis=0)) < len(fronts):  # refined patches' children keep their parent's cell
        raise ValueError("refined patches share a grid cell: the sweep maps unrefined solves only (refinements=0)")
    lookup[keys[:, 0], keys[:, 1], keys[:, 2]] = fronts
    return lookup


def _locate(is_triangle: bool, split, s: np.ndarray, t: np.ndarray):
    """Grid row, grid column and in-patch (s, t) of parameters on a (columns, rows) split (core.subdivide)."""
    columns, rows = int(split[0]), int(split[1])
    scaled_s, scaled_t = np.clip(s * columns, 0, columns - 1e-9), np.clip(t * rows, 0, rows - 1e-9)
    column, row = np.floor(scaled_s).astype(np.int64), np.floor(scaled_t).astype(np.int64)
    local_s, local_t = scaled_s - column, scaled_t - row
    if not is_triangle:
        return row, column, local_s, local_t
    inverted = local_s + local_t > 1  # the sub-triangle (i+1, r), (i+1, r+1), (i, r+1)
    return row, 2 * column + inverted, local_s, local_t


def surface_grid(patches: Patches, surface_index: int, patch_radiosity: np.ndarray,
                 element_radiosity: np.ndarray | None) -> np.ndarray:
    """(rows·S, columns·S, 3) values of a quad surface on its regular grid of patches (S = 1) or
    elements, indexed [t row, s column]."""
    n_columns, n_rows = (int(v) for v in patches.split[surface_index])
    members = np.flatnonzero((patches.surface == surface_index) & ~patches.is_back)
    rows, columns = patches.grid[members, 0], patches.grid[members, 1]
    if element_radiosity is None:
        grid = np.zeros((n_rows, n_columns, 3))
        grid[rows, columns] = patch_radiosity[members]
        return grid
    size = element_radiosity.shape[1]
    grid = np.zeros((n_rows, size, n_columns, size, 3))
    grid[rows, :, columns, :] = element_radiosity[members]
    return grid.reshape(n_rows * size, n_columns * size, 3)


def bilinear_on_grid(grid: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Bilinear interpolation between cell centres of `grid` (rows, columns, 3), clamped at the border:
    what a lightmap with one texel per cell shows under bilinear filtering."""
    my, mx = grid.shape[:2]
    x, y = np.clip(s * mx - 0.5, 0, mx - 1), np.clip(t * my - 0.5, 0, my - 1)
    x0 = np.minimum(np.floor(x).astype(np.int64), mx - 2 if mx > 1 else 0)
    y0 = np.minimum(np.floor(y).astype(np.int64), my - 2 if my > 1 else 0)
    x1, y1 = np.minimum(x0 + 1, mx - 1), np.minimum(y0 + 1, my - 1)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    return ((1 - fy) * ((1 - fx) * grid[y0, x0] + fx * grid[y0, x1])
            + fy * ((1 - fx) * grid[y1, x0] + fx * grid[y1, x1]))


def solution_texels(scene: Scene, patches: Patches, patch_radiosity: np.ndarray,
                    element_radiosity: np.ndarray | None, resolution: int, interpolate: bool = False) -> np.ndarray:
    """(surfaces, R, R, 3): our answer averaged over each texel.

    Per element where the solution has elements and the patch is a quad, else per patch; piecewise
    constant, or with `interpolate` bilinear between cell centres on quad surfaces (as a lightmap
    shows it; triangle surfaces stay piecewise constant).
    """
    lookup = _patch_lookup(patches, len(scene))
    s, t = sample_parameters(resolution)
    texels = np.zeros((len(scene), resolution, resolution, 3))
    for index in range(len(scene)):
        triangle = bool(scene.is_triangle[index])
        if interpolate and not triangle:
            grid = surface_grid(patches, index, patch_radiosity, element_radiosity)
            texels[index] = bilinear_on_grid(grid, s, t).mean(axis=2)
            continue
        row, column, local_s, local_t = _locate(triangle, patches.split[index], s, t)
        patch = lookup[index, row, column]
        values = patch_radiosity[patch]
        if element_radiosity is not None and not triangle:
            size = element_radiosity.shape[1]
            element_t = np.minimum((local_t * size).astype(np.int64), size - 1)
            element_s = np.minimum((local_s * size).astype(np.int64), size - 1)
            values = element_radiosity[patch, element_t, element_s]
        texels[index] = values.mean(axis=2)
    return texels


def texel_patches(scene: Scene, patches: Patches, resolution: int) -> np.ndarray:
    """(surfaces, R, R) index of the patch holding each texel's centre (meaningful on covered texels)."""
    lookup = _patch_lookup(patches, len(scene))
    s, t = sample_parameters(resolution, supersamples=1)
    owners = np.zeros((len(scene), resolution, resolution), dtype=np.int64)
    for index in range(len(scene)):
        row, column, _, _ = _locate(bool(scene.is_triangle[index]), patches.split[index], s[..., 0], t[..., 0])
        owners[index] = lookup[index, row, column]
    return owners
