"""CPU references for the progressive method's GPU passes (numpy, float64).

- `visible_from`: ray-cast visibility from a point to many points against all
  patch triangles (Möller–Trumbore), the independent check of the
  hemispherical item buffer.
- `point_polygon_form_factor`: Lambert's contour integral from points with
  normals to a convex polygon clipped to each point's front half-space, the
  reference of the GPU's exact kernel.
"""

from __future__ import annotations

import numpy as np

from .patches import Patches


def visible_from(eye: np.ndarray, points: np.ndarray, patches: Patches, ignore: np.ndarray,
                 epsilon: float = 1e-6, chunk: int = 2048) -> np.ndarray:
    """(N,) bool: the segment eye -> points[k] hits no patch triangle except `ignore[k]`
    (the receiver's own patch) strictly between its ends (relative margin `epsilon`)."""
    triangles = patches.triangles()  # (P, 2, 3, 3)
    keep = np.ones(triangles.shape[:2], dtype=bool)
    keep[patches.is_triangle, 1] = False
    owner = np.repeat(np.arange(len(patches))[:, None], 2, axis=1)[keep]
    v0, v1, v2 = (triangles[keep][:, k] for k in range(3))
    e1, e2 = v1 - v0, v2 - v0
    out = np.empty(len(points), dtype=bool)
    for start in range(0, len(points), chunk):
        d = points[start:start + chunk] - eye  # (n, 3) segment, t in (0, 1)
        pvec = np.cross(d[:, None], e2[None])  # (n, T, 3)
        det = (e1[None] * pvec).sum(-1)
        ok = np.abs(det) > 1e-15
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tvec = (eye - v0)[None]
        u = (tvec * pvec).sum(-1) * inv
        qvec = np.cross(tvec, e1[None])
        v = (d[:, None] * qvec).sum(-1) * inv
        t = (e2[None] * qvec).sum(-1) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > epsilon) & (t < 1 - epsilon)
        hit &= owner[None] != ignore[start:start + chunk, None]
        out[start:start + chunk] = ~hit.any(axis=1)
    return out


def point_polygon_form_factor(points: np.ndarray, normals: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(N,) differential-area-to-polygon form factors from points (N, 3) with unit normals (N, 3)
    to a planar convex polygon (K, 3) whose front faces the points. Parts of the polygon behind
    a point's tangent plane are clipped away."""
    points, normals = np.atleast_2d(points), np.atleast_2d(normals)
    result = np.zeros(len(points))
    for n_index in range(len(points)):
        x, n = points[n_index], normals[n_index]
        rel = polygon - x
        heights = rel @ n
        clipped = []
        for k in range(len(rel)):
            a, b, da, db = rel[k], rel[(k + 1) % len(rel)], heights[k], heights[(k + 1) % len(rel)]
            if da >= 0:
                clipped.append(a)
            if (da >= 0) != (db >= 0):
                clipped.append(a + (b - a) * da / (da - db))
        total = 0.0
        for k in range(len(clipped)):
            a, b = clipped[k], clipped[(k + 1) % len(clipped)]
            la, lb = np.linalg.norm(a), np.linalg.norm(b)
            if la < 1e-300 or lb < 1e-300:
                continue
            c = np.cross(a / la, b / lb)
            lc = np.linalg.norm(c)
            if lc > 1e-15:
                total += np.arctan2(lc, np.dot(a, b) / (la * lb)) * np.dot(n, c) / lc
        result[n_index] = max(-total, 0.0) / (2 * np.pi)
    return result
