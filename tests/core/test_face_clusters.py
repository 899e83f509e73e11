"""Small faces are clustered into patch-sized surfaces for the solve (scene.face_clusters): the
solve's size follows the patch size, not the mesh's triangle count, and a clustered mesh bakes
like the surfaces it came from."""

import numpy as np
import pytest

from radiosity_addon.core import LightmapSettings, SolveSettings, bake_lightmaps, solve
from radiosity_addon.core.scene.face_clusters import cluster_faces
from radiosity_addon.core.scene.topology import connected_labels
from scenes import grid_triangles, sphere_triangles, triangle_scene

SQUARE_UV = [[0, 0], [1, 0], [1, 1], [0, 1]]


def plane(n: int, size: float = 1.0, reflectance=0.5):
    triangles, uv = grid_triangles([0, 0, 0], [size, 0, 0], [0, size, 0], n)
    return triangle_scene([("plane", triangles, uv, reflectance, 0.0)])


@pytest.mark.parametrize("n", [16, 64])
def test_a_subdivided_plane_comes_back_as_the_rectangle_it_was(n):
    clusters = cluster_faces(plane(n), patch_size=1.0)
    assert clusters.merged.all() and len(clusters.proxies) == 1
    corners = clusters.proxies.corners[0]
    expected = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    # the same rectangle, whatever corner it starts from, facing the same way
    assert min(np.abs(np.roll(corners, k, axis=0) - expected).max() for k in range(4)) < 1e-9
    assert clusters.proxies.normal[0] @ [0, 0, 1] > 1 - 1e-12


def test_the_surfaces_solved_follow_the_patch_size_not_the_triangles():
    counts = {n: len(cluster_faces(plane(n, size=3.0), patch_size=1.0).proxies) for n in (24, 48, 96)}
    assert counts == {24: 9, 48: 9, 96: 9}  # 3 x 3 rectangles of 1 m, from 1 152 to 18 432 triangles
    assert len(cluster_faces(plane(48, size=3.0), patch_size=0.5).proxies) == 36
    coarse, fine = (cluster_faces(triangle_scene([("ball", *sphere_triangles([0, 0, 0], 0.4, rings), 0.5, 0.0)]),
                                  patch_size=1.0) for rings in (24, 96))
    assert len(fine.faces) > 14 * len(coarse.faces)
    assert 0.7 < len(fine.proxies) / len(coarse.proxies) < 1.4


def test_a_triangle_soup_in_any_order_clusters_as_the_mesh_does():
    triangles, uv = grid_triangles([0, 0, 0], [2, 0, 0], [0, 1, 0], 40, 20)
    rng = np.random.default_rng(3)
    order = rng.permutation(len(triangles))
    turned = np.roll(triangles[order], 1, axis=1)  # every triangle starting from another corner
    mesh = cluster_faces(triangle_scene([("slab", triangles, uv, 0.5, 0.0)]), patch_size=1.0)
    soup = cluster_faces(triangle_scene([("slab", turned, np.roll(uv[order], 1, axis=1), 0.5, 0.0)]), patch_size=1.0)
    assert len(mesh.proxies) == len(soup.proxies) == 2
    centres = lambda c: np.sort(np.round(c.proxies.corners.mean(axis=1), 9), axis=0)  # noqa: E731
    np.testing.assert_allclose(centres(mesh), centres(soup), atol=1e-9)
    # faces of one cluster stay together whatever their order
    np.testing.assert_array_equal(mesh.proxy_of_face[order] == mesh.proxy_of_face[order][0],
                                  soup.proxy_of_face == soup.proxy_of_face[0])


def test_one_object_of_many_materials_clusters_across_them_and_keeps_emitters_apart():
    triangles, uv = grid_triangles([0, 0, 0], [1, 0, 0], [0, 1, 0], 40)
    scene = triangle_scene([("shelf", triangles, uv, 0.5, 0.0)])
    stripe = np.floor(triangles.mean(axis=1)[:, 0] * 20).astype(int)  # 20 materials in stripes 5 cm wide
    scene.reflectance[:] = (0.1 + 0.04 * stripe)[:, None]
    glowing = stripe == 7
    scene.emission[glowing] = 3.0
    clusters = cluster_faces(scene, patch_size=1.0)
    proxies = clusters.proxies
    emits = np.any(proxies.emission > 0, axis=1)
    assert emits.sum() == 1 and (~emits).sum() == 2  # the glowing stripe, and the plane on either side of it
    assert np.all(clusters.proxy_of_face[glowing] == np.flatnonzero(emits)[0])
    np.testing.assert_allclose(proxies.emission[emits][0], 3.0)
    np.testing.assert_allclose(proxies.area[emits][0], 0.05, rtol=1e-9)
    # each side's reflectance is its stripes' mean, weighted by area
    for proxy in np.flatnonzero(~emits):
        members = clusters.proxy_of_face == proxy
        np.testing.assert_allclose(proxies.reflectance[proxy], np.average(scene.reflectance[members], axis=0,
                                                                           weights=scene.area[members]))


def test_a_curved_surface_becomes_rectangles_of_its_area_none_bent_past_its_flatness():
    triangles, uv = grid_triangles([0, 0, 0], [1, 0, 0], [0, 1, 0], 60)
    ball = sphere_triangles([0, 0, 0], 0.4, 64)
    scene = triangle_scene([("ball", *ball, 0.5, 0.0)])
    clusters = cluster_faces(scene, patch_size=1.0)
    proxies, faces = clusters.proxies, clusters.faces
    assert 8 <= len(proxies) <= 80
    # the rectangles hold the faces' projected area: within a few per cent of the sphere's
    assert abs(proxies.area.sum() / (4 * np.pi * 0.4 ** 2) - 1) < 0.08
    # no face turns more than about 50 degrees from its rectangle
    facing = np.einsum("nd,nd->n", faces.normal, proxies.normal[clusters.proxy_of_face])
    assert facing.min() > np.cos(np.radians(55))


