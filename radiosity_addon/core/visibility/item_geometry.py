"""What item buffers draw: the scene's geometry, each primitive telling which patch it shows.

A hemi-cube batch draws the whole scene once per face of every hemi-cube, so its cost grows with
the triangles drawn (on llvmpipe, measured: time in proportion to them). A flat quad surface split
into many patches (a wall, a floor, refined near an emitter) is therefore drawn once, as its own
two triangles, and the fragment shader finds the patch under each pixel: the point's bilinear
parameters (s, t) in the surface, then the patch whose rectangle holds them in a table over the
surface's distinct cut parameters (every patch of a quad surface is a rectangle of its parameter
domain: the grid of `subdivide`, cut again by `split_patches`). The same pixel centre gets the same
patch as drawing the patches' own triangles would, up to rounding at their shared edges.

Everything else (triangles' pieces, curved quads, surfaces of one patch, patches without their
rectangle) is drawn patch by patch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Patches
from ..scene.geometry import area_vector, bilinear_each

DIRECT = -1  # a vertex's `lookup` when it belongs to a patch drawn by its own triangles
NO_PATCH = 0xFFFFFFFF  # a table cell no patch covers (nothing is drawn there)
PLANAR = 1e-6  # of a surface's size: farther from its plane a corner makes it curved (drawn patch by patch)
CUT_QUANTUM = 2.0 ** -40  # cut parameters this close are one cut (one patch's edge seen from both sides)
TABLE_CELLS_PER_PATCH = 16  # a surface whose cut table would hold more cells than this per patch is drawn
# patch by patch (cuts that do not line up across it make the table grow as their product)

# Looked up only where the triangles saved per face outnumber the face's pixels (the lookup runs for
# every fragment, overdrawn ones too). Measured on llvmpipe (docs/architecture.md): the Cornell box's
# `final` form factors (64 px, 1.07 saved per pixel) 1.73 -> 1.20 s and a 4k room's hemi-cube
# `final` (2.3) 27.5 -> 20.9 s gain; the room's 128-px `good` shooter maps (~0.6) and 256-px
# probes lose (11.8 -> 13.5 s, 0.05 -> 0.08 s a batch), so they stay patch by patch.
LOOKUP_PIXELS_PER_TRIANGLE = 1.0

VERTEX_FORMAT = "3f 3f 1u 1i 1i"  # position, normal, patch, twin, lookup
VERTEX_DTYPE = [("p", "f4", 3), ("n", "f4", 3), ("id", "u4"), ("twin", "i4"), ("lookup", "i4")]


@dataclass
class ItemGeometry:
    vertices: np.ndarray  # VERTEX_DTYPE rows
    indices: np.ndarray  # (3 T,) uint32 triangles
    surfaces: np.ndarray  # (L, 6, 4) float32 per looked-up surface: origin, axis s, axis t (scaled to its
    # size), corners 1-3 in that frame (x, y, 0, 0), then (cuts s offset, count, cuts t offset, count) as uint
    cuts: np.ndarray  # float32 cut parameters, each surface's s then t, ascending from 0 to 1
    table: np.ndarray  # uint32 front patch ids, per surface (ns - 1) x (nt - 1) cells, row-major in t
    table_offsets: np.ndarray  # (L,) uint32 where each surface's table starts
    twins: np.ndarray  # (fronts,) int32 each front's back patch, -1 when its back is not simulated

    @property
    def looked_up(self) -> int:
        return len(self.surfaces)


def item_geometry(patches: Patches, face_pixels: int | None = None) -> ItemGeometry:
    """The item-buffer geometry of `patches`' fronts: looked-up surfaces as one quad, the rest patch by
    patch. With `face_pixels` (the pixels of one face of the maps drawn), surfaces are looked up only
    where that saves time (LOOKUP_PIXELS_PER_TRIANGLE); with 0 never."""
    count = patches.front_count
    lookup = _lookup_surfaces(patches) if face_pixels != 0 else None
    if lookup is not None and face_pixels is not None:
        replaced = np.isin(patches.surface[:count], lookup["surfaces"])
        saved = int(np.where(patches.is_triangle[:count][replaced], 1, 2).sum()) - 2 * len(lookup["surfaces"])
        if saved < LOOKUP_PIXELS_PER_TRIANGLE * face_pixels:
            lookup = None
    surface = patches.surface[:count]
    direct = np.ones(count, dtype=bool) if lookup is None else ~np.isin(surface, lookup["surfaces"])
    vertices, indices = _patch_geometry(patches, np.flatnonzero(direct))
    twins = patches.twin[:count].astype(np.int32)
    if lookup is None:
        empty = np.zeros((0, 6, 4), dtype=np.float32)
        return ItemGeometry(vertices, indices, empty, np.zeros(1, np.float32), np.zeros(1, np.uint32),
                            np.zeros(0, np.uint32), twins)
    quads, quad_indices = _surface_geometry(patches.surface_corners[lookup["surfaces"]], len(vertices))
    return ItemGeometry(np.concatenate([vertices, quads]), np.concatenate([indices, quad_indices]),
                        lookup["records"], lookup["cuts"], lookup["table"], lookup["table_offsets"], twins)


def _patch_geometry(patches: Patches, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of the front patches `rows`: a back patch is drawn as its front seen from
    behind (the twin id), so coincident sides never fight over depth."""
    count = len(rows)
    vertices = np.empty(count * 4, dtype=VERTEX_DTYPE)
    vertices["p"] = patches.corners[rows].reshape(-1, 3)
    vertices["n"] = np.repeat(patches.normal[rows], 4, axis=0)
    vertices["id"] = np.repeat(rows.astype(np.uint32), 4)
    vertices["twin"] = np.repeat(patches.twin[rows].astype(np.int32), 4)
    vertices["lookup"] = DIRECT
    base = (np.arange(count) * 4)[:, None]
    is_triangle = patches.is_triangle[rows]
    indices = np.where(is_triangle[:, None], base + np.array([0, 1, 2, 0, 1, 2]), base + np.array([0, 1, 2, 0, 2, 3]))
    keep = np.ones_like(indices, dtype=bool)
    keep[is_triangle, 3:] = False  # the degenerate half
    return vertices, indices[keep].astype(np.uint32)


