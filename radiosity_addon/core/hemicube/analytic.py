"""Analytic unoccluded form factors in numpy (float64), vectorized over point x polygon pairs:
the hemi-cube method's kernel when the scene analysis proves nothing occludes."""

from __future__ import annotations

import numpy as np


def point_to_polygon(points: np.ndarray, normals: np.ndarray, polygons: np.ndarray) -> np.ndarray:
    """Unoccluded form factor from differential areas to polygons (Lambert's contour formula).

    points, normals: (M, 3); polygons: (N, K, 3), counter-clockwise seen from their fronts
    (a repeated vertex, as in triangle patches, adds nothing). Returns (M, N):

        F = -1/(2π) Σ_k γ_k  n · (R_k × R_k+1) / |R_k × R_k+1|,   R_k = v_k − x,

    γ_k the angle between R_k and R_k+1. Exact when every polygon lies in the closed front
    half-space of the point (the case of a scene without occlusion, e.g. a convex room);
    polygons whose front does not face the point give 0.
    """
    relative = polygons[None, :, :, :] - points[:, None, None, :]  # (M, N, K, 3)
    following = np.roll(relative, -1, axis=2)
    cross = np.cross(relative, following)
    cross_norm = np.linalg.norm(cross, axis=-1)
    sine_scale = np.linalg.norm(relative, axis=-1) * np.linalg.norm(following, axis=-1)
    dot = np.einsum("mnkd,mnkd->mnk", relative, following)
    angle = np.arctan2(cross_norm, dot)  # γ_k, robust for tiny and near-straight angles
    safe_norm = np.where(cross_norm > 1e-300, cross_norm, 1.0)
    projected = np.einsum("mnkd,md->mnk", cross, normals) / safe_norm
    contribution = np.where((cross_norm > 1e-300) & (sine_scale > 0), angle * projected, 0.0)
    factor = -contribution.sum(axis=2) / (2 * np.pi)

    polygon_area_vector = 0.5 * np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, -1] - polygons[:, 1])
    if polygons.shape[1] == 3:
        polygon_area_vector = 0.5 * np.cross(polygons[:, 1] - polygons[:, 0], polygons[:, 2] - polygons[:, 0])
    facing = np.einsum("mnd,nd->mn", -relative[:, :, 0, :], polygon_area_vector) > 0
    return np.where(facing, np.maximum(factor, 0.0), 0.0)


def unoccluded_form_factor_matrix(centers: np.ndarray, normals: np.ndarray, corners: np.ndarray,
                                  rows: np.ndarray, chunk_bytes: int = 1 << 28) -> np.ndarray:
    """F (P x P, float32) from patch centres to patch polygons without visibility, for the
    given rows (other rows stay 0) — the hemi-cube's centre-point factor, without its aliasing."""
    count = len(corners)
    matrix = np.zeros((count, count), dtype=np.float32)
    per_row = count * corners.shape[1] * 3 * 8 * 6  # the kernel's largest temporaries
    step = max(1, chunk_bytes // per_row)
    for start in range(0, len(rows), step):
        chosen = rows[start:start + step]
        block = point_to_polygon(centers[chosen], normals[chosen], corners)
        block[np.arange(len(chosen)), chosen] = 0.0  # a planar patch cannot see itself
        matrix[chosen] = block
    return matrix
