"""Surfaces split into patches (vectorized numpy), every patch stored as a quad of four corners
(a triangle's sub-triangles repeat their last corner), the bilinear map of `geometry`.

A two-sided surface whose back the scene analysis simulates gets back patches too: the same
pieces with their corners in reverse order (so their normal points the other way), after all
the fronts. `back_of` and `twin` pair them.

Two ways to split (`SolveSettings`):
- uniform: every surface N x N (quads on a bilinear grid, triangles into N² triangles);
- by size: each surface into pieces about `patch_size` across — a quad into ceil(side /
  size) along each of its two directions, a triangle into n² with n = ceil(longest edge /
  size), at most MAX_SPLIT along a side — so big faces get many patches and small ones stay
  whole (the Blender panel's default).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..settings import MAX_SPLIT
from .geometry import area_centroid, area_vector, bilinear, bilinear_each, reversed_corners
from .model import Scene
from .opacity import OpacityMaps, coverage


def _read_only(array: np.ndarray) -> np.ndarray:
    array.flags.writeable = False
    return array


@dataclass
class Patches:
    corners: np.ndarray  # (P, 4, 3) float64
    uv: np.ndarray  # (P, 4, 2) lightmap UVs of the corners (zeros where the scene has none)
    surface: np.ndarray  # (P,) int index into the scene's surfaces
    reflectance: np.ndarray  # (P, 3)
    emission: np.ndarray  # (P, 3)
    is_triangle: np.ndarray  # (P,) bool: c3 repeats c2
    grid: np.ndarray  # (P, 2) int (row along t, column along s) of the patch in its surface's split
    split: np.ndarray  # (S, 2) int per surface: (columns along s, rows along t); triangles (n, n)
    back_of: np.ndarray | None = None  # (P,) int: the front patch a back patch mirrors, -1 for fronts
    twin: np.ndarray | None = None  # (P,) int: a front patch's back patch, -1 when its back is not simulated
    # where each patch lies in its surface: (P, 2, 2) [(s0, t0), (s1, t1)] of a quad surface's bilinear
    # map, or for a triangle's pieces of the map of their grid triangle (c0, c1, c2, c2) — refinement's
    # children are rectangles of it too (NaN: not known); and the surfaces' corners (S, 4, 3), None when
    # not known.
    # Item buffers draw a surface once and find the patch under each pixel from them (visibility.item_geometry).
    params: np.ndarray | None = None
    surface_corners: np.ndarray | None = None
    # the opacity textures of patches on alpha-cut surfaces (scene.opacity): per patch its texture and its
    # corners' texture UVs, subdivided like `uv`; None when the scene has none
    opacity: OpacityMaps | None = None

    def __post_init__(self):
        if self.back_of is None:
            self.back_of = np.full(len(self.corners), -1, dtype=np.int64)
        if self.twin is None:
            self.twin = np.full(len(self.corners), -1, dtype=np.int64)
        if self.params is None:
            self.params = np.full((len(self.corners), 2, 2), np.nan)

    def __len__(self) -> int:
        return len(self.corners)

    @property
    def is_back(self) -> np.ndarray:
        return self.back_of >= 0

    @property
    def front_count(self) -> int:
        """Fronts come first: patches [0, front_count) are fronts, the rest their backs."""
        return int(np.count_nonzero(self.back_of < 0))

    @property
    def drawn(self) -> np.ndarray:
        """(P,) the front patch whose geometry shows each patch in item buffers (itself for fronts)."""
        return np.where(self.back_of >= 0, self.back_of, np.arange(len(self.corners)))

    @property
    def plane(self) -> np.ndarray:
        """(P,) plane id: the surface for fronts, surfaces + surface for backs (the other side)."""
        return np.where(self.back_of >= 0, self.surface + len(self.split), self.surface)

    # the corners' measures, computed once (a solve asks for them many times; a split makes new
    # Patches, and nothing writes into a Patches' corners). Read-only, so a caller cannot spoil them.
    @cached_property
    def area_vector(self) -> np.ndarray:
        return _read_only(area_vector(self.corners))

    @cached_property
    def area(self) -> np.ndarray:
        return _read_only(np.linalg.norm(self.area_vector, axis=1))

    @cached_property
    def normal(self) -> np.ndarray:
        a = self.area_vector
        return _read_only(a / np.linalg.norm(a, axis=1, keepdims=True))

    @cached_property
    def center(self) -> np.ndarray:
        return _read_only(area_centroid(self.corners))

    @cached_property
    def coverage(self) -> np.ndarray:
        """(P,) the share of each patch that blocks light (1 but on alpha-cut surfaces: `opacity.coverage`)."""
        if self.opacity is None:
            return _read_only(np.ones(len(self.corners)))
        return _read_only(coverage(self.opacity))

    def points(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Bilinear points of every patch at parameters s, t (broadcast): (P, *s.shape, 3)."""
        return bilinear(self.corners, s, t)


