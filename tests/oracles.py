"""Independent references for the tests: CPU (numpy, float64) versions of what the GPU computes,
and small helpers to look inside GPU objects. Nothing here ships in the extension.

- `visible_from`: ray-cast visibility, the check of the progressive method's item buffers;
- `point_to_clipped_polygon`: the exact point-to-polygon form factor with the polygon clipped
  to the receiver's hemisphere (the shooting pass's exact kernel);
- `spot_falloff`: Cycles' spot cone;
- `visibility_misclassification`: a visibility variant's errors against `visible_from`;
- `hemispherical_projection`, `item_buffer_image`, `patch_shooter`.
"""

from __future__ import annotations

import math

import numpy as np

from radiosity_addon.core import Patches
from radiosity_addon.core.shooting import (ElementTextures, PatchBuffers, PatchShooters, ShootingPass, ShotVisibility,
                                           element_centers)
from radiosity_addon.core.visibility import VARIANTS


def hemispherical_projection(points: np.ndarray, eye: np.ndarray, axes) -> np.ndarray:
    """(x/|p|, y/|p|, z/|p|) of points (..., 3) in the eye's frame (the visibility map's projection)."""
    d = np.asarray(points) - eye
    q = np.stack([d @ axes[0], d @ axes[1], d @ axes[2]], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def item_buffer_image(visibility_map) -> np.ndarray:
    """(R, R) uint32 item buffer [y, x] of a VisibilityMap: patch id + 1, 0 = nothing."""
    r = visibility_map.resolution
    return np.frombuffer(visibility_map.items.read(), dtype=np.uint32).reshape(r, r)


def patch_shooter(patches: Patches, index: int, radiosity, eye_parameters=None):
    """One patch as a Shooter (the progressive method makes them with PatchShooters)."""
    return PatchShooters(patches).shooter(index, radiosity, eye_parameters)


def visible_from(eye: np.ndarray, points: np.ndarray, patches: Patches, ignore: np.ndarray,
                 epsilon: float = 1e-6, chunk: int = 2048) -> np.ndarray:
    """(N,) bool: the segment eye -> points[k] hits no patch triangle except `ignore[k]`
    (the receiver's own patch) strictly between its ends (relative margin `epsilon`)."""
    c = patches.corners
    triangles = np.stack([c[:, [0, 1, 2]], c[:, [0, 2, 3]]], axis=1)  # (P, 2, 3, 3)
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


def point_to_clipped_polygon(points: np.ndarray, normals: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(N,) differential-area-to-polygon form factors from points (N, 3) with unit normals (N, 3)
    to one planar convex polygon (K, 3) whose front faces the points. Parts of the polygon behind
    a point's tangent plane are clipped away first (Sutherland–Hodgman), so this also holds where
    `point_to_polygon` does not. The CPU reference of the progressive method's exact GPU kernel
    (shaders/shoot_to_elements.comp); a loop per point, for tests and tools."""
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


def spot_falloff(cos_angle: np.ndarray, lamp) -> np.ndarray:
    """Cycles' spot cone: smoothstep over the blend band inside the cone's edge."""
    cos_half = math.cos(lamp.spot_size / 2)
    smooth = (1 - cos_half) * lamp.spot_blend
    t = np.clip((cos_angle - cos_half) / smooth, 0, 1) if smooth > 0 else (cos_angle > cos_half).astype(float)
    return t * t * (3 - 2 * t)


def visibility_misclassification(gpu, scene, patches, elements: int, resolution: int, variant: str, shooters) -> dict:
    """How the GPU visibility of `variant` misclassifies receiver elements against `visible_from`, for
    shots from the patches `shooters`: fractions wrong (all, non-grazing), counts, form-factor weighted."""
    count = len(patches)
    x = element_centers(patches, elements).reshape(-1, 3)
    owner = np.repeat(np.arange(count), elements ** 2)
    normal = patches.normal[owner]
    wrong = total = false_visible = false_hidden = 0
    wrong_steep = total_steep = 0
    weight_wrong = weight_visible = 0.0
    with gpu.resources() as res:
        textures = ElementTextures(res, patches, elements)
        buffers = PatchBuffers(res, patches, textures)
        shooting = ShootingPass(res, textures, buffers, "exact",
                                ShotVisibility(res, patches, resolution, variant, scene.diameter),
                                record_visibility=True)
        for s in shooters:
            shooter = patch_shooter(patches, s, np.zeros(3))
            shooting.shoot([shooter])
            seen = shooting.recorded_visibility() > 0.5
            d = x - shooter.position
            r = np.linalg.norm(d, axis=1)
            cos_shooter = (d @ shooter.axes[2]) / r
            cos_receiver = -(normal * d).sum(axis=1) / r
            candidate = (cos_shooter > 1e-9) & (cos_receiver > 1e-9) & (owner != s)
            ref = visible_from(shooter.position, x[candidate], patches, owner[candidate])
            got = seen[candidate]
            bad = got != ref
            wrong += bad.sum()
            total += candidate.sum()
            false_visible += (got & ~ref).sum()
            false_hidden += (~got & ref).sum()
            steep = (cos_shooter[candidate] > 0.05) & (cos_receiver[candidate] > 0.05)
            wrong_steep += (bad & steep).sum()
            total_steep += steep.sum()
            area = shooter.area
            weight = area * cos_shooter[candidate] * cos_receiver[candidate] / (np.pi * r[candidate] ** 2 + area)
            weight_wrong += weight[bad].sum()
            weight_visible += weight[ref].sum()
    return {"variant": variant, "search_radius": VARIANTS[variant].search_radius, "misclassified": wrong / total,
            "false_visible": int(false_visible), "false_hidden": int(false_hidden), "candidates": int(total),
            "misclassified_non_grazing": wrong_steep / max(total_steep, 1),
            "form_factor_weighted_error": weight_wrong / weight_visible}