def _surface_geometry(corners: np.ndarray, first_vertex: int) -> tuple[np.ndarray, np.ndarray]:
    count = len(corners)
    area = area_vector(corners)
    vertices = np.empty(count * 4, dtype=VERTEX_DTYPE)
    vertices["p"] = corners.reshape(-1, 3)
    vertices["n"] = np.repeat(area / np.linalg.norm(area, axis=1, keepdims=True), 4, axis=0)
    vertices["id"] = 0
    vertices["twin"] = -1
    vertices["lookup"] = np.repeat(np.arange(count, dtype=np.int32), 4)
    base = first_vertex + (np.arange(count) * 4)[:, None]
    return vertices, (base + np.array([0, 1, 2, 0, 2, 3])).ravel().astype(np.uint32)


def _lookup_surfaces(patches: Patches) -> dict | None:
    """The surfaces drawn once with a patch table, and their records, cuts and tables (None: none can be)."""
    corners = patches.surface_corners
    count = patches.front_count
    if corners is None or count == 0:
        return None
    surface = patches.surface[:count].astype(np.int64)
    params = patches.params[:count]
    surfaces = len(corners)
    per_surface = np.bincount(surface, minlength=surfaces)
    known = np.isfinite(params).all(axis=(1, 2))
    candidate = (per_surface >= 2) & (np.bincount(surface, weights=~known, minlength=surfaces) == 0)
    candidate &= _planar(corners)
    # the patches must be where their rectangles say (the bilinear map of the surface at their corners)
    mine = candidate[surface]
    rect_corners = _rectangle_corners(params[mine])
    expected = bilinear_each(corners[surface[mine]], rect_corners[..., 0], rect_corners[..., 1])
    size = np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)
    misplaced = np.linalg.norm(expected - patches.corners[:count][mine], axis=2).max(axis=1) > 1e-6 * size[surface[mine]]
    candidate[np.unique(surface[mine][misplaced])] = False

    chosen = np.flatnonzero(candidate[surface])  # front patches of candidate surfaces
    if len(chosen) == 0:
        return None
    chosen = chosen[np.argsort(surface[chosen], kind="stable")]
    s_cuts, _ = _cuts(surface[chosen], params[chosen, :, 0])
    t_cuts, _ = _cuts(surface[chosen], params[chosen, :, 1])
    listed = s_cuts["surfaces"]
    # tables of at most TABLE_CELLS_PER_PATCH cells a patch (cuts that do not line up multiply them)
    small = (s_cuts["count"] - 1) * (t_cuts["count"] - 1) <= TABLE_CELLS_PER_PATCH * per_surface[listed]
    candidate[listed[~small]] = False
    chosen = chosen[candidate[surface[chosen]]]
    if len(chosen) == 0:
        return None
    owner = surface[chosen]
    s_cuts, s_index = _cuts(owner, params[chosen, :, 0])
    t_cuts, t_index = _cuts(owner, params[chosen, :, 1])
    listed = s_cuts["surfaces"]
    place = np.searchsorted(listed, owner)  # each patch's surface among `listed`
    columns, rows = s_cuts["count"] - 1, t_cuts["count"] - 1
    cells = columns * rows
    table_start = np.concatenate([[0], np.cumsum(cells)[:-1]])
    cell, which = _cells(s_index, t_index, columns[place])
    flat = table_start[place[which]] + cell
    # every cell under one patch at most (else the rectangles overlap: the surface is drawn patch by patch)
    hits = np.bincount(flat, minlength=int(cells.sum()))
    fits = np.ones(len(listed), dtype=bool)
    fits[np.unique(place[which][hits[flat] > 1])] = False
    if not fits.any():
        return None
    table = np.full(int(cells.sum()), NO_PATCH, dtype=np.uint32)
    table[flat] = chosen[which]
    table = table[np.repeat(fits, cells)]
    table_offsets = np.concatenate([[0], np.cumsum(cells[fits])[:-1]]).astype(np.uint32)
    cuts, offsets = _interleaved_cuts(s_cuts, t_cuts, fits)
    return {"surfaces": listed[fits], "records": _records(corners[listed[fits]], offsets), "cuts": cuts,
            "table": table, "table_offsets": table_offsets}


