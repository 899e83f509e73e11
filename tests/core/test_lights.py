"""Lamps and the world colour as shooters, against analytic direct lighting (core/shooting/lamps.py)."""

import math

import numpy as np
import pytest
from scenes import solve_settings, surface

from radiosity_addon.core.scene import analyse
from radiosity_addon.core.hemicube.method import element_means
from radiosity_addon.core.shooting import element_areas, element_centers
from radiosity_addon.core import point_to_polygon
from radiosity_addon.core import SceneError, scene_from_dict
from radiosity_addon.core import solve
from radiosity_addon.core.scene import subdivide
from radiosity_addon.core.shooting.direct import sky_light
from radiosity_addon.core.shooting.sky import SKY_DIRECTIONS

RHO = 0.8
FLOOR = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]  # 2 x 2, facing +z


def floor_scene(lights=None, world=None, extra_surfaces=()):
    data = {"surfaces": [surface("floor", FLOOR, RHO, 0.0), *extra_surfaces]}
    if lights:
        data["lights"] = lights
    if world is not None:
        data["world"] = {"color": world}
    return scene_from_dict(data)


def floor_elements(solution, elements):
    """(points (N, 3), radiosity (N, 3)) of the floor's elements."""
    mask = solution.patches.surface == 0
    points = element_centers(solution.patches, elements)[mask].reshape(-1, 3)
    return points, solution.element_radiosity[mask].reshape(-1, 3)


def progressive(scene, gpu, elements=4, **settings):
    return solve(scene, solve_settings(subdiv=2, elements=elements, **settings), gpu=gpu)


POINT = {"name": "bulb", "type": "point", "position": [0.2, -0.1, 1.0], "color": [1.0, 0.5, 0.25], "power": 100.0}


def point_lamp_radiance(points, lamp, falloff=1.0):
    d = points - np.asarray(lamp["position"])
    r2 = (d * d).sum(axis=1)
    cosine = -d[:, 2] / np.sqrt(r2)
    intensity = np.asarray(lamp["color"]) * lamp["power"] / (4 * math.pi)
    return RHO * intensity * (cosine * falloff / (math.pi * r2))[:, None]


def test_point_lamp_on_a_floor_is_exact_at_element_centres(gpu):
    solution = progressive(floor_scene([POINT]), gpu)
    points, radiosity = floor_elements(solution, 4)
    np.testing.assert_allclose(radiosity, point_lamp_radiance(points, POINT), rtol=1e-4)
    assert solution.report.work.direct.lamps == 1 and solution.report.effects.emitters == 1


def test_point_lamp_through_the_hemicube_method(gpu):
    """The lamp's light on every hemi-cube element (2 x 2 a patch) is the analytic one, averaged
    over the element's 2 x 2 of the 4 x 4 points its patch measures the direct light at."""
    scene = floor_scene([POINT])
    solution = solve(scene, solve_settings(method="hemicube", subdiv=4, refinements=0, hemicube_elements=2), gpu=gpu)
    patches = solution.patches
    points = element_centers(patches, 4)
    analytic = point_lamp_radiance(points.reshape(-1, 3), POINT).reshape(len(patches), 4, 4, 3)
    expected = element_means(analytic, element_areas(patches, 4), 2)
    np.testing.assert_allclose(solution.element_radiosity, expected, rtol=2e-3)
    centre_values = point_lamp_radiance(element_centers(patches, 2).reshape(-1, 3), POINT)
    assert np.abs(centre_values / expected.reshape(-1, 3) - 1).max() > 1e-2  # the mean, not the centre