def quad_grid(columns: int, rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Corner parameters (k, 4, 2) of a columns x rows split of the unit square, and (row, col)."""
    row, col = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    row, col = row.ravel(), col.ravel()
    offsets = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)  # (s, t)
    params = (np.stack([col, row], axis=1)[:, None, :] + offsets[None]) / np.array([columns, rows])
    return params, row, col


def triangle_grid(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Barycentric (b1, b2) corners (n*n, 4, 2) of the n^2 sub-triangles of a triangle.

    Row r (from the v0-v1 edge towards v2) holds 2(n-r)-1 triangles: upright
    ones (i, r), (i+1, r), (i, r+1) and inverted ones (i+1, r), (i+1, r+1),
    (i, r+1), all counter-clockwise like the parent.
    """
    corners, rows, cols = [], [], []
    for r in range(n):
        for i in range(n - r):
            corners.append([(i, r), (i + 1, r), (i, r + 1), (i, r + 1)])
            rows.append(r)
            cols.append(2 * i)
            if i < n - r - 1:
                corners.append([(i + 1, r), (i + 1, r + 1), (i, r + 1), (i, r + 1)])
                rows.append(r)
                cols.append(2 * i + 1)
    return np.asarray(corners, dtype=np.float64) / n, np.asarray(rows), np.asarray(cols)


def split_counts(scene: Scene, subdiv: int | None, patch_size: float) -> np.ndarray:
    """(S, 2) columns along s and rows along t for every surface."""
    if subdiv is not None:
        if subdiv < 1:
            raise ValueError("subdivision must be at least 1")
        return np.full((len(scene), 2), subdiv, dtype=np.int64)
    c = scene.corners
    edges = np.linalg.norm(np.roll(c, -1, axis=1) - c, axis=2)  # (S, 4): c0c1, c1c2, c2c3, c3c0
    pieces = lambda length: np.clip(np.ceil(length / patch_size), 1, MAX_SPLIT).astype(np.int64)  # noqa: E731
    along_s = pieces(np.maximum(edges[:, 0], edges[:, 2]))
    along_t = pieces(np.maximum(edges[:, 1], edges[:, 3]))
    triangle = pieces(edges.max(axis=1))
    return np.where(scene.is_triangle[:, None], triangle[:, None], np.stack([along_s, along_t], axis=1))


def _opacity_rows(patches: Patches, rows: np.ndarray) -> OpacityMaps | None:
    return None if patches.opacity is None else patches.opacity.rows(rows)


def fronts_of(patches: Patches) -> Patches:
    """The front patches alone (backs come after them)."""
    count = patches.front_count
    return Patches(corners=patches.corners[:count], uv=patches.uv[:count], surface=patches.surface[:count],
                   reflectance=patches.reflectance[:count], emission=patches.emission[:count],
                   is_triangle=patches.is_triangle[:count], grid=patches.grid[:count], split=patches.split,
                   params=patches.params[:count], surface_corners=patches.surface_corners,
                   opacity=_opacity_rows(patches, np.arange(count)))


def split_patches(patches: Patches, mask: np.ndarray, backs: np.ndarray, at: np.ndarray | None = None) -> Patches:
    """Every patch in `mask` (P,) (or whose twin is) replaced by its 2 x 2 bilinear children — a
    triangle's top children are triangles again — and the backs of the surfaces in `backs` (S,)
    made anew. A quad is cut at its parameters `at` (P, 2) (s, t), its middle (0.5, 0.5) when
    not given: a cut along an outline that crosses it (`refinement.outline_cuts`) leaves no child
    astride that outline. Children keep their parent's place, so patches of a surface stay together."""
    count = patches.front_count
    chosen = mask[:count].copy()
    twins = patches.twin[:count]
    chosen[twins >= 0] |= mask[twins[twins >= 0]]
    fronts = fronts_of(patches)
    params, rows, _ = quad_grid(2, 2)
    cut = np.full((count, 2), 0.5)
    if at is not None:  # (a front split only for its back's sake is cut in the middle)
        own = mask[:count] & ~fronts.is_triangle
        cut[own] = at[:count][own]
    # the grid's middle parameter (0.5) moved to each patch's cut
    params = np.where(params[None] == 0.5, cut[chosen][:, None, None, :], params[None])  # (n, 4, 4, 2)
    children = bilinear_each(fronts.corners[chosen], params[..., 0], params[..., 1])  # (n, 4, 4, 3)
    child_uv = bilinear_each(fronts.uv[chosen], params[..., 0], params[..., 1])
    opacity = None
    if fronts.opacity is not None:
        opacity_uv = fronts.opacity.uv[np.repeat(np.arange(count), np.where(chosen, 4, 1))].copy()
    repeat = np.where(chosen, 4, 1)
    take = np.repeat(np.arange(count), repeat)
    corners = fronts.corners[take].copy()
    uv = fronts.uv[take].copy()
    first = np.concatenate([[0], np.cumsum(repeat)[:-1]])[chosen]  # where each split patch's children start
    places = (first[:, None] + np.arange(4)[None]).ravel()
    corners[places] = children.reshape(-1, 4, 3)
    uv[places] = child_uv.reshape(-1, 4, 2)
    if fronts.opacity is not None:
        opacity_uv[places] = bilinear_each(fronts.opacity.uv[chosen], params[..., 0], params[..., 1]).reshape(-1, 4, 2)
        opacity = OpacityMaps(fronts.opacity.images, fronts.opacity.index[take], opacity_uv)
    is_triangle = fronts.is_triangle[take].copy()
    is_triangle[places] = (fronts.is_triangle[chosen][:, None] & (rows[None] == 1)).ravel()
    # each child's rectangle in the surface: its parent's, cut at the same parameters (corners 0 and 2)
    low, high = fronts.params[chosen, 0][:, None, None, :], fronts.params[chosen, 1][:, None, None, :]
    child_params = low + (high - low) * params[:, :, [0, 2]]  # (n, 4 children, 2 corners, 2)
    patch_params = fronts.params[take].copy()
    patch_params[places] = child_params.reshape(-1, 2, 2)
    refined = Patches(corners=corners, uv=uv, surface=fronts.surface[take], reflectance=fronts.reflectance[take],
                      emission=fronts.emission[take], is_triangle=is_triangle, grid=fronts.grid[take],
                      split=patches.split, params=patch_params, surface_corners=patches.surface_corners, opacity=opacity)
    return with_back_patches(refined, backs)


def with_back_patches(patches: Patches, backs: np.ndarray) -> Patches:
    """`patches` followed by a back patch for every patch of a surface in the mask `backs` (S,)."""
    fronts = np.flatnonzero(backs[patches.surface])
    if len(fronts) == 0:
        return patches
    count = len(patches)
    twin = np.full(count + len(fronts), -1, dtype=np.int64)
    twin[fronts] = count + np.arange(len(fronts))
    back_of = np.concatenate([np.full(count, -1, dtype=np.int64), fronts])
    take = np.concatenate([np.arange(count), fronts])
    corners = np.concatenate([patches.corners, reversed_corners(patches.corners[fronts], patches.is_triangle[fronts])])
    uv = np.concatenate([patches.uv, reversed_corners(patches.uv[fronts], patches.is_triangle[fronts])])
    opacity = None
    if patches.opacity is not None:
        opacity = OpacityMaps(patches.opacity.images, patches.opacity.index[take], np.concatenate(
            [patches.opacity.uv, reversed_corners(patches.opacity.uv[fronts], patches.is_triangle[fronts])]))
    return Patches(corners=corners, uv=uv, surface=patches.surface[take], reflectance=patches.reflectance[take],
                   emission=patches.emission[take], is_triangle=patches.is_triangle[take], grid=patches.grid[take],
                   split=patches.split, back_of=back_of, twin=twin, params=patches.params[take],
                   surface_corners=patches.surface_corners, opacity=opacity)


def subdivide(scene: Scene, subdiv: int | None = None, patch_size: float = 0.5,
              backs: np.ndarray | None = None) -> Patches:
    """Split every surface N x N (`subdiv`), or by `patch_size` when subdiv is None; surfaces in
    the mask `backs` get back patches too."""
    split = split_counts(scene, subdiv, patch_size)
    opacity_of = scene.opacity.uv if scene.opacity is not None else np.zeros((len(scene), 4, 2))
    keys = np.concatenate([scene.is_triangle[:, None].astype(np.int64), split], axis=1)
    groups, group_of = np.unique(keys, axis=0, return_inverse=True)
    parts = []
    for number, (triangle, columns, rows) in enumerate(groups):
        members = np.flatnonzero(group_of.ravel() == number)
        if triangle:
            params, row, col = triangle_grid(int(columns))
            weights = np.concatenate([1 - params.sum(axis=2, keepdims=True), params], axis=2)  # (k, 4, 3)
            corners = np.einsum("kcw,gwd->gkcd", weights, scene.corners[members, :3])
            uv = np.einsum("kcw,gwd->gkcd", weights, scene.uv[members, :3])
            opacity_uv = np.einsum("kcw,gwd->gkcd", weights, opacity_of[members, :3])
            # each piece the whole of its own (degenerate) bilinear map: its children are rectangles of it
            rects = np.broadcast_to(np.array([[0.0, 0.0], [1.0, 1.0]]), (len(params), 2, 2))
        else:
            params, row, col = quad_grid(int(columns), int(rows))
            corners = bilinear(scene.corners[members], params[..., 0], params[..., 1])
            uv = bilinear(scene.uv[members], params[..., 0], params[..., 1])
            opacity_uv = bilinear(opacity_of[members], params[..., 0], params[..., 1])
            rects = params[:, [0, 2]]
        count = len(params)
        parts.append((np.repeat(members, count), corners.reshape(-1, 4, 3), uv.reshape(-1, 4, 2),
                      np.tile(np.stack([row, col], axis=1), (len(members), 1)), np.tile(rects, (len(members), 1, 1)),
                      opacity_uv.reshape(-1, 4, 2)))
    surface = np.concatenate([p[0] for p in parts])
    order = np.argsort(surface, kind="stable")  # surface by surface, each in its grid order
    surface = surface[order]
    patches = Patches(
        corners=np.concatenate([p[1] for p in parts])[order],
        uv=np.concatenate([p[2] for p in parts])[order],
        surface=surface.astype(np.int32),
        reflectance=scene.reflectance[surface],
        emission=scene.emission[surface],
        is_triangle=scene.is_triangle[surface],
        grid=np.concatenate([p[3] for p in parts])[order].astype(np.int32),
        split=split,
        params=np.concatenate([p[4] for p in parts])[order],
        surface_corners=np.asarray(scene.corners, dtype=np.float64),
        opacity=None if scene.opacity is None else OpacityMaps(
            scene.opacity.images, scene.opacity.index[surface], np.concatenate([p[5] for p in parts])[order]),
    )
    return patches if backs is None else with_back_patches(patches, backs)


def surface_patches(scene: Scene, patches: Patches) -> Patches:
    """One patch per surface of `scene` (front k is surface k), with a back wherever `patches`
    have backs: what the surfaces show, whatever their split (the texel pass's item buffers)."""
    backs = np.zeros(len(scene), dtype=bool)
    backs[patches.surface[patches.is_back]] = True
    return subdivide(scene, subdiv=1, backs=backs)
