"""Texel validity never darkens what sees the room: a closed box standing 1 mm, 5 mm or 2 cm over a
floor under a sun straight down (32 texels per metre: the contact distance is half a texel, 15.6
mm). Texels of the floor a texel and more outside the box's footprint get the sun's whole light
S / pi, whatever the gap; under the box, the two gaps under half a texel are contacts (black, as
Cycles bakes them) and the 2 cm gap is not (it takes the room's light the solve gives it)."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import box_faces, surface

from radiosity_addon.core import LightmapSettings, SolveSettings, bake_lightmaps, scene_from_dict, solve

FLOOR = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
UV = [[0, 0], [1, 0], [1, 1], [0, 1]]
LOW, HIGH = 0.8, 1.2  # the box's footprint, both axes
DENSITY = 32.0
STRENGTH = 3.0


def box_over_the_floor(gap: float):
    faces = box_faces([LOW, LOW, gap], [HIGH, HIGH, gap + 0.4])
    sun = {"name": "sun", "type": "sun", "direction": [0, 0, -1], "color": [1, 1, 1], "strength": STRENGTH}
    surfaces = [{**surface("floor", FLOOR, 0.5, 0.0), "uv": UV}] + [
        surface(f"box {k}", corners, 0.5, 0.0, obj="box") for k, corners in enumerate(faces)]
    return scene_from_dict({"surfaces": surfaces, "lights": [sun]})


@pytest.mark.parametrize("gap", [0.001, 0.005, 0.02])
def test_a_box_over_the_floor_darkens_only_its_footprint(gpu, gap):
    scene = box_over_the_floor(gap)
    solution = solve(scene, SolveSettings.preset("good"), gpu=gpu)
    lightmap = bake_lightmaps(scene, solution, LightmapSettings.preset("good", texel_density=DENSITY),
                              gpu=gpu)["floor"]
    light = lightmap.rgba[..., :3].mean(axis=2)
    height, width = light.shape
    v, u = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    x, y = 2 * u, 2 * v  # texel centres on the floor
    outside = np.maximum(np.maximum(LOW - x, x - HIGH), np.maximum(LOW - y, y - HIGH))  # < 0 under the box
    texel = 2.0 / width
    lit = outside > 1.5 * texel
    assert lit.sum() > 1000
    assert light[lit].min() > 0.97 * STRENGTH / np.pi, (gap, light[lit].min())  # the sun, and bounce on top
    under = outside < -1.5 * texel
    if gap < 0.5 * texel:  # a contact: nothing comes in that a texel could show
        assert light[under].max() < 1e-6, (gap, light[under].max())
    else:  # no contact: the light the solve gives there, less than the open floor's, not none
        assert 0 < light[under].mean() < 0.5 * STRENGTH / np.pi, (gap, light[under].mean())
