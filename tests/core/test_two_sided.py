"""Two-sided surfaces (Blender's faces): the back emits and reflects like the front; the scene
analysis simulates a back only where it can send or receive light."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import area_weighted_mean, opposed_rectangles_form_factor, solve_settings, surface

from radiosity_addon.core import scene_from_dict, solve
from radiosity_addon.core.scene import analyse
from radiosity_addon.core.scene.analysis import simulated_backs

SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]  # faces +z
METHODS = {
    "hemicube": solve_settings(method="hemicube", subdiv=8, hemicube_res=128, tolerance=1e-7),
    "progressive": solve_settings(subdiv=4, elements=4, tolerance=1e-5),
}


def at_height(points, z, flip=False):
    lifted = [[x, y, z] for x, y, _ in points]
    return lifted[::-1] if flip else lifted


def panel_under_ceiling(two_sided: bool) -> dict:
    """A unit emitter facing down 1 m under a unit ceiling facing down too: only the emitter's
    back can light the ceiling (a plane close under a ceiling, as users make lights)."""
    emitter = surface("panel", at_height(SQUARE, 1.0, flip=True), 0.0, 1.0)
    emitter["two_sided"] = two_sided
    ceiling = surface("ceiling", at_height(SQUARE, 2.0, flip=True), 0.6, 0.0)
    floor = surface("floor", at_height(SQUARE, 0.0), 0.6, 0.0)
    return {"surfaces": [emitter, ceiling, floor]}


@pytest.mark.parametrize("method", METHODS)
def test_an_emissive_planes_back_lights_the_ceiling_above_it(gpu, method):
    one_sided = solve(scene_from_dict(panel_under_ceiling(False)), METHODS[method], gpu=gpu)
    two_sided = solve(scene_from_dict(panel_under_ceiling(True)), METHODS[method], gpu=gpu)
    assert area_weighted_mean(one_sided, 1)[0] == pytest.approx(0.0, abs=1e-9)
    exact = 0.6 * opposed_rectangles_form_factor(1, 1, 1)  # ρ E F, the panel's back facing up
    assert area_weighted_mean(two_sided, 1)[0] == pytest.approx(exact, rel=0.01)
    # the floor below sees the same front in both scenes
    assert area_weighted_mean(two_sided, 2)[0] == pytest.approx(area_weighted_mean(one_sided, 2)[0], rel=1e-3)
    assert two_sided.report.effects.back_sides == 1
    assert two_sided.report.counts.patches > one_sided.report.counts.patches


def wall_between(two_sided: bool, facing_light: bool) -> dict:
    """A unit emitter on the floor-like plane z = 0 facing up, a reflecting wall at z = 1 above it
    (its front facing up, away from the light, unless `facing_light`), and a receiver at z = 0.5
    facing up between them, seeing only the wall's underside... and the receiver also facing down."""
    light = surface("light", at_height(SQUARE, 0.0), 0.0, 1.0)
    wall = surface("wall", at_height(SQUARE, 1.0, flip=facing_light), 0.8, 0.0)
    wall["two_sided"] = two_sided
    return {"surfaces": [light, wall]}


@pytest.mark.parametrize("method", METHODS)
def test_a_single_plane_wall_reflects_on_its_back_as_a_wall_facing_the_light_does(gpu, method):
    """A two-sided wall turned away from the light reflects it exactly as a one-sided wall turned
    towards it: the light's own radiosity is unchanged, and what reaches the light back matches."""
    settings = METHODS[method]
    away = solve(scene_from_dict(wall_between(True, False)), settings, gpu=gpu)
    towards = solve(scene_from_dict(wall_between(False, True)), settings, gpu=gpu)
    unlit = solve(scene_from_dict(wall_between(False, False)), settings, gpu=gpu)
    back = np.flatnonzero(away.patches.is_back)
    assert len(back) > 0 and np.all(away.patches.surface[back] == 1)
    area = away.patches.area[back]
    back_mean = (away.patch_radiosity[back, 0] * area).sum() / area.sum()
    assert back_mean == pytest.approx(area_weighted_mean(towards, 1)[0], rel=2e-3)
    assert back_mean == pytest.approx(0.8 * opposed_rectangles_form_factor(1, 1, 1), rel=0.01)
    assert area_weighted_mean(unlit, 1)[0] == pytest.approx(0.0, abs=1e-9)
    # the lightmap stores the front: the wall's front faces nothing that shines
    assert area_weighted_mean(away, 1)[0] == pytest.approx(0.0, abs=1e-9)


