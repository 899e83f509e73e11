"""The solve's smooth light on clustered faces: a weighted mean of nearby element values at their
corners, laid over their texels by the rasterizer (linear over each face).

A face the solve took as part of a cluster (`scene.face_clusters`) has no patches of its own: its
cluster was solved as a rectangle that covers the faces only roughly (a curved cluster bulges off
it, neighbouring rectangles leave slivers between them), so the patch lattices, continuous across
the edges patches share, cannot be laid onto its texels. Each face corner instead takes the mean of
the element values around its point, of its object only (a face's texels then cost nothing more than
its rasterization): every element centre is a sample reaching
SUPPORT times its element's half-diagonal, weighted (1 - d²/r²)², and by how far its normal turns
from the texel's (none past NORMAL_LIMIT_DEGREES: the other side of a thin object or of a crease).
The weights fall to zero at a sample's reach, so the light is continuous across clusters and
their faces; a corner that no sample reaches (a face bulging far off its cluster) takes the nearest
sample's value.
"""

from __future__ import annotations

import math

import numpy as np

from ..scene import Patches
from ..scene.geometry import bilinear
from ..scene.neighbours import near_pairs
from ..scene.rows import row_labels
from ..shooting.elements import element_parameters

SUPPORT = 2.0  # a sample's reach in half-diagonals of its element: 2 reaches the ring of elements around it
NORMAL_LIMIT_DEGREES = 60.0  # samples whose normal turns further from the texel's take no part
NEAREST_CHUNK = 1 << 22  # (texel, sample) distances at once for the texels no sample reaches


def element_samples(patches: Patches, values: np.ndarray, rows: np.ndarray):
    """Samples of the element `values` (P, S, S, 3) of the patches `rows`: centres (n, 3), normals
    (n, 3), reaches (n,), values (n, 3) and patches (n,)."""
    elements = values.shape[1]
    s, t = element_parameters(elements)
    centres = bilinear(patches.corners[rows], s, t).reshape(-1, 3)
    step = 1.0 / elements
    low, high = bilinear(patches.corners[rows], s - 0.5 * step, t - 0.5 * step), bilinear(
        patches.corners[rows], s + 0.5 * step, t + 0.5 * step)
    across = np.linalg.norm(high - low, axis=-1).reshape(-1)
    low2, high2 = bilinear(patches.corners[rows], s + 0.5 * step, t - 0.5 * step), bilinear(
        patches.corners[rows], s - 0.5 * step, t + 0.5 * step)
    across = np.maximum(across, np.linalg.norm(high2 - low2, axis=-1).reshape(-1))
    per_patch = elements * elements
    return (centres, np.repeat(patches.normal[rows], per_patch, axis=0), SUPPORT * 0.5 * across,
            values[rows].reshape(-1, 3), np.repeat(rows, per_patch))


def scattered_values(points: np.ndarray, normals: np.ndarray, samples) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) the samples' weighted mean at `points` (N, 3) with `normals` (N, 3) (module doc), and
    (N,) the patch of the sample weighing most at each."""
    centres, sample_normals, reach, values, patch = samples
    count = len(points)
    result = np.zeros((count, 3))
    total = np.zeros(count)
    best, best_patch = np.zeros(count), np.full(count, -1, dtype=np.int64)
    if count == 0 or len(centres) == 0:
        return result, best_patch
    limit = math.cos(math.radians(NORMAL_LIMIT_DEGREES))
    everything = np.concatenate([points, centres])
    radius = np.concatenate([np.zeros(count), reach])
    queries = np.arange(count)
    for query, other in near_pairs(everything, radius, queries, np.zeros(count), others=count + np.arange(len(centres))):
        sample = other - count
        offset = centres[sample] - points[query]
        distance2 = np.einsum("nd,nd->n", offset, offset) / np.square(reach[sample])
        facing = np.einsum("nd,nd->n", normals[query], sample_normals[sample])
        weight = np.square(np.maximum(1.0 - distance2, 0.0)) * np.clip((facing - limit) / (1.0 - limit), 0.0, 1.0)
        keep = weight > 0
        query, sample, weight = query[keep], sample[keep], weight[keep]
        total += np.bincount(query, weights=weight, minlength=count)
        for c in range(3):
            result[:, c] += np.bincount(query, weights=weight * values[sample, c], minlength=count)
        # the heaviest sample's patch per texel
        order = np.lexsort((-weight, query))
        first = np.ones(len(order), dtype=bool)
        first[1:] = query[order][1:] != query[order][:-1]
        top_query, top_weight = query[order][first], weight[order][first]
        heavier = top_weight > best[top_query]
        best[top_query[heavier]] = top_weight[heavier]
        best_patch[top_query[heavier]] = patch[sample[order][first][heavier]]
    reached = total > 0
    result[reached] /= total[reached, None]
    lone = np.flatnonzero(~reached)
    if len(lone):
        nearest = _nearest(points[lone], centres)
        result[lone] = values[nearest]
        best_patch[lone] = patch[nearest]
    return result, best_patch


def _nearest(points: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(n,) the index of the centre nearest each point."""
    chunk = max(1, NEAREST_CHUNK // max(len(centres), 1))
    found = np.empty(len(points), dtype=np.int64)
    for first in range(0, len(points), chunk):
        part = points[first:first + chunk]
        distance = (np.square(part[:, None] - centres[None])).sum(axis=2)
        found[first:first + len(part)] = np.argmin(distance, axis=1)
    return found


NORMAL_BINS = 4  # corners share a value where their faces' normals round alike at this many steps per unit


def corner_values(corners: np.ndarray, normals: np.ndarray, samples, scene_size: float):
    """(n, 4, 3) `scattered_values` at the corners (n, 4, 3) of faces with `normals` (n, 3), and
    (n, 4) the heaviest sample's patch at each: a point of a mesh is asked once for the faces whose
    normals agree there (a smooth surface's ~6 triangles at a vertex), apart across a crease."""
    count = len(corners)
    points = corners.reshape(-1, 3)
    facing = np.repeat(normals, 4, axis=0)
    keys = np.concatenate([np.rint(points / (1e-6 * scene_size)), np.rint(facing * NORMAL_BINS)], axis=1)
    inverse = row_labels(keys.astype(np.int64))
    first = np.zeros(int(inverse.max()) + 1, dtype=np.int64)
    first[inverse[::-1]] = np.arange(len(inverse))[::-1]
    values, nearest = scattered_values(points[first], facing[first], samples)
    return values[inverse].reshape(count, 4, 3), nearest[inverse].reshape(count, 4)
