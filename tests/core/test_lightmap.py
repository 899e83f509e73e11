"""Lightmaps and the preview renderer (issue 4): coverage, gutters, means, continuity, mips, picture.

Two kinds of solutions go through the same baking path: the hemi-cube method's
(one value per patch, S = 1) on the Cornell box, and synthetic element
solutions (S > 1) built here, so the element path is tested without waiting
for a progressive solve.
"""

from __future__ import annotations

import numpy as np
import pytest

from scenes import solve_settings, lightmap_settings

from radiosity_addon import core
from radiosity_addon.core import (SceneError, Solution, SolveError, bilinear,
                                  load_scene, scene_from_dict, solve, subdivide)
from radiosity_addon.core.imaging import dilate
from radiosity_addon.core.lightmap import gl_mip_count
from radiosity_addon.core.lightmap.lattice import lattice_parameters
from radiosity_addon.core.lightmap.size import MIN_SIZE, resolve_size
from radiosity_addon.core.settings import LIGHTMAP_GUTTER as GUTTER

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

CORNELL_DENSITY = 128.0  # texels per metre: 7.8 mm texels
FINE_DENSITY = 256.0  # the demo's density: the smallest Cornell faces (block sides) ~41 texels across


def bake_lightmaps(scene, solution, texel_density=CORNELL_DENSITY, gpu=None, objects=None, **settings):
    """core.bake_lightmaps with this file's defaults (128 texels per metre, up to 2048 texels, B)."""
    # these tests follow the interpolation of B (the direct light per texel is tested in test_texel_light.py)
    settings = {"max_size": 2048, "content": "combined", "direct_per_texel": False, **settings}
    return core.bake_lightmaps(scene, solution, lightmap_settings(texel_density=texel_density, **settings), gpu=gpu,
                               objects=objects)


@pytest.fixture(scope="module")
def cornell():
    return load_scene("cornell-box")


@pytest.fixture(scope="module")
def cornell_solution(cornell, gpu):
    return solve(cornell, solve_settings(method="hemicube", subdiv=4, hemicube_res=64), gpu=gpu)


def element_geometry(patches, elements: int):
    """Element centres (P, S, S, 3) and areas (P, S, S), [patch, t row, s column]."""
    edges = np.arange(elements + 1) / elements
    s, t = np.meshgrid(edges, edges)
    corners = bilinear(patches.corners, s, t)  # (P, S+1, S+1, 3)
    c0, c1, c2, c3 = corners[:, :-1, :-1], corners[:, :-1, 1:], corners[:, 1:, 1:], corners[:, 1:, :-1]
    areas = 0.5 * np.linalg.norm(np.cross(c2 - c0, c3 - c1), axis=-1)
    middle = (np.arange(elements) + 0.5) / elements
    s, t = np.meshgrid(middle, middle)
    return bilinear(patches.corners, s, t), areas


def synthetic_element_solution(scene, subdiv: int, elements: int, values) -> Solution:
    """A Solution whose element radiosity is values(centres (P,S,S,3), surface (P,)) -> (P,S,S,3)."""
    patches = subdivide(scene, subdiv)
    centres, areas = element_geometry(patches, elements)
    element_radiosity = values(centres, patches.surface)
    patch_radiosity = (element_radiosity * areas[..., None]).sum(axis=(1, 2)) / areas.sum(axis=(1, 2))[:, None]
    return Solution(patches=patches, patch_radiosity=patch_radiosity, element_radiosity=element_radiosity)


def smooth_field(centres, group):
    """A smooth, positive, coloured field with a level per group (objects differ, as in a real solve;
    within a chart the field must be continuous, as radiosity is across a flat shared edge)."""
    x, y, z = centres[..., 0], centres[..., 1], centres[..., 2]
    level = 0.2 + 0.1 * (group % 5)[:, None, None]
    red = level * (1 + 0.8 * np.sin(6 * x) * np.cos(4 * z) + 0.5 * y)
    green = level * (1.2 + 0.5 * np.cos(5 * y + 2 * x))
    blue = level * (0.8 + 0.6 * x * z + 0.3 * np.sin(7 * z))
    return np.stack([red, green, blue], axis=-1)


