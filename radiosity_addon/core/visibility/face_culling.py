"""Which triangles each hemi-cube face can show, decided per cluster of triangles before the draw.

On llvmpipe a batch of hemi-cubes costs in proportion to the triangles it draws, whatever the size of
its faces: every face of every hemi-cube runs the vertex shader and clips every triangle of the
scene, though a face sees a fifth of the hemisphere at most and nothing below the horizon. So the
item geometry's triangles are grouped into small, compact clusters (sorted by size, then along a
Morton curve) with a bounding box each, and a face draws only the clusters whose box reaches
into its frustum: one indirect draw command per (face, cluster) kept, all in one multi-draw call.
The test is conservative (a box only partly inside is drawn, and clipping does the rest), so the
item buffers are the same as drawing everything, up to the order of triangles at equal depth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CLUSTER_TRIANGLES = 64  # triangles per cluster at most: fewer make more commands, more cull less
MORTON_BITS = 10  # per axis
TESTS_PER_STEP = 1 << 20  # (face, cluster) pairs tested in one vectorized step (bounds the memory)
COMMAND_WORDS = 5  # DrawElementsIndirectCommand: count, instanceCount, firstIndex, baseVertex, baseInstance


@dataclass
class TriangleClusters:
    indices: np.ndarray  # (3 T,) uint32: the triangles, reordered so each cluster is one range
    first: np.ndarray  # (C,) first index of each cluster
    count: np.ndarray  # (C,) indices in each cluster
    centre: np.ndarray  # (C, 3) bounding boxes: centres
    half: np.ndarray  # (C, 3) and half extents

    def __len__(self) -> int:
        return len(self.first)


def _morton(cells: np.ndarray) -> np.ndarray:
    """Interleaved bits of (n, 3) non-negative integers below 2^MORTON_BITS."""
    code = np.zeros(len(cells), dtype=np.int64)
    for bit in range(MORTON_BITS):
        for axis in range(3):
            code |= ((cells[:, axis] >> bit) & 1).astype(np.int64) << (3 * bit + axis)
    return code


def triangle_clusters(positions: np.ndarray, indices: np.ndarray,
                      size: int = CLUSTER_TRIANGLES) -> TriangleClusters:
    """Clusters of at most `size` triangles of the indexed triangles, each of one size class (so a
    wall drawn as two triangles does not swell a cluster of a chair's small ones)."""
    triangles = indices.reshape(-1, 3)
    if len(triangles) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return TriangleClusters(indices, empty, empty, np.zeros((0, 3)), np.zeros((0, 3)))
    corners = positions[triangles].astype(np.float64)  # (T, 3, 3)
    low, high = corners.min(axis=1), corners.max(axis=1)
    centre = 0.5 * (low + high)
    extent = np.linalg.norm(high - low, axis=1)
    scene_low, scene_high = centre.min(axis=0), centre.max(axis=0)
    diameter = max(float(np.linalg.norm(scene_high - scene_low)), 1e-30)
    size_class = np.clip(np.floor(np.log2(np.maximum(extent, 1e-30) / diameter)), -20, 1).astype(np.int64)
    cells = ((centre - scene_low) / np.maximum(scene_high - scene_low, 1e-30) * ((1 << MORTON_BITS) - 1))
    order = np.lexsort((_morton(cells.astype(np.int64)), -size_class))
    size_class = size_class[order]
    # a cluster: `size` consecutive triangles of one size class
    class_start = np.flatnonzero(np.r_[True, size_class[1:] != size_class[:-1]])
    rank = np.arange(len(order)) - np.repeat(class_start, np.diff(np.r_[class_start, len(order)]))
    starts = np.flatnonzero(np.r_[True, (size_class[1:] != size_class[:-1]) | (rank[1:] % size == 0)])
    low = np.minimum.reduceat(low[order], starts, axis=0)
    high = np.maximum.reduceat(high[order], starts, axis=0)
    counts = np.diff(np.r_[starts, len(order)])
    return TriangleClusters(indices=triangles[order].reshape(-1).astype(np.uint32), first=starts * 3,
                            count=counts * 3, centre=0.5 * (low + high), half=0.5 * (high - low))


def face_planes(instances: np.ndarray) -> np.ndarray:
    """(I, 5, 3) inward normals of the planes through the eye that bound each face instance's frustum
    (hemicube.face_instances' rows: eye, right, up, forward, tile, up_min): c >= 0, |a| <= c,
    b <= c, b >= up_min c, with a, b, c the offsets along right, up and forward."""
    right, up, forward = instances[:, 3:6], instances[:, 6:9], instances[:, 9:12]
    up_min = instances[:, 16:17]
    return np.stack([forward, forward - right, forward + right, forward - up, up - up_min * forward], axis=1)


def draw_commands(clusters: TriangleClusters, instances: np.ndarray) -> np.ndarray:
    """(M, 5) uint32 indirect draw commands: for every face instance (its row number is its
    baseInstance) each cluster whose bounding box is not wholly outside its frustum."""
    instances = instances.astype(np.float64)
    planes = face_planes(instances).reshape(-1, 3)  # (5 I, 3)
    # a box is outside a plane through the eye when its centre is farther behind it than the box reaches
    # (n·centre - n·eye < -|n|·half): two (5 I, 3) x (3, C) products, no (I, C, 5, 3) temporary
    eye_side = np.einsum("fk,fk->f", planes, np.repeat(instances[:, 0:3], 5, axis=0))[:, None]
    visible = np.empty((len(instances), len(clusters)), dtype=bool)
    step = max(1, TESTS_PER_STEP // max(1, 5 * len(clusters)))  # instances tested at once
    for first in range(0, len(instances), step):
        rows = slice(5 * first, 5 * (first + step))
        outside = planes[rows] @ clusters.centre.T - eye_side[rows] < -(np.abs(planes[rows]) @ clusters.half.T)
        visible[first:first + step] = ~outside.reshape(-1, 5, len(clusters)).any(axis=1)
    instance, cluster = np.nonzero(visible)
    commands = np.empty((len(instance), COMMAND_WORDS), dtype=np.uint32)
    commands[:, 0] = clusters.count[cluster]
    commands[:, 1] = 1
    commands[:, 2] = clusters.first[cluster]
    commands[:, 3] = 0
    commands[:, 4] = instance
    return commands
