"""Direct light per lightmap texel: an emitter's light at every texel against Lambert's exact
formula, and a sun's shadow as sharp as the lightmap, texel by texel against a ray cast. A texel
holds the mean over its square (as Cycles bakes one), not the value at its centre."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import box_faces, lightmap_settings, solve_settings, surface

from radiosity_addon.core import (bake_lightmaps, point_to_polygon,
                                  scene_from_dict, solve, subdivide)
from radiosity_addon.core.lightmap.direct import direct_light, matched_map_resolution

FLOOR = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
UV = [[0, 0], [1, 0], [1, 1], [0, 1]]


def texel_centres(size, corners):
    """World points of the texel centres of a lightmap of `size` on the planar quad `corners` with
    the unit UV square (row 0 at v = 0)."""
    width, height = size
    v, u = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    c = np.asarray(corners, dtype=float)
    return (c[0] * ((1 - u) * (1 - v))[..., None] + c[1] * (u * (1 - v))[..., None]
            + c[2] * (u * v)[..., None] + c[3] * ((1 - u) * v)[..., None])


def texel_means(size, corners, value, samples: int = 6):
    """The mean of `value` (points (..., 3) -> (...)) over each texel's square: a midpoint rule
    of samples x samples points per texel."""
    width, height = size
    fine = value(texel_centres((width * samples, height * samples), corners))
    return fine.reshape(height, samples, width, samples).mean(axis=(1, 3))


@pytest.mark.parametrize("method", ["progressive", "hemicube"])
def test_an_emitters_light_at_every_texel_is_lamberts_formula(gpu, method):
    """A 0.5 m square emitter 0.4 m above a 2 m floor: the light at each texel (content light) is
    E · F(texel -> emitter), whatever the patches (one 2 m patch here)."""
    emitter_corners = [[0.75, 0.75, 0.4], [0.75, 1.25, 0.4], [1.25, 1.25, 0.4], [1.25, 0.75, 0.4]]
    floor = {**surface("floor", FLOOR, 0.5, 0.0), "uv": UV}
    emitter = {**surface("emitter", emitter_corners, 0.0, 2.0), "uv": UV}
    scene = scene_from_dict({"surfaces": [floor, emitter]})
    settings = solve_settings(method=method, subdiv=1, elements=1, hemicube_res=32, tolerance=1e-4)
    solution = solve(scene, settings, gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16), gpu=gpu)["floor"]
    inside = lightmap.patch_index >= 0
    lambert = lambda points: 2.0 * point_to_polygon(  # noqa: E731
        points.reshape(-1, 3), np.tile([0, 0, 1.0], (points[..., 0].size, 1)),
        np.asarray(emitter_corners)[None])[:, 0].reshape(points.shape[:-1])
    exact = texel_means(lightmap.size, FLOOR, lambert)[inside]
    measured = lightmap.rgba[inside][:, 0]
    assert exact.max() > 0.5
    # where the light is smooth a texel holds its centre's value, within half a per cent of its
    # mean (lightmap.direct.SHARP_CONTRAST)
    np.testing.assert_allclose(measured, exact, rtol=5e-3, atol=1e-4 * exact.max())


def test_a_suns_shadow_is_as_sharp_as_the_lightmap(gpu):
    """A sun straight down on a floor under a 0.5 m x 0.5 m plate (its own patch): texels whose
    centres lie under the plate are dark, the others lit by S cos/π... texel by texel, where a
    patch-sized answer would blur the edge over a whole 1 m patch."""
    plate = [[0.6, 0.6, 0.5], [1.1, 0.6, 0.5], [1.1, 1.1, 0.5], [0.6, 1.1, 0.5]]  # facing up
    sun = {"name": "sun", "type": "sun", "direction": [0, 0, -1], "color": [1, 1, 1], "strength": 3.0}
    data = {"surfaces": [{**surface("floor", FLOOR, 0.5, 0.0), "uv": UV},
                         {**surface("plate", plate, 0.5, 0.0), "uv": UV}], "lights": [sun]}
    scene = scene_from_dict(data)
    solution = solve(scene, solve_settings(subdiv=2, elements=2, tolerance=1e-3), gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, lightmap_settings(texel_density=32), gpu=gpu)["floor"]
    inside = lightmap.patch_index >= 0
    points = texel_centres(lightmap.size, FLOOR)
    shadowed = (points[..., 0] > 0.6) & (points[..., 0] < 1.1) & (points[..., 1] > 0.6) & (points[..., 1] < 1.1)
    light = lightmap.rgba[..., 0]
    lit_value = 3.0 / np.pi
    # a texel whose centre is within half a texel of the edge may go either way
    half = 0.5 / 32
    near_edge = np.zeros_like(shadowed)
    for axis in (0, 1):
        for edge in (0.6, 1.1):
            near_edge |= np.abs(points[..., axis] - edge) < half * 1.01
    clear = inside & ~near_edge
    direct = light - light[clear & shadowed].mean()  # the shadow keeps the (smooth) indirect light
    assert np.all(np.abs(direct[clear & ~shadowed] - lit_value) < 0.05 * lit_value + 0.05)
    assert light[clear & shadowed].max() < 0.1 * lit_value
    assert (clear & shadowed).sum() > 200
    # a texel the shadow's edge crosses holds its lit share (not its centre's all or nothing);
    # 4 x 4 points per texel resolve a share to an eighth
    lit_share = texel_means(lightmap.size, FLOOR, lambda p: ~(
        (p[..., 0] > 0.6) & (p[..., 0] < 1.1) & (p[..., 1] > 0.6) & (p[..., 1] < 1.1)), samples=40)
    crossed = inside & (lit_share > 0.1) & (lit_share < 0.9)
    assert crossed.sum() > 20
    assert np.all(np.abs(direct[crossed] - lit_value * lit_share[crossed]) < 0.15 * lit_value + 0.05)


def occluded_emitter_light(points, emitter_corners, emission, box_low, box_high, samples=48):
    """E ∫ cos cos / (π r²) V dA over a downward-facing square emitter, V by ray casting against an
    axis-aligned box (midpoint rule, samples² points): the independent reference."""
    c = np.asarray(emitter_corners, dtype=float)
    s = (np.arange(samples) + 0.5) / samples
    u, v = np.meshgrid(s, s, indexing="ij")
    on = (c[0] + (c[3] - c[0]) * u.reshape(-1, 1) + (c[1] - c[0]) * v.reshape(-1, 1))  # (N, 3)
    area = np.linalg.norm(np.cross(c[3] - c[0], c[1] - c[0])) / len(on)
    light = np.zeros(len(points))
    for start in range(0, len(points), 256):
        p = points[start:start + 256, None, :]  # (n, 1, 3)
        d = on[None] - p  # to the emitter
        r2 = (d ** 2).sum(axis=-1)
        cosines = d[..., 2] ** 2 / r2  # floor normal +z, emitter normal -z: both d_z / r
        with np.errstate(divide="ignore", invalid="ignore"):  # slab test of the segment against the box
            t0, t1 = (box_low - p) / d, (box_high - p) / d
        enter = np.nanmax(np.minimum(t0, t1), axis=-1)
        leave = np.nanmin(np.maximum(t0, t1), axis=-1)
        hidden = (enter < leave) & (leave > 1e-9) & (enter < 1.0)
        light[start:start + 256] = emission * (cosines / (np.pi * r2) * ~hidden).sum(axis=1) * area
    return light


@pytest.mark.parametrize("method", ["progressive", "hemicube"])
def test_no_light_leaks_under_a_box_and_its_penumbra_is_texel_sharp(gpu, method):
    """A black 0.4 m box standing on the floor under a 0.5 m emitter: the floor under the box gets
    nothing, and every texel around it — the contact line, the penumbra — matches a ray-cast
    reference (the floor's one 2 m patch could not show any of it)."""
    low, high = np.array([0.8, 0.8, 0.0]), np.array([1.2, 1.2, 0.4])
    emitter_corners = [[0.75, 0.75, 1.5], [0.75, 1.25, 1.5], [1.25, 1.25, 1.5], [1.25, 0.75, 1.5]]
    surfaces = ([{**surface("floor", FLOOR, 0.5, 0.0), "uv": UV}]
                + [surface(f"box {k}", corners, 0.0, 0.0, obj="box") for k, corners in enumerate(box_faces(low, high))]
                + [surface("emitter", emitter_corners, 0.0, 10.0)])
    scene = scene_from_dict({"surfaces": surfaces})
    solution = solve(scene, solve_settings(method=method, subdiv=1, elements=2, hemicube_res=64, refinements=0),
                     gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, lightmap_settings(texel_density=64), gpu=gpu)["floor"]
    inside = lightmap.patch_index >= 0
    points = texel_centres(lightmap.size, FLOOR)[inside]
    measured = lightmap.rgba[inside][:, 0]
    exact = occluded_emitter_light(points, emitter_corners, 10.0, low, high)
    from_box = np.maximum(np.abs(points[:, 0] - 1.0), np.abs(points[:, 1] - 1.0)) - 0.2  # > 0 outside it
    under = from_box < -1.0 / 64
    contact = (from_box > 0) & (from_box < 0.05)
    assert under.sum() > 300 and contact.sum() > 300
    assert measured[under].max() <= 1e-3 * exact.max()  # nothing leaks under the box
    # the contact line and the penumbra, texel by texel (one texel's width of a sharp edge aside)
    assert exact[contact].mean() < 0.8 * exact[from_box > 0.5].mean()  # the box does shade its foot
    np.testing.assert_allclose(measured[contact].mean(), exact[contact].mean(), rtol=0.03)
    outside = from_box > 1.5 / 64
    relative_rms = np.sqrt(((measured - exact)[outside] ** 2).mean() / (exact[outside] ** 2).mean())
    assert relative_rms < 0.02


def test_the_solves_own_direct_light_keeps_penumbrae_and_leaks_nowhere(gpu):
    """What the solve's bounces start from: the direct light of the box scene above at the floor's
    element centres (progressive, 0.5 m patches of 8 x 8 elements, the emitter one patch), against
    the ray-cast reference. The emitter shoots in pieces, each with its own hemi-cube, and an
    element behind what its pixel shows is hidden: the floor's total is right to 1.5 % and its
    relative RMS is 2.8 % (shot from the emitter's centre it was 25 %: hard shadows)."""
    from radiosity_addon.core.shooting import element_areas, element_centers

    low, high = np.array([0.8, 0.8, 0.0]), np.array([1.2, 1.2, 0.4])
    box = [surface(f"box {k}", c, 0.0, 0.0, obj="box") for k, c in enumerate(box_faces(low, high))]
    emitter_corners = [[0.75, 0.75, 1.0], [0.75, 1.25, 1.0], [1.25, 1.25, 1.0], [1.25, 0.75, 1.0]]
    scene = scene_from_dict({"surfaces": [surface("floor", FLOOR, 0.0, 0.0), *box,
                                          surface("emitter", emitter_corners, 0.0, 10.0)]})
    solution = solve(scene, solve_settings(patch_size=0.5, elements=8, refinements=0), gpu=gpu)
    floor = np.flatnonzero(solution.patches.surface == 0)
    points = element_centers(solution.patches, 8)[floor].reshape(-1, 3)
    areas = element_areas(solution.patches, 8)[floor].reshape(-1)
    measured = solution.element_direct[floor].reshape(-1, 3)[:, 0]
    exact = occluded_emitter_light(points, emitter_corners, 10.0, low, high)
    under = np.all((points[:, :2] > low[:2] + 0.02) & (points[:, :2] < high[:2] - 0.02), axis=1)
    assert under.sum() > 30 and measured[under].max() == 0.0  # nothing reaches under the box
    assert (areas * measured).sum() == pytest.approx((areas * exact).sum(), rel=0.015)
    relative_rms = np.sqrt((areas * (measured - exact) ** 2).sum() / (areas * exact ** 2).sum())
    assert relative_rms < 0.05


@pytest.mark.parametrize("method", ["hemicube", "progressive"])
def test_the_light_trapped_over_an_emitters_back_is_counted_once(gpu, method):
    """A 0.4 m two-sided emitter 5 mm under a 2 m ceiling. Over its middle the two are parallel
    plates: the ceiling gets H = E / (1 - ρ_light ρ_ceiling) (E straight from the emitter's back,
    the rest what the back reflects of the ceiling's light). The texels take the emitter's light
    and what it reflects from its pieces (`emitters_reflected_light`), the rest from the solve's
    elements less the same: counted once, not twice (22.7 here, 30 if counted twice)."""
    gap, emission, light_reflectance, ceiling_reflectance = 0.005, 10.0, 0.8, 0.7
    floor = {**surface("floor", FLOOR, 0.5, 0.0), "uv": UV}
    ceiling_corners = [[x, y, 2.0] for x, y, _ in FLOOR][::-1]
    ceiling = {**surface("ceiling", ceiling_corners, ceiling_reflectance, 0.0), "uv": UV}
    light = surface("light", [[x, y, 2.0 - gap] for x, y in [[0.8, 0.8], [1.2, 0.8], [1.2, 1.2], [0.8, 1.2]]][::-1],
                    light_reflectance, emission)
    light["two_sided"] = True
    scene = scene_from_dict({"surfaces": [floor, ceiling, light]})
    solution = solve(scene, solve_settings(method=method, patch_size=0.5, refinements=4, tolerance=1e-3), gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16, content="light"), gpu=gpu)["ceiling"]
    centres = texel_centres(lightmap.size, ceiling_corners)
    middle = (np.abs(centres[..., 0] - 1.0) < 0.1) & (np.abs(centres[..., 1] - 1.0) < 0.1) & (lightmap.patch_index >= 0)
    assert middle.sum() >= 4
    expected = emission / (1 - light_reflectance * ceiling_reflectance)
    np.testing.assert_allclose(lightmap.rgba[middle][:, 0], expected, rtol=0.03)


