"""An emitter hung close under a ceiling (a panel 1 mm below it, as users model ceiling lights):
the ceiling around it is lit by the room like the rest of it, not left in a dark ring. The
footprint right over the emitter's back keeps its own values (lightmap/seams.py), and what is
interpolated of the solve's light is never below zero."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import light_under_ceiling

from radiosity_addon.core import (LightmapSettings, SolveSettings, bake_lightmaps, point_to_polygon, scene_from_dict,
                                  solve, subdivide)
from radiosity_addon.core.lightmap.seams import under_near_emitters

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

UV = [[0, 0], [1, 0], [1, 1], [0, 1]]
HALF = 0.2  # the emitter's half width, centred at (1, 1)


def ring_scene(gap: float):
    data = light_under_ceiling(gap)
    for entry in data["surfaces"]:
        entry["uv"] = UV
    return scene_from_dict(data)


def test_the_ceiling_beside_an_emitter_1mm_under_it_is_lit_by_the_room(gpu):
    scene = ring_scene(0.001)
    solution = solve(scene, SolveSettings.preset("final"), gpu=gpu)
    maps = bake_lightmaps(scene, solution, LightmapSettings.preset("final", texel_density=32, content="light"),
                          gpu=gpu)
    light = maps["ceiling"].rgba[..., :3].mean(axis=2)  # H, grey: every reflectance is grey
    height, width = light.shape
    corners = np.asarray(scene.corners[1])  # the ceiling, UV square on its corners in order
    v, u = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    points = (corners[0] * ((1 - u) * (1 - v))[..., None] + corners[1] * (u * (1 - v))[..., None]
              + corners[2] * (u * v)[..., None] + corners[3] * ((1 - u) * v)[..., None])
    outline = np.maximum(np.abs(points[..., 0] - 1.0), np.abs(points[..., 1] - 1.0)) - HALF
    ring = (outline > 0.05) & (outline < 0.4)  # beside the emitter, a texel and more from its outline
    # independently: the ceiling point gathers the floor's radiosity (solved: smooth, far from the
    # emitter) and the emitter's back (its B, light trapped over it included), by Lambert's formula;
    # nothing else is in view (the emitter's edge hides directions within 1 mm of the horizon)
    patches = solution.patches
    radiosity = np.asarray(solution.patch_radiosity).reshape(len(patches), -1).mean(axis=1)
    seen = np.flatnonzero((patches.surface == 0) | ((patches.surface == 2) & patches.is_back))
    polygons = patches.corners[seen]
    factors = point_to_polygon(points[ring], np.tile([0.0, 0.0, -1.0], (int(ring.sum()), 1)), polygons)
    expected = factors @ radiosity[seen]
    ratio = light[ring] / expected
    assert ratio.min() > 0.75, (ratio.min(), outline[ring][np.argmin(ratio)])  # a dark ring was ~0 here
    assert abs(np.median(ratio) - 1.0) < 0.1, np.median(ratio)


def test_the_footprint_of_a_near_emitter_is_found_and_a_far_one_has_none():
    for gap, expected in ((0.001, True), (0.2, False)):
        scene = ring_scene(gap)
        patches = subdivide(scene, None, 0.1, np.ones(len(scene), dtype=bool))  # every back simulated
        under = under_near_emitters(scene, patches)
        centre = patches.corners.mean(axis=1)
        inside = np.maximum(np.abs(centre[:, 0] - 1.0), np.abs(centre[:, 1] - 1.0)) < HALF
        ceiling = (patches.surface == 1) & ~patches.is_back
        assert ceiling.sum() > 100 and np.array_equal(under[ceiling], inside[ceiling] & expected)
        assert not under[patches.surface != 1].any()  # the floor is 2 m away; the emitter is no receiver