def test_a_rough_surface_keeps_its_rectangles_where_a_smooth_one_has_them():
    rng = np.random.default_rng(5)
    heights = rng.normal(0.0, 0.002, (97, 97))  # bumps of 2 mm on faces of 2 cm: normals 15-25 degrees off
    triangles, uv = grid_triangles([0, 0, 0], [2, 0, 0], [0, 2, 0], 96, heights=heights)
    rough = cluster_faces(triangle_scene([("rough", triangles, uv, 0.5, 0.0)]), patch_size=1.0)
    assert len(rough.proxies) == 4
    np.testing.assert_allclose(rough.proxies.area.sum(), 4.0, rtol=0.01)


def room(floor_cells: int) -> object:
    """A 2 x 2 m floor (one quad, or `floor_cells`² cells of two triangles) under a light off its
    centre, beside a wall and a box top: the floor's light bends unevenly."""
    quads = [("wall", [[0, 0, 0], [0, 0, 1.5], [0, 2, 1.5], [0, 2, 0]], [[0, 0], [0, 1], [1, 1], [1, 0]], 0.7, 0.0),
             ("light", [[0.3, 0.3, 1.2], [0.3, 0.8, 1.2], [0.8, 0.8, 1.2], [0.8, 0.3, 1.2]], SQUARE_UV, 0.0, 8.0),
             ("box", [[1.2, 1.2, 0.4], [1.6, 1.2, 0.4], [1.6, 1.6, 0.4], [1.2, 1.6, 0.4]], SQUARE_UV, 0.5, 0.0)]
    if not floor_cells:
        return triangle_scene([], quads + [("floor", [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], SQUARE_UV, 0.6, 0.0)])
    triangles, uv = grid_triangles([0, 0, 0], [2, 0, 0], [0, 2, 0], floor_cells)
    return triangle_scene([("floor", triangles, uv, 0.6, 0.0)], quads)


@pytest.mark.parametrize("quality", ["draft", "final"])
def test_a_subdivided_floor_bakes_like_the_floor_it_came_from(gpu, quality):
    maps = {}
    for cells in (0, 48):
        scene = room(cells)
        solution = solve(scene, SolveSettings.preset(quality), gpu=gpu)
        maps[cells] = bake_lightmaps(scene, solution, LightmapSettings.preset(quality), gpu=gpu)["floor"].rgba
        assert solution.report.counts.clusters == (0 if cells == 0 else {"draft": 4, "final": 16}[quality])
    whole, cut = maps[0], maps[48]
    inside = (whole[..., 3] > 0) & (cut[..., 3] > 0)
    difference = (cut - whole)[..., :3][inside]
    # texel by texel: the direct light (per texel) is the same; the smooth rest is interpolated from the
    # rectangles' elements instead of the quad's patch lattices (measured: 1.5 % draft, 0.6 % final)
    assert np.sqrt((difference ** 2).mean() / (whole[..., :3][inside] ** 2).mean()) < 0.025
    assert np.abs(difference).max() < 0.12 * whole[..., :3][inside].mean()


def union_find_labels(count: int, pairs: np.ndarray) -> np.ndarray:
    """Smallest node per component by a plain union-find: the independent check."""
    parent = list(range(count))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i
    for a, b in pairs:
        ra, rb = root(int(a)), root(int(b))
        parent[max(ra, rb)] = min(ra, rb)
    return np.array([root(i) for i in range(count)])


@pytest.mark.parametrize("seed", range(6))
def test_connected_components_match_a_union_find(seed):
    rng = np.random.default_rng(seed)
    count = int(rng.integers(50, 400))
    pairs = rng.integers(0, count, size=(int(rng.integers(0, count)), 2))
    # a long path too: components whose diameter is far beyond the number of rounds
    path = np.stack([np.arange(count - 1), np.arange(1, count)], axis=1)[rng.random(count - 1) < 0.9]
    pairs = np.concatenate([pairs, path[rng.permutation(len(path))]])
    assert np.array_equal(connected_labels(count, pairs), union_find_labels(count, pairs))


def test_a_bowl_is_cut_into_clusters_that_face_as_its_faces_do():
    """An open hemispherical shell (a bowl, 26 cm across) of small faces: bent, it is cut, and its
    pieces are not joined back into one down-facing rectangle (which saw only the table under it,
    where the bowl's sides see the room): every face stays within 60 degrees of its cluster's normal."""
    triangles, uv = sphere_triangles([0, 0, 0.13], 0.13, 16)
    bowl = triangles[triangles[:, :, 2].mean(axis=1) < 0.13 - 1e-9]  # the lower half, open at the top
    clusters = cluster_faces(triangle_scene([("bowl", bowl, uv[: len(bowl)], 0.5, 0.0)]), patch_size=1.0)
    faces = clusters.faces
    turn = np.einsum("nd,nd->n", faces.normal, clusters.proxies.normal[clusters.proxy_of_face])
    assert clusters.merged.sum() >= 4 and turn.min() > np.cos(np.radians(60.0)), (clusters.merged.sum(), turn.min())
