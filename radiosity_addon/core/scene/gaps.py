"""Surfaces that face each other across a gap narrower than themselves — an emitter a few
millimetres under a ceiling — and where their outlines lie: light trapped in such a gap is many
times the room's and falls off within a few gaps of the opening, so refinement (`refinement.py`)
splits there (cutting along the outline) and progressive refinement's patches there shoot alone,
never in a cluster (`progressive/clusters.cluster_owners`)."""

from __future__ import annotations

import numpy as np

from .neighbours import near_pairs
from .patches import Patches

OPPOSED_COSINE = 0.7  # a gap is between surfaces turned towards each other (not two walls at a corner)


def facing_partners(patches: Patches, candidates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each candidate, the distance from its centre to the plane of the nearest patch of another
    surface that faces it (both fronts towards each other) with its bounding sphere within twice the
    candidate's size, and that patch: ((len(candidates),) float, inf where none does; (len,) int, -1).
    A 5 mm gap between an emitter and a ceiling is such a distance: the light trapped between them
    escapes through it."""
    centre, normal = patches.center, patches.normal
    radius = np.linalg.norm(patches.corners - centre[:, None], axis=2).max(axis=1)
    gaps = np.full(len(candidates), np.inf)
    partners = np.full(len(candidates), -1, dtype=np.int64)
    for query, other in near_pairs(centre, radius, candidates, 2 * radius[candidates]):
        rows = candidates[query]
        offset = centre[other] - centre[rows]  # candidate -> other
        facing = (np.einsum("nd,nd->n", offset, normal[rows]) > 0) & (np.einsum("nd,nd->n", offset, normal[other]) < 0)
        close = facing & (patches.surface[other] != patches.surface[rows])
        query, other = query[close], other[close]
        gap = np.abs(np.einsum("nd,nd->n", offset[close], normal[other]))
        order = np.lexsort((gap, query))  # per query, its smallest gap first
        first = order[np.r_[True, query[order][1:] != query[order][:-1]]] if len(order) else order
        better = gap[first] < gaps[query[first]]
        gaps[query[first][better]] = gap[first][better]
        partners[query[first][better]] = other[first][better]
    return gaps, partners


def covered_centres(patches: Patches, candidates: np.ndarray, surface_size: np.ndarray) -> np.ndarray:
    """(len(candidates),) bool: the candidates whose centre lies under a smaller surface close in
    front of it, closer than half the candidate's size, either side turned towards it (an emitter's
    unlit back 5 mm under a ceiling patch many times its size). A patch gathers its light at its
    centre, which then sees that surface over most of its hemisphere: the whole patch would take
    the dark footprint's light. `surface_size` (S,): each surface's size (its bounding radius)."""
    centre, normal = patches.center, patches.normal
    radius = np.linalg.norm(patches.corners - centre[:, None], axis=2).max(axis=1)
    size = np.sqrt(patches.area)
    covered = np.zeros(len(candidates), dtype=bool)
    for query, other in near_pairs(centre, radius, candidates, 0.5 * size[candidates]):
        rows = candidates[query]
        offset = centre[other] - centre[rows]
        along = np.einsum("nd,nd->n", offset, normal[rows])  # how far in front of the candidate
        parallel = np.abs(np.einsum("nd,nd->n", normal[rows], normal[other])) > OPPOSED_COSINE
        lateral = np.linalg.norm(offset - along[:, None] * normal[rows], axis=1)
        hit = ((along > 0) & (along < 0.5 * size[rows]) & parallel & (patches.surface[other] != patches.surface[rows])
               & (lateral < 0.5 * size[other]) & (surface_size[patches.surface[other]] < 0.5 * size[rows]))
        covered[query[hit]] = True
    return covered


def facing_gaps(patches: Patches, candidates: np.ndarray) -> np.ndarray:
    """The gaps of `facing_partners`."""
    return facing_partners(patches, candidates)[0]


def distance_to_outline(points: np.ndarray, polygons: np.ndarray) -> np.ndarray:
    """(N,) distance from each point (N, 3), projected onto the plane of its polygon (N, 4, 3; a
    triangle repeats its last corner), to that polygon's outline."""
    edges = np.roll(polygons, -1, axis=1) - polygons  # (N, 4, 3)
    normal = np.cross(polygons[:, 2] - polygons[:, 0], polygons[:, 3] - polygons[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    flat = points - np.einsum("nd,nd->n", points - polygons[:, 0], normal)[:, None] * normal
    relative = flat[:, None] - polygons
    length2 = np.maximum(np.einsum("nkd,nkd->nk", edges, edges), 1e-300)
    along = np.clip(np.einsum("nkd,nkd->nk", relative, edges) / length2, 0.0, 1.0)
    nearest = polygons + along[..., None] * edges
    return np.linalg.norm(flat[:, None] - nearest, axis=2).min(axis=1)


def emitter_gaps(patches: Patches) -> np.ndarray:
    """(P,) the gap across which each patch faces another surface's patch turned towards it
    (normals within OPPOSED_COSINE of opposite: not a wall meeting it at a corner) when one of
    the two emits (`facing_partners`), inf where none does."""
    emits = np.any(patches.emission > 0, axis=1)
    # only an emitter or a patch within `facing_partners`' reach of one (centres closer than twice
    # its radius plus the emitter's) can have an emitter for a partner: search from those alone,
    # not from every patch of the scene, most of which are far from any emitter
    emitting = np.flatnonzero(emits)
    radius = np.linalg.norm(patches.corners - patches.center[:, None], axis=2).max(axis=1)
    near = [other for _, other in near_pairs(patches.center, 2 * radius, emitting, radius[emitting])]
    candidates = np.unique(np.concatenate([emitting, *near]))
    gaps = np.full(len(patches), np.inf)
    found, partners = facing_partners(patches, candidates)
    other = np.maximum(partners, 0)
    opposed = np.einsum("nd,nd->n", patches.normal[candidates], patches.normal[other]) < -OPPOSED_COSINE
    gaps[candidates] = np.where((partners >= 0) & opposed & (emits[candidates] | emits[other]), found, np.inf)
    return gaps