@pytest.fixture(scope="module")
def cornell_bakes(cornell, cornell_solution, gpu):
    """(name, solution, lightmaps): the hemi-cube solve and a synthetic S = 4 element solution at the
    default density, then both at the demo's density, then the hemi-cube solve at a coarse one."""
    object_of_surface = np.array([cornell.objects.index(s.object_name) for s in cornell.surfaces])
    elements = synthetic_element_solution(cornell, subdiv=3, elements=4,
                                          values=lambda c, surface: smooth_field(c, object_of_surface[surface]))
    return [
        ("hemicube", cornell_solution, bake_lightmaps(cornell, cornell_solution, CORNELL_DENSITY, gpu=gpu)),
        ("elements", elements, bake_lightmaps(cornell, elements, CORNELL_DENSITY, gpu=gpu)),
        ("hemicube fine", cornell_solution, bake_lightmaps(cornell, cornell_solution, FINE_DENSITY, gpu=gpu)),
        ("elements fine", elements, bake_lightmaps(cornell, elements, FINE_DENSITY, gpu=gpu)),
        ("coarse", cornell_solution, bake_lightmaps(cornell, cornell_solution, 24.0, gpu=gpu)),
    ]


def texel_centres(size):
    width, height = size
    x, y = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    return np.stack([x, y], axis=-1)  # (H, W, 2) in texels, row 0 at v = 0


def polygon_distance_at_most(points, polygon, limit):
    """True where the max-norm distance from a point to the convex polygon is <= limit (texels):
    separating axes of the square of half-width `limit` around the point and the polygon."""
    near = np.ones(points.shape[:-1], dtype=bool)
    axes = [np.array([1.0, 0.0]), np.array([0.0, 1.0])]
    edges = np.roll(polygon, -1, axis=0) - polygon
    axes += [np.array([e[1], -e[0]]) / np.linalg.norm(e) for e in edges if np.linalg.norm(e) > 1e-12]
    for axis in axes:
        projected = polygon @ axis
        centre = points @ axis
        reach = limit * (abs(axis[0]) + abs(axis[1]))
        near &= (centre + reach >= projected.min() - 1e-9) & (centre - reach <= projected.max() + 1e-9)
    return near


# --- coverage and gutters --------------------------------------------------------------------

def test_no_uncovered_texel_inside_footprints_or_their_two_texel_gutters(cornell, cornell_bakes):
    for label, solution, lightmaps in cornell_bakes:
        for name, lightmap in lightmaps.items():
            centres = texel_centres(lightmap.size)
            covered = lightmap.rgba[..., 3] > 0
            for index, uv in zip(lightmap.surfaces, lightmap.surface_uv):
                polygon = uv * np.asarray(lightmap.size)
                inside = polygon_distance_at_most(centres, polygon, 0.0)
                gutter = polygon_distance_at_most(centres, polygon, GUTTER)
                where = f"{label}: {cornell.surfaces[index].name}"
                assert inside.sum() > 0, f"{where}: no texel centre inside the face"
                assert covered[gutter].all(), f"{where}: {np.count_nonzero(~covered[gutter])} texels uncovered"
                owner = lightmap.patch_index[inside]
                assert (owner >= 0).all(), f"{where}: texel centres inside the face hold no patch"
                values = lightmap.rgba[gutter][:, :3]
                assert np.isfinite(values).all() and (values >= 0).all()


def test_charts_keep_their_gutters_apart(cornell, cornell_bakes):
    """Texels inside different charts are more than two gutters apart, so no gutter overwrites
    another chart's texels (the layout's margins are >= gutter + the grazed texel)."""
    _, solution, lightmaps = cornell_bakes[0]
    for name in ("tall_block", "short_block"):  # five charts each
        lightmap = lightmaps[name]
        surface = np.where(lightmap.patch_index >= 0, solution.patches.surface[lightmap.patch_index], -1)
        indices = sorted(lightmap.surfaces)
        for a in indices:
            _, grown = dilate(np.zeros(surface.shape + (1,)), surface == a, 2 * GUTTER)
            for b in indices:
                if b != a:
                    assert not (grown & (surface == b)).any(), f"{name}: charts {a} and {b} too close"


