"""The preview renderer: the Cornell box through its lightmaps, measured on the PNG, and the
command line's `solve --lightmaps --preview`."""

from __future__ import annotations

import numpy as np
import pytest

from scenes import solve_settings, lightmap_settings

from radiosity_addon import cli
from radiosity_addon.core import (bake_lightmaps, load_scene, render_preview,
                                  save_preview, solve)
from radiosity_addon.core.imaging import dilate

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709


def test_cornell_preview_shows_colour_bleeding_and_the_light_is_brightest(gpu, tmp_path):
    """Measured on the PNG (decoded by matplotlib, not by our writer): on the white back wall,
    floor and ceiling, the strip next to the red wall is redder than the middle strip and the
    strip next to the green wall greener; the light's pixels are the brightest surface."""
    image_module = pytest.importorskip("matplotlib.image")
    cornell = load_scene("cornell-box")
    solution = solve(cornell, solve_settings(method="hemicube", subdiv=4, hemicube_res=64), gpu=gpu)
    lightmaps = bake_lightmaps(cornell, solution, lightmap_settings(texel_density=128.0), gpu=gpu)
    preview = render_preview(cornell, lightmaps, width=256, height=256, gpu=gpu)
    path = tmp_path / "cornell.png"
    save_preview(path, cornell, preview)
    encoded = image_module.imread(path)[..., :3].astype(np.float64)
    assert encoded.shape == (256, 256, 3)
    rgb = np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)  # back to linear
    names = [s.name for s in cornell.surfaces]
    seen = preview.surface_index

    def strip_colour(surface, which):
        rows, cols = np.nonzero(seen == names.index(surface))
        low, high = np.percentile(cols, 2), np.percentile(cols, 98)
        edges = {"left": (0.0, 0.15), "middle": (0.425, 0.575), "right": (0.85, 1.0)}[which]
        chosen = (cols >= low + edges[0] * (high - low)) & (cols <= low + edges[1] * (high - low))
        colour = rgb[rows[chosen], cols[chosen]].mean(axis=0)
        return colour / colour.sum()

    for surface in ("back_wall", "floor", "ceiling"):
        left, middle, right = (strip_colour(surface, w) for w in ("left", "middle", "right"))
        assert left[0] > middle[0] + 0.02, f"{surface}: no red bleeding near the red wall ({left} vs {middle})"
        assert right[1] > middle[1] + 0.02, f"{surface}: no green bleeding near the green wall ({right} vs {middle})"

    luminance = rgb @ LUMINANCE
    light = seen == names.index("light")
    assert light.sum() > 50
    means = {name: luminance[seen == k].mean() for k, name in enumerate(names) if (seen == k).any()}
    brightest_other = max(v for n, v in means.items() if n != "light")
    assert means["light"] > 0.9 and means["light"] > 1.5 * brightest_other, means
    brightest = np.argsort(luminance, axis=None)[-light.sum():]  # as many pixels as the light has
    _, light_and_rim = dilate(np.zeros(light.shape + (1,)), light, 1)  # rim pixels blend light in
    assert light_and_rim.ravel()[brightest].mean() > 0.97


def test_cli_solve_writes_lightmaps_and_preview(tmp_path):
    status = cli.main(["solve", "cornell-box", "--method", "hemicube", "--subdiv", "2", "--hemicube-res", "16",
                       "--quiet", "--lightmaps", str(tmp_path / "maps"), "--texel-density", "32",
                       "--preview", str(tmp_path / "preview.png"), "--preview-size", "64"])
    assert status == 0
    floor = np.load(tmp_path / "maps" / "floor_lightmap.npy")
    assert floor.dtype == np.float32 and floor.ndim == 3 and floor.shape[2] == 4
    assert sorted(p.name for p in (tmp_path / "maps").iterdir()) == sorted(
        f"{name}_lightmap.npy" for name in load_scene("cornell-box").objects)
    assert (tmp_path / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
