"""Item buffers that draw a flat surface (or a triangle's grid triangle) once and find the patch under each
pixel (visibility.item_geometry) must show what drawing every patch shows: the same patch at every pixel
but along shared edges."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import box_faces, surface

from radiosity_addon.core import scene_from_dict, subdivide
from radiosity_addon.core.scene import split_patches
from radiosity_addon.core.scene.geometry import bilinear_each
from radiosity_addon.core.visibility import hemicube, item_geometry as items


def cut_room():
    """A room of rectangular walls, a trapezoid, a two-sided panel and a triangle, split by size and then cut
    off-centre twice (as refinement's outline cuts do), so the patches' rectangles do not line up; the
    triangle's grid triangles are split into triangles and quads."""
    walls = [surface(f"wall{k}", face[::-1], 0.5, 1.0 if k == 0 else 0.0) for k, face in enumerate(box_faces((0, 0, 0), (4, 3, 2.5)))]
    extra = [surface("trapezoid", [[0.5, 0.5, 0.3], [3.0, 0.5, 0.3], [2.5, 2.0, 0.3], [1.0, 2.0, 0.3]], 0.5, 0.0),
             surface("panel", [[1.0, 2.9, 0.5], [1.0, 1.0, 0.5], [1.0, 1.0, 2.0], [1.0, 2.9, 2.0]], 0.5, 0.0),
             surface("triangle", [[3.5, 0.2, 0.1], [3.9, 0.2, 0.1], [3.7, 0.2, 1.5]], 0.5, 0.0)]
    scene = scene_from_dict({"surfaces": walls + extra})
    backs = np.zeros(len(scene), dtype=bool)
    backs[len(walls) + 1] = True  # the panel is seen from both sides
    patches = subdivide(scene, None, 0.6, backs)
    rng = np.random.default_rng(3)
    for _ in range(2):
        mask = rng.random(len(patches)) < 0.3
        patches = split_patches(patches, mask, backs, rng.uniform(0.2, 0.8, (len(patches), 2)))
    return scene, patches


def emulated_inverse_bilinear(geometry: items.ItemGeometry, look: int, plane: np.ndarray) -> np.ndarray:
    """The fragment shader's (s, t) on a skewed quad, in float32, from points (n, 2) in its plane coordinates."""
    e, f = geometry.surfaces[look, 3].view(np.float32).reshape(2, 2)
    g = geometry.surfaces[look, 4, :2].view(np.float32)
    p = plane.astype(np.float32)
    cross = lambda a, b: a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]  # noqa: E731
    k2, k1, k0 = cross(g, f), cross(e, f) + cross(p, g), cross(p, e)
    w = np.sqrt(np.maximum(k1 * k1 - 4 * k0 * k2, 0))
    q = -0.5 * (k1 + np.where(k1 >= 0, w, -w))
    v, other = k0 / q, q / k2
    outside = lambda x: np.abs(x - np.clip(x, 0, 1))  # noqa: E731
    v = np.where(outside(other) < outside(v), other, v)
    d = e + g * v[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):  # the shader divides by the larger component only
        s = np.where(np.abs(d[:, 0]) >= np.abs(d[:, 1]), (p[:, 0] - f[0] * v) / d[:, 0],
                     (p[:, 1] - f[1] * v) / d[:, 1])
    return np.stack([s, v], axis=1)


def emulated_lookup(geometry: items.ItemGeometry, look: int, st: np.ndarray) -> np.ndarray:
    """The fragment shader's table lookup, in numpy, at parameters st (n, 2) of looked-up surface `look`:
    each parameter's uniform bin gives the cut at or below it, or the one before the next."""
    cuts, bins, (table_offset, *_) = geometry.surfaces[look, :3]
    cells = []
    for axis in (0, 1):
        first, count, first_bin, bin_count = cuts[2 * axis], cuts[2 * axis + 1], bins[2 * axis], bins[2 * axis + 1]
        x = st[:, axis].astype(np.float32)
        b = np.clip((x * bin_count).astype(np.int64), 0, bin_count - 1)
        i = geometry.bins[first_bin + b].astype(np.int64)
        step = (i + 2 < count) & (geometry.cuts[first + np.minimum(i + 1, count - 1)] <= x)
        found = i + step
        values = geometry.cuts[first:first + count]
        assert (found == np.clip(np.searchsorted(values, x, side="right") - 1, 0, count - 2)).all()  # = a search
        cells.append(found)
    i, j = cells
    return geometry.table[table_offset + j * (cuts[1] - 1) + i]