def test_thin_faces_still_get_texels(gpu):
    """A sliver far thinner than a texel in its own chart is not an empty (black) map."""
    scene = scene_from_dict({"surfaces": [
        {"name": "sliver", "vertices": [[0, 0, 0], [1, 0, 0], [1, 0.002, 0]],
         "reflectance": [0.5] * 3, "emission": [1, 1, 1]},
    ]})
    solution = synthetic_element_solution(scene, 2, 2, lambda c, s: np.ones(c.shape))
    lightmap = bake_lightmaps(scene, solution, texel_density=32, gpu=gpu)["sliver"]
    covered = lightmap.rgba[..., 3] > 0
    assert covered.sum() >= 32 and np.allclose(lightmap.rgba[covered][:, :3], 1.0, atol=1e-5)


# --- values ------------------------------------------------------------------------------------

def test_face_texel_means_match_area_weighted_radiosity(cornell, cornell_bakes):
    """Per face, the mean of its texels (equal world areas under the automatic layout) equals
    the area-weighted radiosity of its elements within 1 %, at the demo's 256 texels/m. Texels
    sample the map at their centres, so the error scales like (texels along the border / texels
    inside) x the border's contrast: at 128 texels/m the darkest block side (21 texels across)
    is 1.5 % off, at 256 texels/m every face is within 0.8 %."""
    for label, solution, lightmaps in cornell_bakes[2:4]:
        values = solution.element_radiosity
        elements = 1 if values is None else values.shape[1]
        _, areas = element_geometry(solution.patches, elements)
        if values is None:
            values = solution.patch_radiosity[:, None, None, :]
        for name, lightmap in lightmaps.items():
            owner = lightmap.patch_index
            for index in lightmap.surfaces:
                mine = solution.patches.surface == index
                expected = (values[mine] * areas[mine][..., None]).sum(axis=(0, 1, 2)) / areas[mine].sum()
                texels = (owner >= 0) & (solution.patches.surface[np.maximum(owner, 0)] == index)
                measured = lightmap.rgba[texels][:, :3].mean(axis=0)
                error = np.abs(measured - expected) / np.maximum(expected, 1e-3 * expected.max())
                assert error.max() < 0.01, (f"{label}: {cornell.surfaces[index].name}: texel mean"
                                            f" {measured} vs {expected}")


TWO_TILES = {"surfaces": [  # two unit quads sharing the edge x = 1, laid side by side in one UV chart
    {"name": "left", "object": "tiles", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
     "reflectance": [0.5] * 3, "emission": [1, 1, 1], "uv": [[0.05, 0.3], [0.5, 0.3], [0.5, 0.75], [0.05, 0.75]]},
    {"name": "right", "object": "tiles", "vertices": [[1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0]],
     "reflectance": [0.5] * 3, "emission": [0, 0, 0], "uv": [[0.5, 0.3], [0.95, 0.3], [0.95, 0.75], [0.5, 0.75]]},
]}


