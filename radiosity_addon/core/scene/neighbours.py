"""Pairs of nearby things without comparing all pairs: a uniform grid over centres, each query
looking in the 27 cells around its own. Cost: O(N + pairs found), not O(N^2)."""

from __future__ import annotations

import numpy as np

PAIR_CHUNK = 1 << 20  # candidate pairs expanded at once


def _cell_keys(cells: np.ndarray) -> np.ndarray:
    """int64 key per integer cell (N, 3); cells are shifted to be non-negative first."""
    span = cells.max(axis=0) + 3
    return (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]


def near_pairs(centre: np.ndarray, radius: np.ndarray, queries: np.ndarray, reach: np.ndarray):
    """Yield chunks (query positions into `queries`, other indices) of every pair whose centres are
    closer than reach[query] + radius[other]; the query itself is included."""
    centre = np.asarray(centre, dtype=np.float64)
    if len(queries) == 0:
        return
    cell = float(max(reach.max() + radius.max(), 1e-9))
    low = centre.min(axis=0)
    cells = np.floor((centre - low) / cell).astype(np.int64) + 1  # +1: neighbours of cell 0 stay >= 0
    keys = _cell_keys(cells)
    span = cells.max(axis=0) + 3
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    query_cells = cells[queries]
    offsets = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), axis=-1).reshape(-1, 3)
    for offset in offsets:
        c = query_cells + offset
        k = (c[:, 0] * span[1] + c[:, 1]) * span[2] + c[:, 2]
        lo = np.searchsorted(sorted_keys, k, side="left")
        hi = np.searchsorted(sorted_keys, k, side="right")
        counts = hi - lo
        start = 0
        while start < len(queries):
            # as many queries as fit PAIR_CHUNK pairs (at least one)
            cumulative = np.cumsum(counts[start:])
            stop = start + max(1, int(np.searchsorted(cumulative, PAIR_CHUNK, side="right")))
            n = counts[start:stop]
            if n.sum():
                query = np.repeat(np.arange(start, stop), n)
                first = np.repeat(lo[start:stop] - np.concatenate([[0], np.cumsum(n)[:-1]]), n)
                other = order[first + np.arange(n.sum())]
                gap = np.linalg.norm(centre[other] - centre[queries[query]], axis=1)
                close = gap < reach[query] + radius[other]
                yield query[close], other[close]
            start = stop
