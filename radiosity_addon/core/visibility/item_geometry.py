"""What item buffers draw: the scene's geometry, each primitive telling which patch it shows.

A hemi-cube batch draws the whole scene once per face of every hemi-cube, so its cost grows with
the triangles drawn (on llvmpipe, time in proportion to them). A flat convex quad surface
split into many patches (a wall, a floor, refined near an emitter) is therefore drawn once, as its
own two triangles, and the fragment shader finds the patch whose rectangle of the surface's
bilinear parameters (s, t) holds the pixel, in a table over the surface's distinct cut parameters
(every patch of a quad surface is a rectangle of its parameter domain: the grid of `subdivide`, cut
again by `split_patches`). On a parallelogram (s, t) is affine, so the triangles carry it and
interpolation gives it exactly; on any other flat quad (a skewed floor) they carry the point's
coordinates in the quad's plane, affine too, and the shader inverts the bilinear map there (a
quadratic). A triangle surface is split into grid triangles, and every piece refinement cuts from
one is a rectangle of that grid triangle's map p(s, t) = (1 - t)((1 - s) c0 + s c1) + t c2, so each
grid triangle is drawn once the same way: its corners carry barycentric weights (w1, w2), affine,
and the shader takes s = w1 / (1 - w2), t = w2. The same pixel centre gets the same patch as drawing
the patches' own triangles would, up to rounding at their shared edges. What is drawn once with a
table is a "unit": a quad surface, or a grid triangle of a triangle surface.

Everything else (bent or concave quads, units of one patch, patches without their rectangle) is
drawn patch by patch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Patches
from ..scene.geometry import area_vector, bilinear_each
from ..scene.neighbours import expanded_ranges

EMPTY_CELL = 0xFFFFFFFF  # a table cell no patch covers (nothing is drawn there)
PARALLELOGRAM = 1e-6  # of a surface's size: c0 + c2 - c1 - c3 longer than this and it is no parallelogram
FLAT = 1e-6  # of a surface's size: c3 farther than this from the plane of c0, c1, c2 and it is bent
CUT_QUANTUM = 2.0 ** -40  # cut parameters this close are one cut (one patch's edge seen from both sides)
MAX_BINS = 4096  # uniform bins along one side of a surface, each holding at most one cut (else patch by patch)
TABLE_CELLS_PER_PATCH = 16  # a surface whose cut table would hold more cells than this per patch is drawn
# patch by patch (cuts that do not line up across it make the table grow as their product)

# Looked up only where the triangles saved per face reach half the face's pixels (the lookup runs for
# every fragment, overdrawn ones too: below that it costs more than the triangles it saves).
LOOKUP_PIXELS_PER_TRIANGLE = 0.5

RECORD = 5  # uvec4s per looked-up unit (`ItemGeometry.surfaces`)
GRID_ROW_SHIFT = 15  # a grid triangle's unit key: row << 15 | column (columns < 2 n)
TRIANGLE_MAP = 2  # a record's map: a grid triangle (s = w1 / (1 - w2), t = w2 from barycentric weights)
OWN_TRIANGLES = 3  # a vertex's map when it belongs to a patch drawn by its own triangles (no lookup)
# Every vertex of a unit carries the unit's record (`unit_record`), passed on flat: a fragment then reads
# only the cuts, bins and table cell it needs, not the record from a storage buffer (slow per fragment).
VERTEX_DTYPE = [("p", "f4", 3), ("n", "f4", 3), ("id", "u4"), ("twin", "i4"), ("st", "f4", 2),
                ("record", "u4", (4, 4)), ("opacity_uv", "f4", 2), ("opacity_rect", "i4", 4)]


def vertex_format(lookup: bool, opacity: bool) -> tuple[str, list[str]]:
    """The vertex rows' format and attribute names for an item-buffer shader with or without the
    patch lookup (`(s, t)` and the unit's record) and the opacity test (texture UVs and rectangle)."""
    # a patch and its twin in one attribute: with the lookup, the opacity and the five faces' instance
    # attributes, a shader reads 16, what OpenGL guarantees
    fields = "3f 3f 2i " + ("2f 4u 4u 4u 4f" if lookup else "72x") + (" 2f 4i" if opacity else " 24x")
    names = ["in_position", "in_normal", "in_item"]
    names += ["in_st", "in_cuts", "in_bins", "in_table", "in_ef"] if lookup else []
    names += ["in_opacity_uv", "in_opacity_rect"] if opacity else []
    return fields, names


@dataclass
class ItemGeometry:
    vertices: np.ndarray  # VERTEX_DTYPE rows
    indices: np.ndarray  # (3 T,) uint32 triangles
    surfaces: np.ndarray  # (L, RECORD, 4) uint32 per looked-up unit: (cuts s offset, count, cuts t offset,
    # count), (bins s offset, count, bins t offset, count), (table offset, map, 0, 0) with map 0 for a
    # parallelogram, 1 for a skewed quad, 2 for a grid triangle; then for a skewed quad the float32 bits of
    # its bilinear map in plane coordinates (e, f), (g, 0, 0): p = e s + f t + g s t
    cuts: np.ndarray  # float32 cut parameters, each surface's s then t, ascending from 0 to 1
    bins: np.ndarray  # uint32 per surface and side, N uniform bins (N a power of two): the last cut at or
    # below each bin's start, so a parameter's cell is that one or the next (a binary search made the
    # lookup cost more than the triangles it saved)
    table: np.ndarray  # uint32 front patch ids, per surface (ns - 1) x (nt - 1) cells, row-major in t
    twins: np.ndarray  # (fronts,) int32 each front's back patch, -1 when its back is not simulated
    opacity_index: np.ndarray | None = None  # (vertices,) the opacity texture of each vertex's polygon (None: none)

    @property
    def looked_up(self) -> int:
        return len(self.surfaces)


def item_geometry(patches: Patches, face_pixels: int | None = None) -> ItemGeometry:
    """The item-buffer geometry of `patches`' fronts: looked-up units drawn once, the rest patch by
    patch. With `face_pixels` (the pixels of one face of the maps drawn), units are looked up only
    where that saves time (LOOKUP_PIXELS_PER_TRIANGLE); with 0 never."""
    count = patches.front_count
    lookup = lookup_units(patches) if face_pixels != 0 else None
    if lookup is not None and face_pixels is not None:
        replaced = np.isin(lookup["unit_of"], lookup["units"])
        unit_triangles = int(np.where(lookup["skewed"] == TRIANGLE_MAP, 1, 2).sum())
        saved = int(np.where(patches.is_triangle[:count][replaced], 1, 2).sum()) - unit_triangles
        if saved < LOOKUP_PIXELS_PER_TRIANGLE * face_pixels:
            lookup = None
    direct = np.ones(count, dtype=bool) if lookup is None else ~np.isin(lookup["unit_of"], lookup["units"])
    vertices, indices, opacity_index = _patch_geometry(patches, np.flatnonzero(direct))
    twins = patches.twin[:count].astype(np.int32)
    if lookup is None:
        empty = np.zeros((0, RECORD, 4), dtype=np.uint32)
        return ItemGeometry(vertices, indices, empty, np.zeros(1, np.float32), np.zeros(1, np.uint32),
                            np.zeros(1, np.uint32), twins, opacity_index)
    quads, quad_indices = _unit_geometry(lookup["corners"], lookup["corner_st"], lookup["skewed"] == TRIANGLE_MAP,
                                         unit_record(lookup["records"]), len(vertices))
    if opacity_index is not None:  # looked-up units are opaque (`lookup_units`)
        opacity_index = np.concatenate([opacity_index, np.full(len(quads), -1, dtype=np.int64)])
    return ItemGeometry(np.concatenate([vertices, quads]), np.concatenate([indices, quad_indices]),
                        lookup["records"], lookup["cuts"], lookup["bins"], lookup["table"], twins, opacity_index)


def _patch_geometry(patches: Patches, rows: np.ndarray):
    """Vertices and triangles of the front patches `rows`, and each vertex's opacity texture (None: the
    patches have none): a back patch is drawn as its front seen from behind (the twin id), so
    coincident sides never fight over depth."""
    corners, normals, ids = patches.corners[rows], patches.normal[rows], rows
    is_triangle = patches.is_triangle[rows]
    textured = patches.opacity is not None
    opacity_index = patches.opacity.index[rows] if textured else np.full(len(rows), -1)
    opacity_uv = patches.opacity.uv[rows] if textured else np.zeros((len(rows), 4, 2))
    count = len(ids)
    vertices = np.empty(count * 4, dtype=VERTEX_DTYPE)
    vertices["p"] = corners.reshape(-1, 3)
    vertices["n"] = np.repeat(normals, 4, axis=0)
    vertices["id"] = np.repeat(ids.astype(np.uint32), 4)
    vertices["twin"] = np.repeat(patches.twin[ids].astype(np.int32), 4)
    vertices["st"] = 0.0
    vertices["record"] = 0
    vertices["record"][:, 2, 1] = OWN_TRIANGLES
    vertices["opacity_uv"] = opacity_uv.reshape(-1, 2)
    vertices["opacity_rect"] = 0
    base = (np.arange(count) * 4)[:, None]
    indices = np.where(is_triangle[:, None], base + np.array([0, 1, 2, 0, 1, 2]), base + np.array([0, 1, 2, 0, 2, 3]))
    keep = np.ones_like(indices, dtype=bool)
    keep[is_triangle, 3:] = False  # the degenerate half
    return vertices, indices[keep].astype(np.uint32), np.repeat(opacity_index, 4) if textured else None


def unit_record(records: np.ndarray) -> np.ndarray:
    """(L, 4, 4) uint32: what a unit's vertices carry of its record (`ItemGeometry.surfaces`): its cuts'
    and bins' offsets and counts, (table offset, map, g), (e, f) (hemicube_item_buffer.vert)."""
    carried = np.zeros((len(records), 4, 4), dtype=np.uint32)
    carried[:, :2] = records[:, :2]
    carried[:, 2, :2] = records[:, 2, :2]
    carried[:, 2, 2:] = records[:, 4, :2]
    carried[:, 3] = records[:, 3]
    return carried


def _unit_geometry(corners: np.ndarray, corner_st: np.ndarray, triangle: np.ndarray, records: np.ndarray,
                   first_vertex: int) -> tuple[np.ndarray, np.ndarray]:
    """Two triangles per looked-up quad, one per grid triangle, carrying `corner_st` (n, 4, 2) and the
    unit's `records` (`unit_record`) at the corners."""
    count = len(corners)
    area = area_vector(corners)
    vertices = np.empty(count * 4, dtype=VERTEX_DTYPE)
    vertices["p"] = corners.reshape(-1, 3)
    vertices["n"] = np.repeat(area / np.linalg.norm(area, axis=1, keepdims=True), 4, axis=0)
    vertices["id"] = 0
    vertices["twin"] = -1
    vertices["st"] = corner_st.reshape(-1, 2)
    vertices["record"] = np.repeat(records, 4, axis=0)
    vertices["opacity_uv"] = 0.0
    vertices["opacity_rect"] = 0
    base = first_vertex + (np.arange(count) * 4)[:, None]
    indices = base + np.array([0, 1, 2, 0, 2, 3])
    keep = np.ones_like(indices, dtype=bool)
    keep[triangle, 3:] = False  # a grid triangle's second half is empty (c3 repeats c2)
    return vertices, indices[keep].astype(np.uint32)


def _units(patches: Patches):
    """Per front patch its unit (what one table serves), and per unit its corners and whether it is a grid
    triangle: a quad surface is one unit; every grid triangle of a triangle surface (c3 repeating c2) is
    one, its corners those `subdivide` gave it (scene.patches.triangle_grid)."""
    count = patches.front_count
    surface = patches.surface[:count].astype(np.int64)
    corners = patches.surface_corners
    triangle_surface = (corners[:, 3] == corners[:, 2]).all(axis=1)
    row, column = patches.grid[:count, 0].astype(np.int64), patches.grid[:count, 1].astype(np.int64)
    on_triangle = triangle_surface[surface]
    cell = np.where(on_triangle, 1 + (row << GRID_ROW_SHIFT) + column, 0)
    unique, unit_of = np.unique((surface << 32) | cell, return_inverse=True)
    unit_surface, unit_cell = unique >> 32, unique & 0xFFFFFFFF
    unit_corners = corners[unit_surface].copy()
    is_grid_triangle = unit_cell > 0
    if is_grid_triangle.any():
        n = patches.split[unit_surface[is_grid_triangle], 0][:, None, None]
        r, c = np.divmod(unit_cell[is_grid_triangle] - 1, 1 << GRID_ROW_SHIFT)
        i = c // 2
        # (b1, b2) at the corners: upright (i, r), (i+1, r), (i, r+1); inverted (i+1, r), (i+1, r+1), (i, r+1)
        odd = (c % 2 == 1)[:, None]
        b1 = np.where(odd, np.stack([i + 1, i + 1, i, i], 1), np.stack([i, i + 1, i, i], 1))
        b2 = np.where(odd, np.stack([r, r + 1, r + 1, r + 1], 1), np.stack([r, r, r + 1, r + 1], 1))
        bary = np.stack([b1, b2], axis=2) / n
        weights = np.concatenate([1 - bary.sum(axis=2, keepdims=True), bary], axis=2)  # as `subdivide` weighs them
        unit_corners[is_grid_triangle] = np.einsum("kcw,kwd->kcd", weights,
                                                   corners[unit_surface[is_grid_triangle], :3])
    return unit_of.ravel(), unit_corners, is_grid_triangle


def lookup_units(patches: Patches) -> dict | None:
    """The units drawn once with a patch table (`_units`), and their records, cuts and tables (None: none can be)."""
    count = patches.front_count
    if patches.surface_corners is None or count == 0:
        return None
    unit_of, corners, is_grid_triangle = _units(patches)
    surface = unit_of  # the tables below are per unit
    params = patches.params[:count]
    surfaces = len(corners)
    per_surface = np.bincount(surface, minlength=surfaces)
    known = np.isfinite(params).all(axis=(1, 2))
    if patches.opacity is not None:  # an alpha-cut surface is drawn patch by patch, with its texture UVs
        known[np.isin(surface, surface[patches.opacity.index[:count] >= 0])] = False
    candidate = (per_surface >= 2) & (np.bincount(surface, weights=~known, minlength=surfaces) == 0)
    candidate &= np.where(is_grid_triangle, np.linalg.norm(area_vector(corners), axis=1) > 0, _flat_convex_quad(corners))
    # the patches must be where their rectangles say (the bilinear map of the unit at their corners)
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
    s_bins, t_bins = _bin_counts(s_cuts), _bin_counts(t_cuts)
    fits = (s_bins <= MAX_BINS) & (t_bins <= MAX_BINS)
    fits[np.unique(place[which][hits[flat] > 1])] = False
    if not fits.any():
        return None
    table = np.full(int(cells.sum()), EMPTY_CELL, dtype=np.uint32)
    table[flat] = chosen[which]
    table = table[np.repeat(fits, cells)]
    table_offsets = np.concatenate([[0], np.cumsum(cells[fits])[:-1]]).astype(np.uint32)
    cuts, offsets = _interleaved_cuts(s_cuts, t_cuts, fits)
    bins, bin_offsets = _bins(s_cuts, t_cuts, s_bins, t_bins, fits)
    records = np.zeros((int(fits.sum()), RECORD, 4), dtype=np.uint32)
    records[:, 0], records[:, 1], records[:, 2, 0] = offsets, bin_offsets, table_offsets
    kept = listed[fits]
    corner_st, skewed, maps = _plane_maps(corners[kept])
    triangle = is_grid_triangle[kept]
    corner_st[triangle] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]  # barycentric (w1, w2)
    skewed[triangle] = TRIANGLE_MAP
    records[:, 2, 1] = skewed
    records[:, 3:] = maps.view(np.uint32)
    return {"units": kept, "unit_of": unit_of, "corners": corners[kept], "skewed": skewed, "records": records,
            "cuts": cuts, "bins": bins, "table": table, "corner_st": corner_st}