def test_values_are_continuous_across_patch_and_face_borders(gpu):
    """The bound: the map is the bilinear interpolant of element centres and border points whose
    values are the mean of both sides, so crossing a border is linear from one element centre
    to the other: the step between the two texels straddling the border equals the step between
    neighbouring texels on either side (same slope), up to the bilinear twist along the border —
    |v_b - v_a| <= 1.25 max(|v_a - v_a'|, |v_b' - v_b|) + 1e-4, with a' beyond a and b' beyond b.
    Random element values make every border a potential step of ~0.5; a map that showed the
    patches' own values (no averaging) would break the bound by far, which is checked too."""
    scene = scene_from_dict(TWO_TILES)
    rng = np.random.default_rng(4)
    solution = synthetic_element_solution(scene, subdiv=2, elements=4,
                                          values=lambda c, s: rng.uniform(0.1, 1.0, c.shape))
    lightmap = bake_lightmaps(scene, solution, texel_density=100, gpu=gpu)["tiles"]
    assert lightmap.size == (224, 224)  # 100 texels/unit over 0.45 uv per unit: 222 -> multiple of 8
    value, owner = lightmap.rgba[..., :3].astype(np.float64), lightmap.patch_index
    own = own_element_values(solution, lightmap)
    steps, bounds, raw_jumps = [], [], []
    for axis in (0, 1):
        v, o, e = (np.moveaxis(x, axis, 0) for x in (value, owner, own))
        a, b = slice(1, -2), slice(2, -1)  # a and b straddle a border where their owners differ
        before, after = slice(0, -3), slice(3, None)
        crossing = (o[a] >= 0) & (o[b] >= 0) & (o[a] != o[b]) & (o[before] == o[a]) & (o[after] == o[b])
        step = np.abs(v[b] - v[a]).max(axis=-1)
        side = np.maximum(np.abs(v[a] - v[before]), np.abs(v[after] - v[b])).max(axis=-1)
        steps.append(step[crossing])
        bounds.append(1.25 * side[crossing] + 1e-4)
        raw_jumps.append(np.abs(e[b] - e[a]).max(axis=-1)[crossing])
    steps, bounds, raw_jumps = map(np.concatenate, (steps, bounds, raw_jumps))
    assert len(steps) > 200  # every patch border of both faces is crossed many times
    assert (steps <= bounds).all(), f"{np.count_nonzero(steps > bounds)} steps exceed the bound"
    assert np.median(raw_jumps) > 5 * np.median(bounds)  # the bound would catch a step


def own_element_values(solution, lightmap):
    """(H, W, 3): the value of the element holding each texel centre in its own patch (what a map
    without continuity would show); the two-tiles patches are axis-aligned rectangles in UV."""
    width, height = lightmap.size
    rows, cols = np.indices((height, width))
    patch = np.maximum(lightmap.patch_index, 0)
    uv = np.stack([(cols + 0.5) / width, (rows + 0.5) / height], axis=-1)
    low, high = solution.patches.uv[patch, 0], solution.patches.uv[patch, 2]
    st = (uv - low) / (high - low)
    elements = solution.element_radiosity.shape[1]
    i, j = np.moveaxis(np.clip((st * elements).astype(int), 0, elements - 1), -1, 0)
    return solution.element_radiosity[patch, j, i]


TWO_ISLANDS = {"surfaces": [  # the same two quads, each its own UV island (as Blender's Lightmap Pack does)
    {**TWO_TILES["surfaces"][0], "uv": [[0.05, 0.3], [0.48, 0.3], [0.48, 0.73], [0.05, 0.73]]},
    {**TWO_TILES["surfaces"][1], "uv": [[0.52, 0.3], [0.95, 0.3], [0.95, 0.73], [0.52, 0.73]]},
]}


def test_values_are_continuous_across_a_flat_edge_between_uv_islands(gpu):
    """Each face its own island: the texels nearest the shared edge on either island (half a texel
    from it, edges on texel borders at 200 x 200) differ no more than neighbouring texels allow,
    as across a border inside a chart (see the test above)."""
    scene = scene_from_dict(TWO_ISLANDS)
    rng = np.random.default_rng(5)
    solution = synthetic_element_solution(scene, subdiv=2, elements=4,
                                          values=lambda c, s: rng.uniform(0.1, 1.0, c.shape))
    lightmap = bake_lightmaps(scene, solution, resolution_overrides={"tiles": 200}, gpu=gpu)["tiles"]
    value = lightmap.rgba[..., :3].astype(np.float64)
    rows = np.arange(61, 145)  # v in (0.305, 0.725): inside both islands
    a, a2, b, b2 = value[rows, 95], value[rows, 94], value[rows, 104], value[rows, 105]
    assert (lightmap.patch_index[rows, 95] >= 0).all() and (lightmap.patch_index[rows, 104] >= 0).all()
    step = np.abs(b - a).max(axis=1)
    bound = 1.25 * np.maximum(np.abs(a - a2), np.abs(b2 - b)).max(axis=1) + 1e-4
    assert (step <= bound).all(), f"{np.count_nonzero(step > bound)} rows step across the edge"


