"""CPU ray-cast visibility (numpy, float64): the independent check of the
progressive method's hemispherical item buffers. `visible_from` tests segments
from a point to many points against all patch triangles (Möller–Trumbore).
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
