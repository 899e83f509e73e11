"""Texels in contact: where another face touches a surface face to face (a box standing on the
floor, a ceiling slab resting on a wall), the surface's texels see nothing, as Cycles bakes them."""

from __future__ import annotations

import numpy as np
from scenes import box_faces, lightmap_settings, solve_settings, surface

from radiosity_addon.core import bake_lightmaps, scene_from_dict, solve
from radiosity_addon.core.lightmap.contact import in_contact, touching_faces
from radiosity_addon.core.lightmap.lattice import element_values

FLOOR = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
UV = [[0, 0], [1, 0], [1, 1], [0, 1]]
LOW, HIGH = np.array([0.6, 0.6, 0.0]), np.array([1.0, 1.0, 0.4])  # a box standing on the floor
EMITTER = [[0.4, 1.2, 1.5], [1.6, 1.2, 1.5], [1.6, 1.6, 1.5], [0.4, 1.6, 1.5]]  # facing down


def box_on_floor(gap: float = 0.0) -> dict:
    box = [surface(f"box {k}", corners, 0.8, 0.0, obj="box")
           for k, corners in enumerate(box_faces(LOW + [0, 0, gap], HIGH + [0, 0, gap]))]
    return {"surfaces": [{**surface("floor", FLOOR, 0.5, 0.0), "uv": UV}] + box
            + [surface("emitter", EMITTER[::-1], 0.0, 5.0)]}


def test_only_faces_on_one_plane_and_facing_each_other_touch():
    scene = scene_from_dict({"surfaces": [
        surface("floor", FLOOR, 0.5, 0.0),
        surface("foot", [[0.2, 0.2, 0], [0.2, 0.4, 0], [0.4, 0.4, 0], [0.4, 0.2, 0]], 0.5, 0.0),  # facing down: touches
        # an emitter hung 2 cm above, facing it: no contact
        surface("hovering", [[1.2, 0.2, 0.02], [1.2, 0.4, 0.02], [1.4, 0.4, 0.02], [1.4, 0.2, 0.02]], 0.5, 5.0),
        surface("coplanar, facing up", [[0.2, 1.2, 0], [0.4, 1.2, 0], [0.4, 1.4, 0], [0.2, 1.4, 0]], 0.5, 0.0)]})
    surfaces, partners = touching_faces(scene, np.array([0]))
    assert surfaces.tolist() == [0] and partners.tolist() == [1]
    points = np.array([[0.3, 0.3, 0.0], [0.41, 0.3, 0.0], [1.3, 0.3, 0.0], [0.3, 1.3, 0.0]])
    assert in_contact(scene, points, np.zeros(4, dtype=np.int64)).tolist() == [True, False, False, False]


def floor_light(gap: float, gpu):
    scene = scene_from_dict(box_on_floor(gap))
    solution = solve(scene, solve_settings(method="progressive", subdiv=1, elements=2, refinements=0, tolerance=1e-3),
                     gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, lightmap_settings(texel_density=32, content="light"), gpu=gpu)["floor"]
    size = lightmap.size
    v, u = np.meshgrid((np.arange(size[1]) + 0.5) / size[1], (np.arange(size[0]) + 0.5) / size[0], indexing="ij")
    points = np.stack([2 * u, 2 * v], axis=-1)
    from_box = np.max(np.abs(points - (LOW[:2] + HIGH[:2]) / 2), axis=-1) - (HIGH[0] - LOW[0]) / 2  # > 0 outside
    inside = lightmap.patch_index >= 0
    return lightmap.rgba[..., :3], from_box, inside, solution


def test_a_box_standing_on_the_floor_leaves_its_footprint_black(gpu):
    """The floor's one 2 m patch gets light from the emitter and the grey box's lit sides; its
    elements' light, interpolated, would reach under the box (a leak through the contact). Texels
    whose centres lie under the box's bottom are black; those around it keep their light."""
    light, from_box, inside, solution = floor_light(0.0, gpu)
    under = inside & (from_box < -0.5 / 32)
    around = inside & (from_box > 1.5 / 32)
    assert under.sum() > 100 and around.sum() > 1000
    assert np.all(light[under] == 0.0)
    assert light[around].mean() > 0.05
    # what the contact rule removes: the floor patch's elements all hold light (interpolated, it
    # would reach under the box)
    floor_elements = element_values(solution, light=True)[0]
    assert floor_elements.min() > 0.05


def test_a_box_hovering_above_the_floor_is_no_contact(gpu):
    """The same box 4 cm above the floor (more than the 31 mm texels show): light reaches under it
    from the sides, so its footprint keeps the floor's interpolated indirect light."""
    light, from_box, inside, _ = floor_light(0.04, gpu)
    under = inside & (from_box < -0.5 / 32)
    assert light[under].mean() > 1e-3


def test_a_gap_thinner_than_half_a_texel_is_contact(gpu):
    """The box 5 mm above the floor: what comes in through the slit fades within a centimetre or
    two (Cycles bakes a sofa set 2 mm over a floor black under it, bar a rim), finer than a 31 mm
    texel shows, so the footprint is black as under a box standing on the floor."""
    light, from_box, inside, _ = floor_light(0.005, gpu)
    under = inside & (from_box < -0.5 / 32)
    assert under.sum() > 100
    assert np.all(light[under] == 0.0)
