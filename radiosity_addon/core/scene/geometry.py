"""Geometry of planar polygons and bilinear patches, vectorized over leading axes.

A polygon is stored as four corners c0..c3, counter-clockwise seen from its front; a triangle
repeats its last corner (c3 == c2). A point of it is the bilinear map

    p(s, t) = c0 (1-s)(1-t) + c1 s (1-t) + c2 s t + c3 (1-s) t,   s, t in [0, 1],

which for a triangle is the collapsed quad whose t = 1 edge is the apex. Patches, elements and
lightmap texels all find their place through it.
"""

from __future__ import annotations

import numpy as np


def area_vector(corners: np.ndarray) -> np.ndarray:
    """(..., 3) half the cross product of the diagonals: |v| is the area of a planar quad or
    triangle (c3 == c2), v/|v| its front normal. corners (..., 4, 3)."""
    c = np.asarray(corners, dtype=np.float64)
    return 0.5 * np.cross(c[..., 2, :] - c[..., 0, :], c[..., 3, :] - c[..., 1, :])


def polygon_area_vector(vertices: np.ndarray) -> np.ndarray:
    """Area vector of one polygon of k vertices (k, 3), by a fan of cross products."""
    v = np.asarray(vertices, dtype=np.float64)
    return 0.5 * np.cross(v[1:-1] - v[0], v[2:] - v[0]).sum(axis=0)


def unit(vectors: np.ndarray) -> np.ndarray:
    vectors = np.asarray(vectors, dtype=np.float64)
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def bilinear(corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """corners (P, 4, D); s, t arrays of one shape -> (P, *shape, D)."""
    return bilinear_each(corners, np.asarray(s)[None], np.asarray(t)[None])


def bilinear_each(corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """corners (P, 4, D); s, t (P, ...) parameters of each patch's own points -> (P, ..., D)."""
    s, t = np.asarray(s, dtype=np.float64)[..., None], np.asarray(t, dtype=np.float64)[..., None]
    expand = (slice(None),) + (None,) * (s.ndim - 2)
    c0, c1, c2, c3 = (corners[expand + (k,)] for k in range(4))
    return c0 * (1 - s) * (1 - t) + c1 * s * (1 - t) + c2 * s * t + c3 * (1 - s) * t


def tangent_frame(normal: np.ndarray, hint: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Unit x, y completing a right-handed frame (x, y, normal); x along `hint` when given."""
    x, y = tangent_axes(np.asarray(normal, dtype=np.float64)[None],
                        np.zeros((1, 3)) if hint is None else np.asarray(hint, dtype=np.float64)[None])
    return x[0], y[0]


def tangent_axes(normals: np.ndarray, hints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit x, y (P, 3) completing right-handed frames (x, y, normal) for the rows of `normals`,
    each x along its row of `hints` (P, 3) unless that is (nearly) parallel to the normal, or zero.
    All rows at once: `tangent_frame` costs ~50 us of numpy's small-array overhead a call, and a
    progressive solve shoots thousands of patches (`shooting.PatchShooters`)."""
    normals, hints = np.asarray(normals, dtype=np.float64), np.asarray(hints, dtype=np.float64)
    loose = np.linalg.norm(np.cross(hints, normals), axis=1) < 1e-6
    fallback = np.where((np.abs(normals[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    hints = np.where(loose[:, None], fallback, hints)
    x = hints - np.einsum("pd,pd->p", hints, normals)[:, None] * normals
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return x, np.cross(normals, x)


def tangent_frames(points: np.ndarray, normals: np.ndarray, edges: np.ndarray):
    """Frames (origin, tangent, bitangent, normal) at many points, each tangent along `edges`."""
    tangent = edges - (edges * normals).sum(axis=1, keepdims=True) * normals
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    return points, tangent, np.cross(normals, tangent), normals


def area_centroid(corners: np.ndarray) -> np.ndarray:
    """(P, 3) area centroids of quads (P, 4, 3): the triangles c0c1c2 and c0c2c3 weighted by area."""
    c = corners
    first = np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1)
    second = np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]), axis=1)
    centroid_first = (c[:, 0] + c[:, 1] + c[:, 2]) / 3
    centroid_second = (c[:, 0] + c[:, 2] + c[:, 3]) / 3
    total = (first + second)[:, None]
    return (first[:, None] * centroid_first + second[:, None] * centroid_second) / total


def reversed_corners(corners: np.ndarray, is_triangle: np.ndarray) -> np.ndarray:
    """The same polygons seen from the back: quads (c0, c3, c2, c1), triangles (c0, c2, c1, c1)."""
    flipped = corners[:, [0, 3, 2, 1]]
    flipped[is_triangle] = corners[is_triangle][:, [0, 2, 1, 1]]
    return flipped