def box_on_floor(two_sided: bool) -> dict:
    """A closed outward box (six faces) standing on a floor under an emitting ceiling."""
    corners = np.array([[x, y, z] for z in (0.0, 0.4) for y in (0.3, 0.7) for x in (0.3, 0.7)])
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    entries = [surface(f"box{k}", corners[list(f)], 0.5, 0.0, obj="box") for k, f in enumerate(faces)]
    entries.append(surface("floor", [[-1, -1, 0], [2, -1, 0], [2, 2, 0], [-1, 2, 0]], 0.5, 0.0))
    entries.append(surface("ceiling", [[-1, -1, 2], [-1, 2, 2], [2, 2, 2], [2, -1, 2]], 0.0, 1.0))
    for entry in entries:
        entry["two_sided"] = two_sided
    return {"surfaces": entries}


def test_backs_of_a_closed_mesh_are_skipped_and_change_nothing(gpu):
    scene = scene_from_dict(box_on_floor(True))
    backs = simulated_backs(scene)
    names = np.array(scene.names)
    assert not backs[np.char.startswith(names, "box")].any()  # they face the box's dark inside
    assert not backs[names == "ceiling"].any() and not backs[names == "floor"].any()  # nothing behind them
    effects = analyse(scene)
    assert (effects.back_sides, effects.back_sides_skipped) == (0, 8)
    settings = solve_settings(subdiv=2, elements=2, tolerance=1e-4, refinements=0)  # the same patches both ways
    skipped = solve(scene, settings, gpu=gpu)
    everything = solve(scene, solve_settings(subdiv=2, elements=2, tolerance=1e-4, skip_unneeded=False,
                                            refinements=0), gpu=gpu)
    fronts = ~skipped.patches.is_back
    assert np.allclose(skipped.patch_radiosity[fronts], everything.patch_radiosity[~everything.patches.is_back],
                       rtol=2e-3, atol=1e-6)
    assert skipped.report.counts.patches < everything.report.counts.patches
    assert skipped.report.effects.back_sides_skipped == 8 and everything.report.effects.back_sides == 8


def test_a_closed_mesh_with_a_lamp_inside_keeps_its_backs():
    data = box_on_floor(True)
    data["lights"] = [{"name": "bulb", "type": "point", "position": [0.5, 0.5, 0.2], "color": [1, 1, 1],
                       "power": 1.0}]
    backs = simulated_backs(scene_from_dict(data))
    assert backs[:6].all()  # the box's six faces: lit from inside


def test_nothing_behind_a_plane_means_its_back_is_skipped():
    """The walls of a closed room (made of separate planes, inward) have nothing behind them."""
    from scenes import closed_cube

    data = closed_cube(reflectance=0.5, emission=1.0, emitting=["ceiling"])
    for entry in data["surfaces"]:
        entry["two_sided"] = True
    scene = scene_from_dict(data)
    assert not simulated_backs(scene).any()
    assert analyse(scene).back_sides_skipped == 6 and analyse(scene).occlusion is False


def test_two_sided_must_be_a_boolean():
    from radiosity_addon.core import SceneError

    data = panel_under_ceiling(True)
    data["surfaces"][0]["two_sided"] = "yes"
    with pytest.raises(SceneError, match="'panel'.*two_sided"):
        scene_from_dict(data)