def test_every_patch_centre_is_found_in_its_units_table():
    scene, patches = cut_room()
    geometry = items.item_geometry(patches)
    lookup = items.lookup_units(patches)
    looked_up, unit_of = lookup["units"], lookup["unit_of"]
    fronts = np.arange(patches.front_count)
    unit_surface = np.zeros(unit_of.max() + 1, dtype=np.int64)
    unit_surface[unit_of] = patches.surface[fronts]
    # the walls, the panel, the trapezoid (flat, skewed) and the triangle's grid triangles that the random cuts
    # split (it is split 3 x 3 into 9 by size), but not a surface whose cuts come closer than 1 / MAX_BINS
    assert geometry.looked_up == len(looked_up) >= 8
    trapezoid, triangle = len(scene) - 3, len(scene) - 1
    on_triangle = unit_surface[looked_up] == triangle
    split_grid_triangles = np.flatnonzero((unit_surface == triangle) & (np.bincount(unit_of) >= 2))
    assert trapezoid in unit_surface[looked_up] and len(split_grid_triangles) >= 3
    assert set(looked_up[on_triangle]) == set(split_grid_triangles)
    maps = geometry.surfaces[:, 2, 1]
    assert (maps[on_triangle] == items.TRIANGLE_MAP).all() and (maps[~on_triangle] != items.TRIANGLE_MAP).all()
    assert (unit_surface[looked_up][maps == 1] == [trapezoid]).all()
    # a grid triangle's corners are those `subdivide` gave its pieces: every piece lies inside it
    corners = lookup["corners"][on_triangle]
    assert np.allclose(corners[:, 3], corners[:, 2])
    corner_st = geometry.vertices["st"][-4 * len(looked_up):].reshape(-1, 4, 2)
    for look, unit in enumerate(looked_up):
        mine = fronts[unit_of == unit]
        centres = patches.params[mine].mean(axis=1)
        if maps[look] == 1:  # the triangles carry plane coordinates; the shader inverts the bilinear map
            plane = bilinear_each(np.repeat(corner_st[look][None], len(mine), axis=0), centres[:, 0], centres[:, 1])
            found = emulated_inverse_bilinear(geometry, look, plane)
            assert np.abs(found - centres).max() < 1e-5
            centres = found
        elif maps[look] == items.TRIANGLE_MAP:  # barycentric weights of the centre's point; s = w1 / (1 - w2)
            point = bilinear_each(lookup["corners"][look][None].repeat(len(mine), axis=0), centres[:, 0], centres[:, 1])
            c0, c1, c2 = lookup["corners"][look][:3]
            w = np.linalg.lstsq(np.stack([c1 - c0, c2 - c0], axis=1), (point - c0).T, rcond=None)[0].T
            assert np.allclose(bilinear_each(corner_st[look][None].repeat(len(mine), axis=0), centres[:, 0],
                                             centres[:, 1]), w)
            found = np.stack([w[:, 0] / (1 - w[:, 1]), w[:, 1]], axis=1)
            assert np.abs(found - centres).max() < 1e-9
            centres = found
        assert (emulated_lookup(geometry, look, centres) == mine).all()
    # the rest is drawn patch by patch: two triangles a quad, one a triangle; a grid triangle is one
    direct = ~np.isin(unit_of, looked_up)
    drawn = len(geometry.indices) // 3 - np.where(maps == items.TRIANGLE_MAP, 1, 2).sum()
    assert drawn == np.where(patches.is_triangle[fronts][direct], 1, 2).sum()


def test_surfaces_are_looked_up_only_where_they_save_more_triangles_than_a_face_has_pixels():
    _, patches = cut_room()
    everything = items.item_geometry(patches, face_pixels=0)
    assert everything.looked_up == 0
    assert len(everything.indices) // 3 == np.where(patches.is_triangle[:patches.front_count], 1, 2).sum()
    assert items.item_geometry(patches, face_pixels=10).looked_up > 0
    assert items.item_geometry(patches, face_pixels=10 ** 7).looked_up == 0