@pytest.mark.parametrize("bend_degrees, averaged", [(90.0, False), (20.0, True)])
def test_creases_keep_their_own_values_and_smooth_bends_share_them(gpu, bend_degrees, averaged):
    """A floor (value 1) and a wall (value 3) of one object meeting at an edge: at a 90° crease
    each keeps its own value (light really differs there); bent by only 20° they meet halfway."""
    bend = np.radians(bend_degrees)
    top = [1 + np.cos(bend), np.sin(bend), 0]  # the second face rises from the edge x = 1
    scene = scene_from_dict({"surfaces": [
        {"name": "floor", "object": "bent", "vertices": [[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]],
         "reflectance": [0.5] * 3, "emission": [1, 1, 1]},
        {"name": "wall", "object": "bent", "vertices": [[1, 0, 0], top, [top[0], top[1], -1], [1, 0, -1]],
         "reflectance": [0.5] * 3, "emission": [0, 0, 0]},
    ]})
    solution = synthetic_element_solution(scene, 2, 2, lambda c, s: np.ones(c.shape) * (1 + 2 * s)[:, None, None, None])
    lightmap = bake_lightmaps(scene, solution, texel_density=40, gpu=gpu)["bent"]
    inside = lightmap.patch_index >= 0
    surface = solution.patches.surface[lightmap.patch_index[inside]]
    values = lightmap.rgba[inside][:, 0]
    if averaged:
        assert values[surface == 0].max() > 1.5 and values[surface == 1].min() < 2.5
    else:
        assert np.allclose(values[surface == 0], 1.0) and np.allclose(values[surface == 1], 3.0)


def test_lattice_border_points_sit_on_patch_edges():
    params = lattice_parameters(4)
    assert params[0] == 0 and params[-1] == 1 and np.allclose(params[1:-1], [0.125, 0.375, 0.625, 0.875])


# --- mip chain -----------------------------------------------------------------------------

def covered_mean(rgba, coverage):
    """Mean radiance over a level's charts, each texel weighted by the fraction of it on charts."""
    return (rgba[..., :3] * coverage[..., None]).sum(axis=(0, 1)) / coverage.sum()


def test_every_mip_level_keeps_the_covered_mean(cornell, cornell_solution, cornell_bakes, gpu):
    """Coverage-aware levels: each level's covered mean equals level 0's within 1 %, and gutters
    stay filled at every level. The test would catch a plain box filter of the padded image
    (what generated mipmaps do): past the gutter's reach it pulls chart borders toward black,
    which is checked to move some object's mean by more than 1 %."""
    power_of_two = bake_lightmaps(cornell, cornell_solution, CORNELL_DENSITY, power_of_two=True, gpu=gpu)
    box_filter_errors = []
    for label, lightmaps in (("hemicube", cornell_bakes[0][2]), ("elements", cornell_bakes[1][2]),
                             ("power of two", power_of_two)):
        for name, lightmap in lightmaps.items():
            assert len(lightmap.levels) >= 4, f"{label}: {name}: chain too short"
            base = covered_mean(lightmap.levels[0], lightmap.coverage[0])
            box = lightmap.levels[0]
            for k, (level, coverage) in enumerate(zip(lightmap.levels, lightmap.coverage)):
                assert level.shape[:2] == coverage.shape
                error = np.abs(covered_mean(level, coverage) - base) / np.maximum(base, 1e-3 * base.max())
                assert error.max() < 0.01, f"{label}: {name} level {k}: {covered_mean(level, coverage)} vs {base}"
                _, ring = dilate(np.zeros(coverage.shape + (1,)), coverage > 0, GUTTER)
                assert (level[..., 3][ring] > 0).all(), f"{label}: {name} level {k}: gutter not filled"
                if 0 < k < gl_mip_count(lightmap.levels):  # sizes GL's generated mipmaps would have
                    h, w = box.shape[0] // 2, box.shape[1] // 2
                    box = box[:2 * h, :2 * w].reshape(h, 2, w, 2, 4).mean(axis=(1, 3))
                    box_error = np.abs(covered_mean(box, coverage) - base) / np.maximum(base, 1e-3 * base.max())
                    box_filter_errors.append(box_error.max())
    assert max(box_filter_errors) > 0.01
    for lightmap in power_of_two.values():
        assert lightmap.levels[-1].shape[:2] == (1, 1)
        assert gl_mip_count(lightmap.levels) == len(lightmap.levels)  # powers of two: GL's sizes all the way
    for lightmap in cornell_bakes[0][2].values():
        assert lightmap.levels[-1].shape[:2] == (1, 1) and gl_mip_count(lightmap.levels) >= 4