def _interleaved_cuts(s_cuts: dict, t_cuts: dict, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The kept surfaces' s cuts then t cuts, one surface after another (float32), and per surface
    (s offset, s count, t offset, t count) into them (uint32)."""
    s_count, t_count = s_cuts["count"][keep], t_cuts["count"][keep]
    lengths = s_count + t_count
    start = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    segment = np.repeat(np.arange(len(lengths)), lengths)
    position = np.arange(int(lengths.sum())) - start[segment]
    in_s = position < s_count[segment]
    s_source = s_cuts["offset"][keep][segment] + position
    t_source = t_cuts["offset"][keep][segment] + position - s_count[segment]
    values = np.where(in_s, s_cuts["values"][np.where(in_s, s_source, 0)],
                      t_cuts["values"][np.where(in_s, 0, t_source)])
    offsets = np.stack([start, s_count, start + s_count, t_count], axis=1).astype(np.uint32)
    return values.astype(np.float32), offsets


def _planar(corners: np.ndarray) -> np.ndarray:
    area = area_vector(corners)
    length = np.linalg.norm(area, axis=1)
    normal = area / np.maximum(length, 1e-300)[:, None]
    size = np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)
    off_plane = np.abs(np.einsum("sd,sd->s", corners[:, 3] - corners[:, 0], normal))
    off_plane = np.maximum(off_plane, np.abs(np.einsum("sd,sd->s", corners[:, 1] - corners[:, 0], normal)))
    return (length > 0) & (off_plane <= PLANAR * size)


def _rectangle_corners(params: np.ndarray) -> np.ndarray:
    """(n, 4, 2) (s, t) at corners 0-3 of rectangles [(s0, t0), (s1, t1)]."""
    (s0, t0), (s1, t1) = params[:, 0].T, params[:, 1].T
    return np.stack([np.stack([s0, t0], 1), np.stack([s1, t0], 1), np.stack([s1, t1], 1), np.stack([s0, t1], 1)], 1)


def _cuts(owner: np.ndarray, ends: np.ndarray) -> tuple[dict, np.ndarray]:
    """The distinct cut parameters of every surface in `owner` (sorted), from its patches' two ends
    `ends` (n, 2); and each patch's ends as indices into its surface's cuts."""
    quantized = np.rint(ends * (1 / CUT_QUANTUM)).astype(np.int64)
    keys = (owner[:, None] << 42) | quantized  # surface, then parameter (at most 2^40)
    unique, inverse = np.unique(keys.ravel(), return_inverse=True)
    surfaces, first, counts = np.unique(unique >> 42, return_index=True, return_counts=True)
    index = inverse.reshape(-1, 2) - first[np.searchsorted(surfaces, owner)][:, None]
    values = (unique & ((1 << 42) - 1)).astype(np.float64) * CUT_QUANTUM
    return {"surfaces": surfaces, "offset": first, "count": counts, "values": values}, index


def _cells(s_index: np.ndarray, t_index: np.ndarray, columns: np.ndarray):
    """Every table cell each patch covers: (cell index within its surface's table, patch row)."""
    width = s_index[:, 1] - s_index[:, 0]
    height = t_index[:, 1] - t_index[:, 0]
    sizes = np.maximum(width * height, 0)
    which = np.repeat(np.arange(len(width)), sizes)
    k = np.arange(len(which)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    i = s_index[which, 0] + k % np.maximum(width[which], 1)
    j = t_index[which, 0] + k // np.maximum(width[which], 1)
    return j * columns[which] + i, which


def _records(corners: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(L, 6, 4) float32: origin, s axis, t axis of each surface's plane frame scaled by 1/size (so the
    inverse bilinear map works at unit scale), its corners 1-3 in that frame, and its cut offsets."""
    origin = corners[:, 0]
    size = np.maximum(np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1),
                      np.linalg.norm(corners[:, 3] - corners[:, 1], axis=1))
    area = area_vector(corners)
    normal = area / np.linalg.norm(area, axis=1, keepdims=True)
    axis_s = corners[:, 1] - origin
    axis_s /= np.linalg.norm(axis_s, axis=1, keepdims=True)
    axis_t = np.cross(normal, axis_s)
    axis_s, axis_t = axis_s / size[:, None], axis_t / size[:, None]
    relative = corners - origin[:, None]
    flat = np.stack([np.einsum("skd,sd->sk", relative, axis_s), np.einsum("skd,sd->sk", relative, axis_t)], axis=2)
    records = np.zeros((len(corners), 6, 4), dtype=np.float32)
    records[:, 0, :3] = origin
    records[:, 1, :3] = axis_s
    records[:, 2, :3] = axis_t
    records[:, 3] = flat[:, 1:3].reshape(-1, 4)  # corners 1, 2
    records[:, 4, :2] = flat[:, 3]  # corner 3
    records[:, 5] = offsets.view(np.float32)
    return records