def test_spot_cone_and_blend(gpu):
    spot = {**POINT, "type": "spot", "position": [0, 0, 1.0], "direction": [0, 0, -1],
            "spot_size": math.radians(60), "spot_blend": 0.3}
    solution = progressive(floor_scene([spot]), gpu, elements=8)
    points, radiosity = floor_elements(solution, 8)
    d = points - np.asarray(spot["position"])
    cos_angle = -d[:, 2] / np.linalg.norm(d, axis=1)
    cos_half = math.cos(spot["spot_size"] / 2)
    t = np.clip((cos_angle - cos_half) / ((1 - cos_half) * spot["spot_blend"]), 0, 1)
    expected = point_lamp_radiance(points, spot, t * t * (3 - 2 * t))
    np.testing.assert_allclose(radiosity, expected, rtol=1e-4, atol=1e-6)
    assert np.any(expected[:, 0] == 0) and np.any(expected[:, 0] > 0)  # both sides of the cone's edge


def test_sun_lights_evenly_and_a_panel_casts_its_shadow(gpu):
    sun = {"name": "sun", "type": "sun", "direction": [0.0, 0.6, -0.8], "color": [1, 1, 1], "strength": 3.0}
    lit = RHO * 3.0 * 0.8 / math.pi
    solution = progressive(floor_scene([sun]), gpu)
    np.testing.assert_allclose(floor_elements(solution, 4)[1], lit, rtol=1e-4)
    # a black panel at height 0.5 over x, y in [-0.5, 0.5]: its shadow is shifted by 0.5 * 0.6/0.8 along +y
    panel = surface("panel", [[-0.5, -0.5, 0.5], [-0.5, 0.5, 0.5], [0.5, 0.5, 0.5], [0.5, -0.5, 0.5]], 0.0, 0.0)
    shaded = progressive(floor_scene([sun], extra_surfaces=[panel]), gpu, elements=4)
    points, radiosity = floor_elements(shaded, 4)
    in_shadow = (np.abs(points[:, 0]) < 0.45) & (np.abs(points[:, 1] - 0.375) < 0.45)
    far_from_shadow = (np.abs(points[:, 0]) > 0.6) | (np.abs(points[:, 1] - 0.375) > 0.6)
    assert np.all(radiosity[in_shadow] < 0.02 * lit)
    np.testing.assert_allclose(radiosity[far_from_shadow], lit, rtol=1e-3)


def test_a_sun_grazing_a_wall_lights_it_whatever_the_map_eye_sees(gpu):
    """The sun's map is orthographic: its eye point (outside the scene) is not where its rays come
    from. A wall's outer face the sun grazes (cos 0.2) lies behind that point's plane of view; it
    was drawn as a back (item 0) and baked black, where Cycles lights it (the room bench's west
    wall outside)."""
    direction = np.array([0.2, 0.8, -math.sqrt(1 - 0.68)])
    sun = {"name": "sun", "type": "sun", "direction": direction.tolist(), "color": [1, 1, 1], "strength": 2.0}
    wall = surface("wall", [[0, 1, 0], [0, -1, 0], [0, -1, 2], [0, 1, 2]], RHO, 0.0)  # facing -x
    floor = surface("floor", [[0, -1, 0], [4, -1, 0], [4, 1, 0], [0, 1, 0]], RHO, 0.0)
    solution = progressive(scene_from_dict({"surfaces": [wall, floor], "lights": [sun]}), gpu, refinements=0)
    assert solution.report.effects.occlusion
    wall_radiosity = solution.element_radiosity[solution.patches.surface == 0]
    np.testing.assert_allclose(wall_radiosity, RHO * 2.0 * 0.2 / math.pi, rtol=1e-4)


def test_area_lamp_is_an_emitting_polygon(gpu):
    corners = [[-0.2, -0.2, 1.0], [-0.2, 0.2, 1.0], [0.2, 0.2, 1.0], [0.2, -0.2, 1.0]]  # front faces -z
    lamp = {"name": "panel", "type": "area", "vertices": corners, "color": [1, 1, 1], "power": 50.0}
    solution = progressive(floor_scene([lamp]), gpu)
    points, radiosity = floor_elements(solution, 4)
    radiance = 50.0 / (math.pi * 0.16)
    factor = point_to_polygon(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), np.asarray([corners], float))
    np.testing.assert_allclose(radiosity[:, 0], RHO * radiance * factor[:, 0], rtol=1e-3)


