"""Alpha-cut surfaces let light through where their texture says, in every visibility pass, at the
texture's own resolution (scene.opacity, visibility.opacity), checked against rays traced here."""

import numpy as np
import pytest

from radiosity_addon.core import LightmapSettings, OpacityMaps, SolveSettings, bake_lightmaps, load_scene, save_scene, solve
from radiosity_addon.core.scene.face_clusters import cluster_faces
from radiosity_addon.core.scene.load import scene_from_dict
from scenes import grid_triangles, solve_settings, triangle_scene

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

SQUARE_UV = [[0, 0], [1, 0], [1, 1], [0, 1]]
SUN = {"type": "sun", "color": [1, 1, 1], "direction": [0.3, 0.2, -1.0], "strength": np.pi}  # H = cos of its angle


def checker(cells: int, size: int = 60) -> np.ndarray:
    """Alpha 0/1 in `cells` x `cells` squares (row 0 at v = 0), the first square clear."""
    i, j = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    return (((i * cells) // size + (j * cells) // size) % 2).astype(np.float32)


def card_over_floor(alpha: np.ndarray, repeat: float = 1.0, world: bool = False):
    """A 2 x 2 m black floor and, 1 m over it, a black 1 x 1 m card cut out by `alpha` (its UVs
    running to `repeat`, so the texture tiles), lit by the sun (or a white sky): no light bounces."""
    surfaces = [{"name": "floor", "vertices": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                 "reflectance": [0.0] * 3, "emission": [0.0] * 3, "uv": SQUARE_UV},
                {"name": "card", "vertices": [[-0.5, -0.5, 1], [0.5, -0.5, 1], [0.5, 0.5, 1], [-0.5, 0.5, 1]],
                 "reflectance": [0.0] * 3, "emission": [0.0] * 3, "uv": SQUARE_UV}]
    light = {"world": {"color": [1.0, 1.0, 1.0]}} if world else {"lights": [SUN]}
    scene = scene_from_dict({"surfaces": surfaces, **light})
    scene.opacity = OpacityMaps([alpha], np.array([-1, 0]), np.array([np.zeros((4, 2)), np.array(SQUARE_UV) * repeat]))
    return scene


def traced_sun(alpha: np.ndarray, size: int, repeat: float = 1.0, per_texel: int = 8) -> np.ndarray:
    """The floor's light, traced here: each texel's square sampled per_texel² times, each sample's
    ray to the sun crossing the card's plane at z = 1 and passing where the texture's alpha < 0.5."""
    direction = -np.array(SUN["direction"]) / np.linalg.norm(SUN["direction"])
    cosine = direction[2]
    steps = (np.arange(size * per_texel) + 0.5) / (size * per_texel) * 2 - 1
    y, x = np.meshgrid(steps, steps, indexing="ij")
    at = 1.0 / direction[2]
    cx, cy = x + direction[0] * at, y + direction[1] * at
    under = (np.abs(cx) < 0.5) & (np.abs(cy) < 0.5)
    u, v = (cx + 0.5) * repeat % 1.0, (cy + 0.5) * repeat % 1.0
    rows, columns = alpha.shape
    blocked = alpha[np.minimum((v * rows).astype(int), rows - 1), np.minimum((u * columns).astype(int), columns - 1)] >= 0.5
    lit = np.where(under & blocked, 0.0, cosine)
    return lit.reshape(size, per_texel, size, per_texel).mean(axis=(1, 3))


@pytest.mark.parametrize("method", ["progressive", "hemicube"])
@pytest.mark.parametrize("cells, repeat", [(5, 1.0), (3, 2.5)])
def test_light_passes_an_alpha_cut_card_where_its_texture_is_clear(gpu, method, cells, repeat):
    alpha = checker(cells)
    scene = card_over_floor(alpha, repeat)
    solution = solve(scene, SolveSettings.preset("good", method=method), gpu=gpu)
    floor = bake_lightmaps(scene, solution, LightmapSettings.preset("good", texel_density=48), gpu=gpu)["floor"]
    light = floor.rgba[..., 0]
    inside = floor.patch_index >= 0
    traced = traced_sun(alpha, floor.size[0], repeat)
    # the shadow's mean (the share of light let through) as traced, and every texel away from a
    # square's edge exactly; a texel a shadow edge crosses is the mean of 2 x 2 points, not of 64
    shadow = inside & (traced < 0.999 * traced.max())
    assert abs(light[shadow].mean() / traced[shadow].mean() - 1) < 0.03
    whole = inside & ((traced == 0) | (traced == traced.max()))
    assert np.abs(light - traced)[whole].max() < 1e-3
    assert np.abs(light - traced)[inside].max() < 0.55 * traced.max()


def test_the_sky_passes_the_clear_part_of_a_card(gpu):
    """The hemi-cubes of the sky fraction drop the clear texels too: under a card that is clear
    on its left half, a floor point sees the sky through that half."""
    half = np.zeros((8, 8), dtype=np.float32)
    half[:, 4:] = 1.0  # u >= 0.5 opaque
    scene = card_over_floor(half, world=True)
    solid = card_over_floor(np.ones((8, 8), dtype=np.float32), world=True)
    clear = card_over_floor(np.zeros((8, 8), dtype=np.float32), world=True)
    settings = solve_settings(method="hemicube", subdiv=8, hemicube_res=64, hemicube_elements=1)
    under = []
    for case in (solid, scene, clear):
        solution = solve(case, settings, gpu=gpu)
        patches = solution.patches
        floor = (patches.surface == 0) & ~patches.is_back
        middle = floor & (np.linalg.norm(patches.center[:, :2], axis=1) < 0.2)
        under.append(solution.patch_light[middle, 0].mean())
    solid_light, half_light, clear_light = under
    assert solid_light < half_light < clear_light
    # about half of what the card blocks comes through its clear half
    assert abs((half_light - solid_light) / (clear_light - solid_light) - 0.5) < 0.1


def test_a_subdivided_card_keeps_its_cut_out_in_the_cluster_standing_for_it(gpu):
    """A card of 32 x 32 cells clusters into one rectangle whose texture UVs are the card's."""
    alpha = checker(4)
    triangles, uv = grid_triangles([-0.5, -0.5, 1.0], [1, 0, 0], [0, 1, 0], 32)
    floor = ("floor", [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], SQUARE_UV, 0.0, 0.0)
    scene = triangle_scene([("card", triangles, uv, 0.0, 0.0)], quads=[floor], lights=[SUN])
    faces = len(scene)
    index = np.where(scene.object_index == 0, 0, -1)
    scene.opacity = OpacityMaps([alpha], index, np.where((index >= 0)[:, None, None], scene.uv, 0.0))
    clusters = cluster_faces(scene, patch_size=1.0)
    card = np.flatnonzero(clusters.proxies.opacity.index >= 0)
    assert len(card) == 1 and clusters.merged[card].all()
    corners, card_uv = clusters.proxies.corners[card[0]], clusters.proxies.opacity.uv[card[0]]
    np.testing.assert_allclose(card_uv, corners[:, :2] + 0.5, atol=1e-9)  # the card's UVs at its corners
    solution = solve(scene, SolveSettings.preset("good"), gpu=gpu)
    assert solution.report.counts.surfaces == faces and solution.report.counts.clusters >= 1
    floor = bake_lightmaps(scene, solution, LightmapSettings.preset("good", texel_density=48), gpu=gpu)["floor"]
    traced = traced_sun(alpha, floor.size[0])
    inside = floor.patch_index >= 0
    shadow = inside & (traced < 0.999 * traced.max())
    assert abs(floor.rgba[..., 0][shadow].mean() / traced[shadow].mean() - 1) < 0.03
    whole = inside & ((traced == 0) | (traced == traced.max()))
    assert np.abs(floor.rgba[..., 0] - traced)[whole].max() < 1e-3


def test_a_scene_with_opacity_goes_through_its_arrays_file(tmp_path):
    alpha = checker(5)
    scene = card_over_floor(alpha)
    save_scene(scene, tmp_path / "scene.npz")
    again = load_scene(tmp_path / "scene.npz")
    np.testing.assert_array_equal(again.corners, scene.corners)
    np.testing.assert_array_equal(again.opacity.index, scene.opacity.index)
    np.testing.assert_array_equal(again.opacity.uv, scene.opacity.uv)
    np.testing.assert_array_equal(again.opacity.images[0], alpha)
    assert again.lamps[0].type == "sun" and list(again.names) == list(scene.names)
