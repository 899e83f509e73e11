"""Uniform subdivision of surfaces into patches (vectorized numpy).

Every patch is stored as a quad of four corners c0..c3 (counter-clockwise from
the front). A triangle's sub-triangles repeat their last corner (c3 == c2), so
one code path serves both: a point of a patch is the bilinear map

    p(s, t) = c0 (1-s)(1-t) + c1 s (1-t) + c2 s t + c3 (1-s) t,   s, t in [0, 1],

which is also how elements (progressive) and lightmap texels find their place.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import Scene


@dataclass
class Patches:
    corners: np.ndarray  # (P, 4, 3) float64
    uv: np.ndarray  # (P, 4, 2) lightmap UVs of the corners (zeros when the scene has none)
    surface: np.ndarray  # (P,) int32 index into scene.surfaces
    reflectance: np.ndarray  # (P, 3)
    emission: np.ndarray  # (P, 3)
    is_triangle: np.ndarray  # (P,) bool: c3 repeats c2
    grid: np.ndarray  # (P, 2) int32 (row, column) of the patch in its surface's N x N split
    subdiv: int

    def __len__(self) -> int:
        return len(self.corners)

    @property
    def area_vector(self) -> np.ndarray:
        c = self.corners
        return 0.5 * np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])

    @property
    def area(self) -> np.ndarray:
        return np.linalg.norm(self.area_vector, axis=1)

    @property
    def normal(self) -> np.ndarray:
        a = self.area_vector
        return a / np.linalg.norm(a, axis=1, keepdims=True)

    @property
    def center(self) -> np.ndarray:
        """Area centroid (the two triangles c0c1c2 and c0c2c3, weighted by area)."""
        c = self.corners
        first = np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
        second = np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]), axis=1)
        centroid_first = (c[:, 0] + c[:, 1] + c[:, 2]) / 3
        centroid_second = (c[:, 0] + c[:, 2] + c[:, 3]) / 3
        total = (first + second)[:, None]
        return (first[:, None] * centroid_first + second[:, None] * centroid_second) / total

    def triangles(self) -> np.ndarray:
        """(P, 2, 3, 3): each patch as two triangles (the second is degenerate for triangles)."""
        c = self.corners
        return np.stack([c[:, [0, 1, 2]], c[:, [0, 2, 3]]], axis=1)

    def points(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Bilinear points of every patch at parameters s, t (broadcast): (P, *s.shape, 3)."""
        return bilinear(self.corners, s, t)


def bilinear(corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """corners (P, 4, D); s, t arrays of one shape -> (P, *shape, D)."""
    s = np.asarray(s, dtype=np.float64)[None, ..., None]
    t = np.asarray(t, dtype=np.float64)[None, ..., None]
    expand = (slice(None),) + (None,) * (s.ndim - 2)
    c0, c1, c2, c3 = (corners[expand + (k,)] for k in range(4))
    return c0 * (1 - s) * (1 - t) + c1 * s * (1 - t) + c2 * s * t + c3 * (1 - s) * t


def _quad_grid(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Corner parameters (n*n, 4, 2) of an n x n split of the unit square, and (row, col)."""
    rows, cols = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    rows, cols = rows.ravel(), cols.ravel()
    offsets = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)  # (s, t)
    params = (np.stack([cols, rows], axis=1)[:, None, :] + offsets[None]) / n
    return params, rows, cols


def _triangle_grid(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Barycentric (b1, b2) corners (n*n, 4, 2) of the n^2 sub-triangles of a triangle.

    Row r (from the v0-v1 edge towards v2) holds 2(n-r)-1 triangles: upright
    ones (i, r), (i+1, r), (i, r+1) and inverted ones (i+1, r), (i+1, r+1),
    (i, r+1), all counter-clockwise like the parent.
    """
    corners, rows, cols = [], [], []
    for r in range(n):
        for i in range(n - r):
            corners.append([(i, r), (i + 1, r), (i, r + 1), (i, r + 1)])
            rows.append(r)
            cols.append(2 * i)
            if i < n - r - 1:
                corners.append([(i + 1, r), (i + 1, r + 1), (i, r + 1), (i, r + 1)])
                rows.append(r)
                cols.append(2 * i + 1)
    return np.asarray(corners, dtype=np.float64) / n, np.asarray(rows), np.asarray(cols)


def subdivide(scene: Scene, n: int) -> Patches:
    """Split every surface into n x n patches (quads) or n^2 sub-triangles (triangles)."""
    if n < 1:
        raise ValueError("subdivision must be at least 1")
    quad_params, quad_rows, quad_cols = _quad_grid(n)
    tri_params, tri_rows, tri_cols = _triangle_grid(n)

    corners, uvs, surface_index, triangle, grid = [], [], [], [], []
    for index, surface in enumerate(scene.surfaces):
        uv = surface.uv if surface.uv is not None else np.zeros((len(surface.vertices), 2))
        if surface.is_triangle:
            weights = np.concatenate([1 - tri_params.sum(axis=2, keepdims=True), tri_params], axis=2)
            corners.append(weights @ surface.vertices)
            uvs.append(weights @ uv)
            grid.append(np.stack([tri_rows, tri_cols], axis=1))
        else:
            quad = np.asarray(surface.vertices)[None]
            corners.append(bilinear(quad, quad_params[..., 0], quad_params[..., 1])[0])
            uvs.append(bilinear(uv[None], quad_params[..., 0], quad_params[..., 1])[0])
            grid.append(np.stack([quad_rows, quad_cols], axis=1))
        count = len(corners[-1])
        surface_index.append(np.full(count, index, dtype=np.int32))
        triangle.append(np.full(count, surface.is_triangle))

    surface_index = np.concatenate(surface_index)
    reflectance = np.stack([s.reflectance for s in scene.surfaces])[surface_index]
    emission = np.stack([s.emission for s in scene.surfaces])[surface_index]
    return Patches(
        corners=np.concatenate(corners),
        uv=np.concatenate(uvs),
        surface=surface_index,
        reflectance=reflectance,
        emission=emission,
        is_triangle=np.concatenate(triangle),
        grid=np.concatenate(grid).astype(np.int32),
        subdiv=n,
    )
