"""The images handed to Blender: no black outside the charts (Blender's own mipmaps would pull it in)."""

import numpy as np

from radiosity_addon.core.lightmap import filled_image


def mip_levels(values, covered, count):
    """RGBA levels, alpha = coverage, each the coverage-weighted 2x2 mean of the one before
    (the shape of `Lightmap.levels`, made here so the test fixes only what filled_image needs)."""
    levels = []
    for _ in range(count):
        levels.append(np.concatenate([values, covered[..., None]], axis=2).astype(np.float32))
        h, w = covered.shape
        weight = covered.reshape(h // 2, 2, w // 2, 2).sum(axis=(1, 3))
        total = (values * covered[..., None]).reshape(h // 2, 2, w // 2, 2, 3).sum(axis=(1, 3))
        values = np.where(weight[..., None] > 0, total / np.maximum(weight, 1)[..., None], 0.0)
        covered = (weight > 0).astype(np.float64)
    return levels


def test_uncovered_texels_take_nearby_values_and_alpha_keeps_coverage():
    values = np.zeros((16, 16, 3))
    covered = np.zeros((16, 16))
    covered[2:6, 2:6] = 1
    values[2:6, 2:6] = [1.0, 2.0, 3.0]
    covered[10:14, 9:15] = 1
    values[10:14, 9:15] = [4.0, 0.5, 0.25]
    levels = mip_levels(values, covered, 3)
    image = filled_image(levels)
    assert image.dtype == np.float32 and image.shape == (16, 16, 4)
    assert np.array_equal(image[..., 3], levels[0][..., 3])
    assert np.allclose(image[2:6, 2:6, :3], [1.0, 2.0, 3.0])
    assert np.allclose(image[10:14, 9:15, :3], [4.0, 0.5, 0.25])
    # every texel is a blend of chart values, none is black
    assert image[..., 0].min() >= 1.0 - 1e-6 and image[..., 2].min() >= 0.25 - 1e-6
    assert np.allclose(image[0, 0, :3], [1.0, 2.0, 3.0])  # near the first chart: its colour
    assert np.allclose(image[15, 15, :3], [4.0, 0.5, 0.25])  # near the second
