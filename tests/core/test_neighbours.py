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


def test_grid_pairs_match_brute_force_across_size_classes():
    """A floor-sized patch among millimetre ones (each class pair gets its own grid): same pairs."""
    rng = np.random.default_rng(5)
    centre = rng.uniform(-2, 2, (1500, 3)) * np.array([1, 1, 0.05])
    radius = np.exp(rng.uniform(np.log(1e-3), np.log(0.3), 1500))
    radius[:3] = [3.0, 0.9, 1e-4]  # a wall, a table top, a speck
    queries = np.concatenate([[0, 1, 2], rng.choice(np.arange(3, 1500), 400, replace=False)])
    reach = 2 * radius[queries]
    found = set()
    for q, o in near_pairs(centre, radius, queries, reach):
        found |= set(zip(q.tolist(), o.tolist()))
    expected = brute_force(centre, radius, queries, reach)
    assert found == expected and len(expected) > 1500 + 400  # the wall meets all


def test_one_large_patch_does_not_make_every_small_one_a_candidate(monkeypatch):
    """20k small patches on a 10 m floor and one 5 m patch: the distances computed stay near the
    pairs found, not 20k^2 / the few cells one 5 m grid would have."""
    rng = np.random.default_rng(7)
    centre = np.concatenate([rng.uniform(0, 10, (20000, 3)) * np.array([1, 1, 0]), [[5.0, 5.0, 0.5]]])
    radius = np.concatenate([np.full(20000, 0.02), [5.0]])
    queries = np.arange(len(centre))
    computed = []
    norm = np.linalg.norm
    monkeypatch.setattr(neighbours.np.linalg, "norm", lambda a, axis=None: computed.append(len(a)) or norm(a, axis=axis))
    pairs = sum(len(q) for q, _ in near_pairs(centre, radius, queries, 2 * radius))
    assert sum(computed) < 20 * pairs, (sum(computed), pairs)


def test_the_grids_small_chunks_come_joined(monkeypatch):
    """One chunk per search while the pairs fit PAIR_CHUNK (not one per class pair and grid step:
    a caller's numpy then runs once), and chunks of at least PAIR_CHUNK pairs but the last."""
    rng = np.random.default_rng(5)
    centre = rng.uniform(-2, 2, (1500, 3)) * np.array([1, 1, 0.05])
    radius = np.exp(rng.uniform(np.log(1e-3), np.log(0.3), 1500))
    queries = np.arange(1500)
    assert len(list(near_pairs(centre, radius, queries, 2 * radius))) == 1
    monkeypatch.setattr(neighbours, "PAIR_CHUNK", 500)
    sizes = [len(q) for q, _ in near_pairs(centre, radius, queries, 2 * radius)]
    assert len(sizes) > 3 and min(sizes[:-1]) >= 500
