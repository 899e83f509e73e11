"""Values to interpolate: every patch carries a lattice of its element centres plus border
points on its edges and corners; a border point's value is the mean of the values the patches
meeting there give it (same object and world point, and the same UV point or a bend under
30°), so bilinear interpolation over the lattice is continuous across patch borders, across
face borders within a chart, and across smooth edges between charts. Hemi-cube results (one
value per patch) are the case S = 1."""

from __future__ import annotations

import math

import numpy as np

from ..scene.geometry import bilinear
from ..scene.rows import row_labels
from ..errors import SolveError
from ..solution import Solution

SMOOTH_EDGE_DEGREES = 30.0  # faces meeting flatter than this share values at their edge (Blender's auto smooth)


def element_values(solution: Solution, light: bool = False, direct: bool = False, sky: bool = False) -> np.ndarray:
    """(P, S, S, 3) radiosity B (with `light` the light H, B = E + ρH; with `direct` the part of H
    straight from lamps and emitters; with `sky` the part straight from the sky): the elements, or
    the patch values as S = 1 (a grey one-channel result is repeated into three)."""
    if sky:
        elements, patches = solution.element_sky, solution.element_sky
    elif direct:
        elements, patches = solution.element_direct, solution.patch_direct
    elif light:
        elements, patches = solution.element_light, solution.patch_light
    else:
        elements, patches = solution.element_radiosity, solution.patch_radiosity
    if patches is None:
        raise SolveError("the solution holds no light values (made by hand?); bake its lightmaps as 'combined'")
    if elements is not None:
        values = np.asarray(elements, dtype=np.float64)
    else:
        values = np.asarray(patches, dtype=np.float64)[:, None, None, :]
    return np.broadcast_to(values, values.shape[:3] + (3,)) if values.shape[3] == 1 else values


def lattice_parameters(elements: int) -> np.ndarray:
    """(S + 2,) patch parameters of the lattice: 0, the element centres, 1."""
    return np.concatenate([[0.0], (np.arange(elements) + 0.5) / elements, [1.0]])


def _sum_within_groups(group: np.ndarray, joins, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For every item i, the sum of values[j] and the count over the items j of its group with
    joins(i, j) true (each item joins itself). Items are compared at every offset within their
    group: a loop over the largest group size (a handful), vectorized over all items."""
    order = np.argsort(group, kind="stable")
    sorted_group = group[order]
    total, count = values.copy(), np.ones(len(group))
    for offset in range(1, len(group)):
        same = sorted_group[offset:] == sorted_group[:-offset]
        if not same.any():
            break
        i, j = order[:-offset][same], order[offset:][same]
        joined = joins(i, j)
        i, j = i[joined], j[joined]
        np.add.at(total, i, values[j])
        np.add.at(total, j, values[i])
        np.add.at(count, i, 1)
        np.add.at(count, j, 1)
    return total, count


def continuous_lattice(corners: np.ndarray, patch_uv: np.ndarray, values: np.ndarray, group: np.ndarray,
                       normals: np.ndarray, world_quantum: float, uv_quantum: float) -> np.ndarray:
    """(P, S+2, S+2, 3) lattice values [patch, t row, s column].

    Inside: the element values. Border points: each patch proposes its nearest
    element's value there (one proposal per patch and place: its own lattice
    points at one place, e.g. along a triangle's collapsed edge, are averaged
    first); then a patch's border value is the mean of the proposals of the
    patches of its `group` (object) at the same world point that either share
    the UV point there (same chart: the image must be continuous) or bend
    from it by less than SMOOTH_EDGE_DEGREES (a smooth surface split into
    faces, e.g. Blender's Lightmap Pack making each face its own chart: no
    seams between them). Creases keep their own values: light differs there."""
    count, elements = values.shape[:2]
    clamp = np.clip(np.arange(elements + 2) - 1, 0, elements - 1)
    lattice = values[:, clamp][:, :, clamp].copy()
    params = lattice_parameters(elements)
    s, t = np.meshgrid(params, params)  # [t row, s column]
    border = np.ones_like(s, dtype=bool)
    border[1:-1, 1:-1] = False
    per_patch = int(border.sum())
    world = np.round(bilinear(corners, s[border], t[border]).reshape(-1, 3) / world_quantum)
    uv = np.round(bilinear(patch_uv, s[border], t[border]).reshape(-1, 2) / uv_quantum)
    owner = np.repeat(np.arange(count), per_patch)
    keys = np.concatenate([group[owner][:, None], world, uv], axis=1).astype(np.int64)
    place = row_labels(keys)  # same object, world and UV point
    _, pair_of_point = np.unique(owner * (place.max() + 1) + place, return_inverse=True)
    pair_of_point = pair_of_point.ravel()
    points_per_pair = np.bincount(pair_of_point)
    proposals = lattice[:, border].reshape(-1, 3)
    pair_value = np.stack([np.bincount(pair_of_point, proposals[:, c]) for c in range(3)], axis=1)
    pair_value /= points_per_pair[:, None]
    first = np.zeros(len(points_per_pair), dtype=np.int64)
    first[pair_of_point[::-1]] = np.arange(len(pair_of_point))[::-1]  # a point of each pair
    pair_patch, pair_place = owner[first], place[first]
    pair_world = row_labels(keys[first, :4])  # object and world point
    smooth = math.cos(math.radians(SMOOTH_EDGE_DEGREES))

    def joins(i, j):
        return (pair_place[i] == pair_place[j]) | (
            np.einsum("ij,ij->i", normals[pair_patch[i]], normals[pair_patch[j]]) > smooth)

    total, joined = _sum_within_groups(pair_world, joins, pair_value)
    lattice[:, border] = (total / joined[:, None])[pair_of_point].reshape(count, per_patch, 3)
    return lattice
