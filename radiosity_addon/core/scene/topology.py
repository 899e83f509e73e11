"""Which surfaces form closed meshes: surfaces sharing edges (corners equal up to a quantum of
the scene size) are connected; a component is closed when every edge is used by exactly two of
its faces in opposite directions (consistently oriented), and outward when its signed volume is
positive (fronts face away from the enclosed volume). Vectorized: edge keys by `rows.row_labels`,
components by label propagation with pointer jumping (O(N log N))."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import Scene
from .rows import row_labels

QUANTUM = 1e-7  # corners closer than this fraction of the scene size are the same point


@dataclass
class Components:
    label: np.ndarray  # (S,) component of each surface, 0..count-1
    closed: np.ndarray  # (count,) bool: every edge used twice, in opposite directions
    volume: np.ndarray  # (count,) signed volume enclosed (meaningful when closed)
    low: np.ndarray  # (count, 3) bounding box
    high: np.ndarray  # (count, 3)

    @property
    def count(self) -> int:
        return len(self.closed)


def _directed_edges(scene: Scene):
    """(E, 2) corner ids of every polygon edge (a triangle's repeated corner adds no edge) and the
    surface of each."""
    size = max(scene.diameter, 1e-30)
    points = np.round(scene.corners.reshape(-1, 3) / (QUANTUM * size)).astype(np.int64)
    ids = row_labels(points).reshape(-1, 4)
    start, end = ids, np.roll(ids, -1, axis=1)
    keep = start != end
    surface = np.repeat(np.arange(len(scene)), 4).reshape(-1, 4)
    return np.stack([start[keep], end[keep]], axis=1), surface[keep]


def connected_labels(count: int, pairs: np.ndarray) -> np.ndarray:
    """Connected components of `count` nodes joined by `pairs` (M, 2): smallest index per component.
    Each round every tree hooks its root under the smallest root it meets across an edge, then
    every node jumps to its root: trees merge whole, so the rounds follow the log of the
    components' sizes, not their diameters (a 100k-triangle floor is 300 edges across)."""
    label = np.arange(count)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    while len(pairs):
        a, b = label[pairs[:, 0]], label[pairs[:, 1]]
        apart = a != b
        if not apart.any():
            break
        pairs, a, b = pairs[apart], a[apart], b[apart]
        high, low = np.maximum(a, b), np.minimum(a, b)
        order = np.lexsort((low, high))
        high, low = high[order], low[order]
        first = np.concatenate([[True], high[1:] != high[:-1]])  # the smallest root each root meets
        label[high[first]] = np.minimum(label[high[first]], low[first])
        while True:  # pointer jumping: every node straight to its root
            jumped = label[label]
            if np.array_equal(jumped, label):
                break
            label = jumped
    return label


def components(scene: Scene) -> Components:
    edges, owner = _directed_edges(scene)
    undirected = np.sort(edges, axis=1)
    edge_id = row_labels(undirected)
    uses = np.bincount(edge_id)  # per distinct edge
    # surfaces sharing an edge are joined: pair each use with the edge's first user
    first_user = np.full(len(uses), -1)
    first_user[edge_id[::-1]] = owner[::-1]
    label = connected_labels(len(scene), np.stack([owner, first_user[edge_id]], axis=1))
    _, label = np.unique(label, return_inverse=True)
    count = int(label.max()) + 1
    # consistently oriented and closed: each undirected edge used twice, once each way
    forward = (edges[:, 0] < edges[:, 1]).astype(np.int64)
    balance = np.bincount(edge_id, weights=2 * forward - 1, minlength=len(uses))
    edge_ok = (uses == 2) & (balance == 0)
    component_of_edge = label[owner]
    closed = np.ones(count, dtype=bool)
    np.logical_and.at(closed, component_of_edge, edge_ok[edge_id])
    # signed volume: sum over the two triangles of every polygon of v0 . (v1 x v2) / 6
    c = scene.corners
    per_surface = (np.einsum("sd,sd->s", c[:, 0], np.cross(c[:, 1], c[:, 2]))
                   + np.einsum("sd,sd->s", c[:, 0], np.cross(c[:, 2], c[:, 3]))) / 6.0
    volume = np.bincount(label, weights=per_surface, minlength=count)
    low = np.full((count, 3), np.inf)
    high = np.full((count, 3), -np.inf)
    np.minimum.at(low, label, c.min(axis=1))
    np.maximum.at(high, label, c.max(axis=1))
    return Components(label=label, closed=closed, volume=volume, low=low, high=high)
