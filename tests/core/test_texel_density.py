"""The automatic texel density (`texel_density` 0, the panel's and a new file's default): a small
scene gets the quality preset's texel budget spread over what is baked, a large one never less
than TEXEL_DENSITY per metre."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import light_under_ceiling, surface

from radiosity_addon.core import (TEXEL_DENSITY, LightmapSettings, chosen_texel_density, lightmap_sizes,
                                  scene_from_dict)

UV = [[0, 0], [1, 0], [1, 1], [0, 1]]


def small_scene():
    data = light_under_ceiling(0.001)
    for entry in data["surfaces"]:
        entry["uv"] = UV
    return scene_from_dict(data)


def test_the_automatic_texel_density_spreads_the_presets_budget_and_keeps_the_floor():

    small = small_scene()  # 2 x 2 m floor and ceiling and a 0.4 m emitter: 8.16 m2 (a side each)
    area = float(small.area.sum())
    for quality in ("draft", "good", "final"):
        settings = LightmapSettings.preset(quality, texel_density=0)
        expected = max(TEXEL_DENSITY, np.sqrt(settings.texel_budget / area))
        assert chosen_texel_density(small, settings) == pytest.approx(expected)
        texels = sum(w * h for w, h in lightmap_sizes(small, settings).values())
        assert 0.8 * settings.texel_budget < texels < 1.6 * settings.texel_budget  # sizes round up to 8s
    assert chosen_texel_density(small, LightmapSettings.preset("final", texel_density=0), ["light"]) > \
        chosen_texel_density(small, LightmapSettings.preset("final", texel_density=0))  # only what is baked
    large = scene_from_dict({"surfaces": [{**surface("floor", [[0, 0, 0], [40, 0, 0], [40, 40, 0], [0, 40, 0]], 0.5,
                                                     1.0), "uv": UV}]})
    assert chosen_texel_density(large, LightmapSettings.preset("final", texel_density=0)) == TEXEL_DENSITY
    assert chosen_texel_density(small, LightmapSettings.preset("good", texel_density=20.0)) == 20.0  # as given