def test_an_emitters_pieces_send_their_own_reflected_light(gpu):
    """The texel pass sends an emitter's light and what it reflects from its pieces, each piece
    with its own mean of what its patches reflect (`piece_means`), weighted by how much of each
    piece a point sees: uniform reflection R scales the light by (E + R) / E exactly; more on one
    half lights the floor under that half more, and the two halves' light adds up to the whole."""
    emitter_corners = [[0.5, 0.75, 0.3], [0.5, 1.25, 0.3], [1.5, 1.25, 0.3], [1.5, 0.75, 0.3]]
    floor = surface("floor", FLOOR, 0.5, 0.0)
    scene = scene_from_dict({"surfaces": [floor, surface("emitter", emitter_corners, 0.5, 2.0)]})
    patches = subdivide(scene, 4, 0.5, np.zeros(len(scene), dtype=bool))
    points = np.array([[0.75, 1.0, 0.0], [1.25, 1.0, 0.0], [1.0, 1.0, 0.0]])
    owners = np.zeros(len(points), dtype=np.int64)  # a floor patch: the points' plane and normal

    def light(reflected):
        return direct_light(gpu, scene, patches, points, patches.normal[owners], patches.plane[owners], "hemicube", 256,
                            True, 2, reflected)[0][:, 0]

    plain = light(None)
    emits = patches.surface == 1
    uniform = np.where(emits[:, None], 1.0, 0.0) * np.ones((1, 3))
    np.testing.assert_allclose(light(uniform), plain * 1.5, rtol=1e-4)
    left = np.where((emits & (patches.center[:, 0] < 1.0))[:, None], 1.0, 0.0) * np.ones((1, 3))
    right = uniform - left
    from_left, from_right = light(left) - plain, light(right) - plain
    assert from_left[0] > 2 * from_left[1] and from_right[1] > 2 * from_right[0]
    np.testing.assert_allclose(from_left + from_right, plain * 0.5, rtol=1e-4)
    np.testing.assert_allclose(from_left[2], from_right[2], rtol=1e-3)  # the middle sees both alike


