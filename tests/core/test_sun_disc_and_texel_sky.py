"""A sun with an angle and the sky, texel by texel, against exact values: the penumbra of a sun's
disc behind a straight edge (the disc's part past the edge, a circular segment), and the sky
fraction under a card (1 minus Lambert's factor to it), each averaged over the texel's square."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scenes import surface
from test_texel_light import UV, texel_means

from radiosity_addon.core import LightmapSettings, SolveSettings, bake_lightmaps, point_to_polygon, scene_from_dict, solve
from radiosity_addon.core.shooting.lamps import sun_disc

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

FLOOR = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
ANGLE = math.radians(10.0)  # the sun's disc: its penumbra 2 tan(5°) = 17.5 cm wide at 1 m
STRENGTH = 2.0
LIT = STRENGTH / math.pi  # the light H a sun of strength S sends straight down (units: lamps.py)


def floor_light(gpu, extra, lights=None, world=None, **lightmap):
    floor = {**surface("floor", FLOOR, 0.0, 0.0), "uv": UV}
    data = {"surfaces": [floor, *extra]}
    if lights:
        data["lights"] = lights
    if world:
        data["world"] = {"color": world}
    scene = scene_from_dict(data)
    solution = solve(scene, SolveSettings.preset("good", method="progressive"), gpu=gpu)
    settings = LightmapSettings.preset("good", texel_density=48, content="light", **lightmap)
    floor_map = bake_lightmaps(scene, solution, settings, gpu=gpu)["floor"]
    return floor_map.rgba[..., 0], floor_map.size


def test_a_suns_disc_directions_fill_it_evenly():
    direction = np.array([0.3, -0.2, -0.9]) / np.linalg.norm([0.3, -0.2, -0.9])
    spread = sun_disc(direction, ANGLE, 16)
    off_axis = np.arccos(np.clip(spread @ direction, -1, 1))
    assert len(spread) == 16 and off_axis.max() <= ANGLE / 2 + 1e-9
    # as far from the axis on the whole as a uniform disc's points: 2/3 of its radius
    assert abs(off_axis.mean() / (ANGLE / 2) - 2 / 3) < 0.03
    np.testing.assert_allclose(spread.mean(axis=0) / np.linalg.norm(spread.mean(axis=0)), direction, atol=5e-3)
    assert np.allclose(sun_disc(direction, 0.0, 1), direction)


def test_a_sun_with_an_angle_casts_the_penumbra_of_its_disc(gpu):
    """A sun straight above with a 10° disc, a black panel 1 m over the floor's half x < 0: at x
    the disc's part over x' < 0 (a circular segment of radius R = tan 5°) is hidden."""
    panel = surface("panel", [[-1.2, -1.2, 1], [-1.2, 1.2, 1], [0, 1.2, 1], [0, -1.2, 1]], 0.0, 0.0)
    sun = {"name": "sun", "type": "sun", "direction": [0, 0, -1], "color": [1, 1, 1], "strength": STRENGTH,
           "angle": ANGLE}
    light, size = floor_light(gpu, [panel], lights=[sun])
    radius = math.tan(ANGLE / 2)

    def exact(points):
        x = np.clip(points[..., 0] / radius, -1, 1)
        hidden = (np.arccos(x) - x * np.sqrt(1 - x * x)) / math.pi  # the segment's share of the disc
        return LIT * (1 - (ANGLE / 2) ** 2 / 4) * (1 - hidden)  # a uniform disc's mean cosine

    expected = texel_means(size, FLOOR, exact)
    band = np.abs(texel_means(size, FLOOR, lambda p: p[..., 0])) < 1.5 * radius
    assert band.sum() > 10 * size[1]  # the penumbra is texels wide
    # texel by texel within a sixteenth of the sun (its disc in 16 directions), and on the whole
    assert np.abs(light - expected).max() < 0.09 * LIT
    assert abs(light[band].mean() / expected[band].mean() - 1) < 0.02
    # a hard shadow (no angle) would be off by half the sun next to the edge
    assert np.abs(light - expected)[band].max() < 0.2 * np.abs(np.where(expected > LIT / 2, LIT, 0) - expected)[band].max()


def test_the_sky_per_texel_is_the_fraction_each_texel_sees(gpu):
    """A white sky over the floor and a black 0.6 m card 0.2 m above its middle: with the sky per
    texel each texel gets 1 - F(texel -> card) (exact), where the elements' sky, interpolated, is
    a patch's mean."""
    card = surface("card", [[-0.3, -0.3, 0.2], [-0.3, 0.3, 0.2], [0.3, 0.3, 0.2], [0.3, -0.3, 0.2]], 0.0, 0.0)
    corners = np.asarray([card["vertices"]], dtype=float)  # it faces the floor

    def exact(points):
        flat = points.reshape(-1, 3)
        factor = point_to_polygon(flat, np.tile([0.0, 0.0, 1.0], (len(flat), 1)), corners)[:, 0]
        return (1 - factor).reshape(points.shape[:-1])

    per_texel, size = floor_light(gpu, [card], world=[1.0, 1.0, 1.0], sky_directions=1024)
    interpolated, _ = floor_light(gpu, [card], world=[1.0, 1.0, 1.0])
    expected = texel_means(size, FLOOR, exact)
    error = np.abs(per_texel - expected)
    assert error.max() < 0.03, error.max()
    assert np.abs(interpolated - expected).max() > 3 * error.max()
