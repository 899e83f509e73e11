"""The grid pair search finds exactly the pairs a brute-force comparison finds."""

import numpy as np

from radiosity_addon.core.scene import neighbours
from radiosity_addon.core.scene.neighbours import near_pairs


def brute_force(centre, radius, queries, reach):
    d = np.linalg.norm(centre[None] - centre[queries, None], axis=2)
    q, o = np.nonzero(d < reach[:, None] + radius[None])
    return set(zip(q.tolist(), o.tolist()))


def test_grid_pairs_match_brute_force(monkeypatch):
    rng = np.random.default_rng(3)
    centre = rng.uniform(-5, 5, (800, 3)) * np.array([1, 1, 0.1])  # flattened: many share cells
    radius = rng.uniform(0.01, 0.4, 800)
    queries = rng.choice(800, 300, replace=False)
    reach = 2 * radius[queries]
    monkeypatch.setattr(neighbours, "PAIR_CHUNK", 97)  # many chunks
    found = set()
    for q, o in near_pairs(centre, radius, queries, reach):
        found |= set(zip(q.tolist(), o.tolist()))
    expected = brute_force(centre, radius, queries, reach)
    assert found == expected
    assert len(expected) > 300  # more than the queries themselves