def _bin_counts(cuts: dict) -> np.ndarray:
    """Per surface, the fewest uniform bins (a power of two) narrower than its closest two cuts, so no
    bin holds two cuts inside it."""
    gaps = np.diff(cuts["values"])
    gaps[np.diff(cuts["keys"] >> 42) != 0] = np.inf  # between two surfaces' cuts
    closest = np.minimum.reduceat(np.append(gaps, np.inf), cuts["offset"])
    return 2 ** np.ceil(np.log2(1 / np.maximum(closest, CUT_QUANTUM))).astype(np.int64)


def _bins(s_cuts: dict, t_cuts: dict, s_bins: np.ndarray, t_bins: np.ndarray, keep: np.ndarray):
    """The kept surfaces' bins, s then t, one surface after another (uint32: the last cut at or below each
    bin's start, counted in the surface's cuts), and per surface (s offset, count, t offset, count)."""
    found = []
    for cuts, bins in ((s_cuts, s_bins[keep]), (t_cuts, t_bins[keep])):
        owner, index = expanded_ranges(np.zeros_like(bins), bins)
        start = index * ((1 << 40) // bins[owner])  # each bin's start, quantized like the cuts
        at = np.searchsorted(cuts["keys"], (cuts["surfaces"][keep][owner] << 42) | start, side="right") - 1
        found.append(at - cuts["offset"][keep][owner])
    first = lambda bins: np.cumsum(bins) - bins  # noqa: E731
    values, offsets = _side_by_side(found[0], first(s_bins[keep]), s_bins[keep],
                                    found[1], first(t_bins[keep]), t_bins[keep])
    return values.astype(np.uint32), offsets


def _interleaved_cuts(s_cuts: dict, t_cuts: dict, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The kept surfaces' s cuts then t cuts, one surface after another (float32), and per surface
    (s offset, s count, t offset, t count) into them (uint32)."""
    values, offsets = _side_by_side(s_cuts["values"], s_cuts["offset"][keep], s_cuts["count"][keep],
                                    t_cuts["values"], t_cuts["offset"][keep], t_cuts["count"][keep])
    return values.astype(np.float32), offsets


def _side_by_side(s_values, s_first, s_count, t_values, t_first, t_count) -> tuple[np.ndarray, np.ndarray]:
    """Per surface its ranges of `s_values` then of `t_values`, one surface after another, and per surface
    (s offset, s count, t offset, t count) into the result (uint32)."""
    lengths = s_count + t_count
    start = np.cumsum(lengths) - lengths
    segment, position = expanded_ranges(np.zeros_like(lengths), lengths)
    in_s = position < s_count[segment]
    values = np.where(in_s, s_values[np.where(in_s, s_first[segment] + position, 0)],
                      t_values[np.where(in_s, 0, t_first[segment] + position - s_count[segment])])
    return values, np.stack([start, s_count, start + s_count, t_count], axis=1).astype(np.uint32)


def _plane_maps(corners: np.ndarray):
    """What the looked-up quads' vertices carry and how their fragments find (s, t): per quad its corners'
    (s, t) (the unit square) on a parallelogram, else their coordinates in the quad's plane (axes along
    c1 - c0 and normal x that, in units of the diagonal c2 - c0, from c0); whether it is skewed; and the
    bilinear map in those coordinates, float32 (n, 2, 4): (e, f), (g, 0, 0), p(s, t) = e s + f t + g s t."""
    count = len(corners)
    skewed = ~_parallelogram(corners)
    normal = area_vector(corners)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    x = corners[:, 1] - corners[:, 0]
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(normal, x)
    relative = (corners - corners[:, :1]) / np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)[:, None, None]
    plane = np.stack([(relative * x[:, None]).sum(axis=2), (relative * y[:, None]).sum(axis=2)], axis=2)
    square = np.broadcast_to(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), (count, 4, 2))
    corner_st = np.where(skewed[:, None, None], plane, square)
    e, f = plane[:, 1], plane[:, 3]
    g = plane[:, 0] - plane[:, 1] + plane[:, 2] - plane[:, 3]
    maps = np.zeros((count, 2, 4), dtype=np.float32)
    maps[:, 0, :2], maps[:, 0, 2:], maps[:, 1, :2] = e, f, g
    return corner_st, skewed.astype(np.uint32), maps


def _flat_convex_quad(corners: np.ndarray) -> np.ndarray:
    """(S,) bool: a quad (not a triangle) in one plane, convex (so its bilinear map is one to one)."""
    size = np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)
    area = area_vector(corners)
    with np.errstate(invalid="ignore", divide="ignore"):
        normal = area / np.linalg.norm(area, axis=1, keepdims=True)
    edges = np.roll(corners, -1, axis=1) - corners
    turns = (np.cross(edges, np.roll(edges, -1, axis=1)) * normal[:, None]).sum(axis=2)
    short = np.linalg.norm(edges, axis=2) <= PARALLELOGRAM * size[:, None]  # a triangle's repeated corner
    flat = np.abs(((corners[:, 3] - corners[:, 0]) * normal).sum(axis=1)) <= FLAT * size
    return (np.linalg.norm(area, axis=1) > 0) & flat & ~short.any(axis=1) & (turns > 0).all(axis=1)


def _parallelogram(corners: np.ndarray) -> np.ndarray:
    """(S,) bool: the quad is a parallelogram (so flat, and its bilinear map affine)."""
    size = np.linalg.norm(corners[:, 2] - corners[:, 0], axis=1)
    skew = np.linalg.norm(corners[:, 0] + corners[:, 2] - corners[:, 1] - corners[:, 3], axis=1)
    return (np.linalg.norm(area_vector(corners), axis=1) > 0) & (skew <= PARALLELOGRAM * size)


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
    return {"surfaces": surfaces, "offset": first, "count": counts, "values": values, "keys": unique}, index


def _cells(s_index: np.ndarray, t_index: np.ndarray, columns: np.ndarray):
    """Every table cell each patch covers: (cell index within its surface's table, patch row)."""
    width = s_index[:, 1] - s_index[:, 0]
    height = t_index[:, 1] - t_index[:, 0]
    which, k = expanded_ranges(np.zeros_like(width), np.maximum(width * height, 0))
    i = s_index[which, 0] + k % np.maximum(width[which], 1)
    j = t_index[which, 0] + k // np.maximum(width[which], 1)
    return j * columns[which] + i, which
