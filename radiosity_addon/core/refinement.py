"""Adaptive substructuring (Cohen et al. 1986): where the light changes fast across a patch — a
shadow edge, a contact, an emitter a few millimetres from a ceiling — the patch is a poor shooter
(it sends its mean radiosity from everywhere on it) and a poor receiver, so it is split 2 x 2;
smooth regions stay coarse.

The estimate is measured, not guessed: the direct light (lamps and emitters, the few shots that
light a scene first) is shot into S x S elements per patch, and a patch whose elements' light
spreads more than `refine_threshold` of its mean (plus a floor of REFINE_FLOOR of the scene's
mean, so dim corners are not split for noise) is split — if another surface faces it from closer
than its own size, where its light, sent as if uniform, lands wrong (a patch far from everything
is a good enough shooter whatever its spread; the lightmaps recompute the direct light per
texel). That is repeated `refinements` times, then the method solves once on the refined patches.
The direct shots cost little next to the solve.
"""

from __future__ import annotations

import numpy as np

from .progressive import solve_progressive
from .scene import Patches, split_patches
from .scene.neighbours import near_pairs
from .timing import StageTimer
from .uvspace import patch_material_values

REFINE_FLOOR = 0.05
PROBE_ELEMENTS = 4  # elements per patch side the direct light is measured on
GAP_RESOLUTION = 2.0  # patches facing another surface closely are split down to this many gaps
SMALLEST_PATCH = 1 / 1024  # of the scene's diameter: no split below it


def facing_gaps(patches: Patches, candidates: np.ndarray) -> np.ndarray:
    """(len(candidates),) float: for each candidate, the distance from its centre to the plane of
    the nearest patch of another surface that faces it (both fronts towards each other) with its
    bounding sphere within twice the candidate's size; inf where none does. A 5 mm gap between an
    emitter and a ceiling is such a distance: the light trapped between them escapes through it."""
    centre, normal = patches.center, patches.normal
    radius = np.linalg.norm(patches.corners - centre[:, None], axis=2).max(axis=1)
    gaps = np.full(len(candidates), np.inf)
    for query, other in near_pairs(centre, radius, candidates, 2 * radius[candidates]):
        rows = candidates[query]
        offset = centre[other] - centre[rows]  # candidate -> other
        facing = (np.einsum("nd,nd->n", offset, normal[rows]) > 0) & (np.einsum("nd,nd->n", offset, normal[other]) < 0)
        close = facing & (patches.surface[other] != patches.surface[rows])
        gap = np.abs(np.einsum("nd,nd->n", offset, normal[other]))[close]
        np.minimum.at(gaps, query[close], gap)
    return gaps


def patches_to_refine(patches: Patches, element_light: np.ndarray, threshold: float, min_size: float) -> np.ndarray:
    """(P,) bool: patches whose elements' light spreads more than `threshold` of their mean (plus
    the floor), that another surface faces from closer than their size (they are split until they
    are GAP_RESOLUTION times the gap: a patch sends its light as if uniform, and across a gap that
    light lands within a gap's width), and that are still larger than `min_size`."""
    light = np.asarray(element_light, dtype=np.float64).sum(axis=-1)  # (P, S, S)
    mean = light.mean(axis=(1, 2))
    area = patches.area
    floor = REFINE_FLOOR * float((area * mean).sum() / area.sum())
    spread = light.max(axis=(1, 2)) - light.min(axis=(1, 2))
    size = np.sqrt(area)
    split = (spread > threshold * (mean + floor)) & (size > min_size)
    candidates = np.flatnonzero(split)
    split[candidates] = size[candidates] > GAP_RESOLUTION * facing_gaps(patches, candidates)
    return split


def within_budget(patches: Patches, split: np.ndarray, budget: int | None) -> np.ndarray:
    """`split` cut down, largest patches first, so that the patches number at most `budget` once
    split (a split adds three patches, six when the patch's back is simulated too)."""
    if budget is None:
        return split
    chosen = np.flatnonzero(split)
    paired = (patches.twin[chosen] >= 0) | (patches.back_of[chosen] >= 0)  # a back is split with its front
    added = np.where(paired, 6, 3)
    if len(patches) + added.sum() <= budget:
        return split
    order = np.argsort(-patches.area[chosen], kind="stable")
    fits = np.cumsum(added[order]) <= budget - len(patches)
    kept = chosen[order[fits]]
    limited = np.zeros_like(split)
    limited[kept] = True
    return limited


def refine(gpu, scene, patches: Patches, backs, settings, effects, timer,
           budget: int | None = None) -> tuple[Patches, list[int]]:
    """`patches` split where the direct light changes fast, and how many were split per round;
    never more than `budget` patches in all (the hemi-cube method's matrices must fit)."""
    from dataclasses import replace

    probe = replace(settings, elements=max(settings.elements, PROBE_ELEMENTS))
    refined = []
    for level in range(settings.refinements):
        with timer.stage("refine"):
            _, _, light, _, _ = solve_progressive(gpu, scene, patches, probe, effects, StageTimer(), direct_only=True)
            min_size = SMALLEST_PATCH * scene.diameter
            split = within_budget(patches, patches_to_refine(patches, light, settings.refine_threshold, min_size),
                                  budget)
            if not split.any():
                break
            refined.append(int(split.sum()))
            patches = split_patches(patches, split, backs)
            if scene.material_maps:
                patches.reflectance, patches.emission = patch_material_values(gpu, scene, patches)
    return patches, refined