# --- resolution --------------------------------------------------------------------------

def test_resolution_follows_density_override_cap_and_power_of_two(cornell, cornell_solution, gpu):
    assert resolve_size((150, 101), None, 2048, False, "x") == (152, 104)
    assert resolve_size((150, 101), None, 2048, True, "x") == (256, 128)
    assert resolve_size((150, 101), None, 100, False, "x") == (100, 100)
    assert resolve_size((150, 101), (64, 32), 2048, False, "x") == (64, 32)
    assert resolve_size((150, 101), 300, 256, True, "x") == (256, 256)
    with pytest.raises(SolveError, match="at least"):
        resolve_size((150, 101), MIN_SIZE - 1, 2048, False, "x")
    maps = bake_lightmaps(cornell, cornell_solution, 64.0, resolution_overrides={"floor": 200, "light": (32, 16)},
                          max_size=128, gpu=gpu)
    assert maps["floor"].size == (128, 128) and maps["light"].size == (32, 16)
    for name in ("back_wall", "tall_block"):  # at least the density asked for; rounding sizes up adds some
        assert 0.98 * 64 < maps[name].texel_density < 1.25 * 64
    with pytest.raises(SolveError, match="no object 'nope'"):
        bake_lightmaps(cornell, cornell_solution, resolution_overrides={"nope": 64}, gpu=gpu)
    with pytest.raises(SolveError, match="do not fit"):  # five charts with their margins need more than 8 x 8
        bake_lightmaps(cornell, cornell_solution, resolution_overrides={"tall_block": 8}, gpu=gpu)


def test_only_the_objects_asked_for_are_baked(cornell, cornell_solution, gpu):
    """Objects that only occlude (a Blender bake of selected objects) need no lightmap."""
    maps = bake_lightmaps(cornell, cornell_solution, CORNELL_DENSITY, objects=["floor", "light"], gpu=gpu)
    assert sorted(maps) == ["floor", "light"]
    everything = bake_lightmaps(cornell, cornell_solution, CORNELL_DENSITY, gpu=gpu)
    assert np.array_equal(maps["floor"].rgba, everything["floor"].rgba)
    with pytest.raises(SolveError, match="no object 'nope'"):
        bake_lightmaps(cornell, cornell_solution, objects=["floor", "nope"], gpu=gpu)


def test_given_uvs_are_used_and_mixed_uvs_refused(gpu):
    scene = scene_from_dict(TWO_TILES)
    solution = synthetic_element_solution(scene, 1, 1, lambda c, s: np.ones(c.shape))
    lightmap = bake_lightmaps(scene, solution, texel_density=100, gpu=gpu)["tiles"]
    assert np.allclose(lightmap.surface_uv[1], TWO_TILES["surfaces"][1]["uv"])
    inside = lightmap.patch_index >= 0
    rows, cols = np.nonzero(inside)
    assert abs(cols.min() - 0.05 * 224) <= 1 and abs(cols.max() + 1 - 0.95 * 224) <= 1
    mixed = {"surfaces": [dict(TWO_TILES["surfaces"][0]), {**TWO_TILES["surfaces"][1], "uv": None}]}
    with pytest.raises(SceneError, match="no lightmap 'uv'"):
        bake_lightmaps(scene_from_dict(mixed), solution, gpu=gpu)


def test_a_face_collapsed_in_uv_space_leaves_no_nan(gpu):
    collapsed = {"surfaces": [TWO_TILES["surfaces"][0],
                              {**TWO_TILES["surfaces"][1], "uv": [[0.7, 0.8]] * 4}]}
    scene = scene_from_dict(collapsed)
    solution = synthetic_element_solution(scene, 2, 2, lambda c, s: np.ones(c.shape))
    lightmap = bake_lightmaps(scene, solution, texel_density=50, gpu=gpu)["tiles"]
    assert np.isfinite(lightmap.rgba).all()
    assert np.allclose(lightmap.rgba[lightmap.rgba[..., 3] > 0][:, :3], 1.0, atol=1e-5)