def test_every_vertex_carries_its_units_record_and_the_others_no_lookup():
    _, patches = cut_room()
    geometry = items.item_geometry(patches)
    record = geometry.vertices["record"]  # (V, 4, 4): what the vertex shader passes on flat
    used = np.unique(geometry.indices)
    own = record[:, 2, 1] == items.OWN_TRIANGLES
    assert 0 < own[used].sum() < len(used)
    carried = items.unit_record(geometry.surfaces)
    # a unit's vertices are its corners: find each looked-up vertex's unit by its record
    units = [np.flatnonzero((carried == record[v]).all(axis=(1, 2))) for v in np.flatnonzero(~own)]
    assert all(len(u) == 1 for u in units)
    unit = np.concatenate(units)
    assert np.array_equal(np.bincount(unit, minlength=geometry.looked_up), np.full(geometry.looked_up, 4))
    # the record's fields where the shader reads them: cuts and bins, (table, map, g), (e, f)
    assert np.array_equal(carried[:, :2], geometry.surfaces[:, :2])
    assert np.array_equal(carried[:, 2, :2], geometry.surfaces[:, 2, :2])
    assert np.array_equal(carried[:, 2, 2:], geometry.surfaces[:, 4, :2])
    assert np.array_equal(carried[:, 3], geometry.surfaces[:, 3])
    assert (geometry.surfaces[:, 2, 1] != items.OWN_TRIANGLES).all()


@pytest.mark.parametrize("resolution", [32, 128])
def test_looked_up_item_buffers_show_the_patches_drawn_one_by_one(gpu, monkeypatch, resolution):
    scene, patches = cut_room()
    rows = np.arange(0, len(patches), max(1, len(patches) // 40))  # fronts and the panel's backs
    frames = tuple(v[rows] for v in hemicube.patch_frames(patches))
    drawn = {}
    for face_pixels in (0, None):  # patch by patch, then every surface that can be looked up
        monkeypatch.setattr(hemicube, "item_geometry",
                            lambda p, face_pixels=None, forced=face_pixels: items.item_geometry(p, forced))
        with gpu.resources() as res:
            atlas = hemicube.HemicubeAtlas(res, patches, resolution, scene.diameter, max_slots=len(rows))
            assert (atlas.looked_up_surfaces > 0) == (face_pixels is None)
            atlas.draw(frames)
            drawn[face_pixels] = np.frombuffer(atlas.item_texture.read(), dtype=np.uint32)
    one_by_one, looked_up = drawn[0].reshape(atlas.atlas_size[1], -1), drawn[None].reshape(atlas.atlas_size[1], -1)
    assert (one_by_one > 0).mean() > 0.5 and np.unique(one_by_one).size > 100
    differ = one_by_one != looked_up
    assert differ.mean() < 2e-3, f"{differ.sum()} of {differ.size} pixels differ"
    # where they differ, an edge moved by a pixel (ties along shared edges and outlines, T-junction cracks):
    # what one drawing shows there, the other shows right beside it
    def beside(image: np.ndarray, shown: np.ndarray) -> np.ndarray:
        padded = np.pad(image, 1)
        y, x = np.nonzero(differ)
        return np.any([padded[y + 1 + dy, x + 1 + dx] == shown
                       for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)
    found = beside(one_by_one, looked_up[differ]) | beside(looked_up, one_by_one[differ])
    # or (patches smaller than a pixel) two patches of one surface that touch each other
    a, b = one_by_one[differ].astype(np.int64) - 1, looked_up[differ].astype(np.int64) - 1
    both = (a >= 0) & (b >= 0) & (a < len(patches)) & (b < len(patches))
    a, b = np.where(both, a, 0), np.where(both, b, 0)
    low, high = patches.corners.min(axis=1) - 1e-6, patches.corners.max(axis=1) + 1e-6
    neighbours = both & (patches.surface[a] == patches.surface[b]) & (low[a] <= high[b]).all(axis=1) & (
        low[b] <= high[a]).all(axis=1)
    assert (found | neighbours).all(), f"{(~(found | neighbours)).sum()} pixels show a patch nowhere near the other's"