def test_world_colour_lights_by_sky_fraction(gpu):
    world = [0.5, 0.5, 0.5]
    open_floor = progressive(floor_scene(world=world), gpu)
    np.testing.assert_allclose(floor_elements(open_floor, 4)[1], RHO * 0.5, rtol=0.01)
    # a black wall standing on the floor's edge x = 1 (facing -x) hides part of the sky
    wall = surface("wall", [[1, -1, 0], [1, -1, 2], [1, 1, 2], [1, 1, 0]], 0.0, 0.0)
    walled = progressive(floor_scene(world=world, extra_surfaces=[wall]), gpu)
    points, radiosity = floor_elements(walled, 4)
    # exact sky fraction at a point: 1 - unoccluded form factor to the wall
    wall_polygon = np.asarray([wall["vertices"]], dtype=float)
    hidden = point_to_polygon(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), wall_polygon)[:, 0]
    np.testing.assert_allclose(radiosity[:, 0], RHO * 0.5 * (1 - hidden), rtol=0.02)


def test_the_sky_from_its_directions_is_the_exact_fraction_beside_a_wall(gpu):
    """Past SKY_DIRECTIONS points, the sky's light is gathered from its directions' maps
    (shooting.sky), not a hemi-cube per point: 2 500 floor points, each within 2 % of the exact."""
    wall = surface("wall", [[1, -1, 0], [1, -1, 2], [1, 1, 2], [1, 1, 0]], 0.0, 0.0)
    scene = floor_scene(world=[1.0, 1.0, 1.0], extra_surfaces=[wall])
    patches = subdivide(scene, 1)
    steps = (np.arange(50) + 0.5) / 50 * 1.9 - 0.95
    x, y = np.meshgrid(steps, steps)
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    assert len(points) > SKY_DIRECTIONS
    with gpu.resources() as res:
        light = sky_light(res, scene, patches, points, np.zeros(len(points), dtype=np.int64), np.ones(3))[:, 0]
    hidden = point_to_polygon(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), np.asarray([wall["vertices"]], float))
    np.testing.assert_allclose(light, 1 - hidden[:, 0], rtol=0.02)


def test_lamps_in_the_scene_analysis():
    assert analyse(floor_scene([POINT])).emitters == 1
    assert analyse(floor_scene([POINT])).channels == 3  # the lamp's colour is not grey
    grey = {**POINT, "color": [1, 1, 1]}
    assert analyse(floor_scene([grey])).channels == 1
    assert analyse(floor_scene([grey])).occlusion is False  # a lamp above a floor: nothing to hide
    below = {**grey, "position": [0, 0, -1.0]}
    assert analyse(floor_scene([below])).occlusion is True  # behind the floor's plane
    sun = {"name": "sun", "type": "sun", "direction": [0, 0, -1], "color": [1, 1, 1], "strength": 1.0}
    assert analyse(floor_scene([sun])).occlusion is True
    assert analyse(floor_scene(world=[0.2, 0.2, 0.2])).emitters == 1


@pytest.mark.parametrize("light, fault", [
    ({"type": "laser", "color": [1, 1, 1]}, "'type'"),
    ({"type": "point", "color": [1, 1, 1], "power": 10}, "'position'"),
    ({"type": "point", "position": [0, 0, 1], "color": [1, 1, 1], "power": -1}, "'power'"),
    ({"type": "spot", "position": [0, 0, 1], "direction": [0, 0, 0], "color": [1, 1, 1], "power": 1,
      "spot_size": 1.0}, "direction"),
    ({"type": "area", "vertices": [[0, 0, 1]] * 4, "color": [1, 1, 1], "power": 1}, "zero area"),
])
def test_bad_lamps_are_refused_by_name(gpu, light, fault):
    with pytest.raises(SceneError, match=fault):
        solve(floor_scene([{"name": "L", **light}]), solve_settings(subdiv=1, elements=1), gpu=gpu)
