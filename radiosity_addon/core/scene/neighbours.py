"""Pairs of nearby things without comparing all pairs: uniform grids over centres, each query
looking in the 27 cells around its own. Things of very different sizes get grids of their own
(size classes a factor CLASS_RATIO apart): one big patch would otherwise set the cell size for
all, and a room's thousands of small patches would share a few cells, O(N^2) candidates. Per
pair of classes the cell is the largest reach plus the largest radius in them, so a query meets
others of its own size or larger within a cell or two of it. Cost: O(N + pairs found) times the
number of class pairs (a few dozen), not O(N^2)."""

from __future__ import annotations

import numpy as np

from ..timing import pulse

PAIR_CHUNK = 1 << 20  # candidate pairs expanded at once
OFFSET_QUERIES = 4096  # query cells searched in one step (the 27 around each query, by offset)
CLASS_RATIO = 2.5  # sizes in a class differ by at most this (smaller: more class pairs; larger: more candidates)
OFFSETS = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), axis=-1).reshape(-1, 3)


def _cell_keys(cells: np.ndarray, span: np.ndarray) -> np.ndarray:
    """int64 key per integer cell (N, 3) of non-negative cells below `span`."""
    return (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]


def _size_classes(sizes: np.ndarray) -> np.ndarray:
    return np.floor(np.log(np.maximum(sizes, 1e-12)) / np.log(CLASS_RATIO)).astype(np.int64)


def near_pairs(centre: np.ndarray, radius: np.ndarray, queries: np.ndarray, reach: np.ndarray,
               others: np.ndarray | None = None):
    """Yield chunks (query positions into `queries`, other indices) of every pair whose centres are
    closer than reach[query] + radius[other]; the query itself is included. `others` (indices into
    `centre`; None: all) are the things a query may meet. The grids' many small
    chunks (per pair of size classes and step of offsets) are joined into chunks of about
    PAIR_CHUNK pairs, so a caller's numpy runs once a chunk, not once a grid step."""
    centre = np.asarray(centre, dtype=np.float64)
    queries = np.asarray(queries)
    if len(queries) == 0 or len(centre) == 0:
        return
    candidates = np.arange(len(centre)) if others is None else np.asarray(others)
    if len(candidates) == 0:
        return
    query_class, other_class = _size_classes(reach), _size_classes(radius[candidates])
    held, count = [], 0
    for q_level in np.unique(query_class):
        in_queries = np.flatnonzero(query_class == q_level)
        for o_level in np.unique(other_class):
            in_class = candidates[other_class == o_level]
            for chunk in _grid_pairs(centre, radius, queries, reach, in_queries, in_class):
                pulse()  # a search over a dense scene's faces runs for seconds
                held.append(chunk)
                count += len(chunk[0])
                if count >= PAIR_CHUNK:
                    yield tuple(np.concatenate(parts) for parts in zip(*held))
                    held, count = [], 0
    if held:
        yield tuple(np.concatenate(parts) for parts in zip(*held))


def _grid_pairs(centre, radius, queries, reach, positions, others):
    """The pairs between queries[positions] and `others` through one grid."""
    cell = float(max(reach[positions].max() + radius[others].max(), 1e-9))
    low = centre[others].min(axis=0)
    cells = np.floor((centre[others] - low) / cell).astype(np.int64) + 1  # +1: neighbours of cell 0 stay >= 0
    span = cells.max(axis=0) + 3
    keys = _cell_keys(cells, span)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    query_cells = np.floor((centre[queries[positions]] - low) / cell).astype(np.int64) + 1
    # queries outside the others' box by more than a cell meet nothing; clip the rest into the grid
    inside = np.all((query_cells >= 0) & (query_cells <= span - 1), axis=1)
    positions, query_cells = positions[inside], query_cells[inside]
    # the 27 cells around the queries, offset by offset (the pairs come in that order), as many
    # offsets at a time as keep OFFSET_QUERIES queries in a step: a small class pair's cost was
    # the loop itself, a large one's runs faster in steps that stay in cache
    step = max(1, OFFSET_QUERIES // max(1, len(positions)))
    for first in range(0, len(OFFSETS), step):
        offsets = OFFSETS[first:first + step]
        c = (offsets[:, None, :] + query_cells[None]).reshape(-1, 3)
        valid = np.all((c >= 0) & (c < span), axis=1)
        k = np.where(valid, _cell_keys(c, span), -1)
        lo = np.searchsorted(sorted_keys, k, side="left")
        hi = np.searchsorted(sorted_keys, k, side="right")
        query_of = np.tile(positions, len(offsets))
        for which, at in range_chunks(lo, np.where(valid, hi - lo, 0)):
            query, other = query_of[which], others[order[at]]
            offset = centre[other] - centre[queries[query]]
            close = np.einsum("nd,nd->n", offset, offset) < np.square(reach[query] + radius[other])
            yield query[close], other[close]


def range_chunks(start: np.ndarray, count: np.ndarray, chunk: int = PAIR_CHUNK):
    """Yield chunks (range index, position) of every position start[r] .. start[r] + count[r] - 1,
    whole ranges in order, as many as fit `chunk` positions (at least one range a chunk)."""
    done = 0
    while done < len(start):
        stop = done + max(1, int(np.searchsorted(np.cumsum(count[done:]), chunk, side="right")))
        if count[done:stop].sum():
            which, at = expanded_ranges(start[done:stop], count[done:stop])
            yield which + done, at
        done = stop


def expanded_ranges(start: np.ndarray, count: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(range index, position) of every position start[r] .. start[r] + count[r] - 1, in order."""
    which = np.repeat(np.arange(len(count)), count)
    return which, np.repeat(start - (np.cumsum(count) - count), count) + np.arange(len(which))