def test_the_direct_maps_resolve_no_finer_than_the_finest_texel():
    """A map R pixels across has pixels 4 d / R wide at distance d on its axis: R = 4 D / t puts
    one texel t at the scene's diameter D, rounded up to a multiple of 16, within [64, the cap]."""
    assert matched_map_resolution(0.95, 1 / 64, 1024) == 256  # 243.2: a 55 cm box at 64 texels/m
    assert matched_map_resolution(7.7, 1 / 64, 1024) == 1024  # a furnished room keeps the cap
    assert matched_map_resolution(7.7, 1 / 64, 512) == 512
    assert matched_map_resolution(1.0, 1.0, 1024) == 64  # coarse lightmaps: the floor
    assert matched_map_resolution(1.0, 1.0, 32) == 32  # a cap under the floor is kept
    assert matched_map_resolution(1.0, float("inf"), 1024) == 64  # no lightmap at all


def test_a_bake_shoots_its_direct_light_at_the_matched_resolution(gpu, monkeypatch):
    """The 2 m floor of the Lambert test (diameter 2.86 m with its emitter) at 16 texels/m: the
    texel pass's maps are 4 x 2.86 x 16 = 183 -> 192 pixels across, not the 1024 of the setting."""
    from radiosity_addon.core.lightmap import bake as lightmap_bake
    emitter_corners = [[0.75, 0.75, 0.4], [0.75, 1.25, 0.4], [1.25, 1.25, 0.4], [1.25, 0.75, 0.4]]
    scene = scene_from_dict({"surfaces": [{**surface("floor", FLOOR, 0.5, 0.0), "uv": UV},
                                          {**surface("emitter", emitter_corners, 0.0, 2.0), "uv": UV}]})
    solution = solve(scene, solve_settings(method="hemicube", subdiv=1, elements=1, hemicube_res=32), gpu=gpu)
    used = []
    real = lightmap_bake.direct_light
    monkeypatch.setattr(lightmap_bake, "direct_light",
                        lambda *args, **kw: used.append(args[7]) or real(*args, **kw))
    settings = lightmap_settings(texel_density=16)
    bake_lightmaps(scene, solution, settings, gpu=gpu)
    sizes = lightmap_bake.lightmap_sizes(scene, settings)  # floor ~32 texels a side + gutters, emitter >= 8
    finest = min(np.sqrt(area / np.prod(sizes[name])) for name, area in (("floor", 4.0), ("emitter", 0.25)))
    assert used and set(used) == {matched_map_resolution(scene.diameter, finest, 1024)}
    assert 160 <= used[0] <= 256
