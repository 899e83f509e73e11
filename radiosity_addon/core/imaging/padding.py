"""Padding shared by the progressive solver's element tiles and the lightmaps.

One implementation of "fill the texels around covered texels from the inside"
(gutters, so bilinear/trilinear filtering never reads garbage) and of
coverage-aware downsampling (mip levels that uncovered texels don't darken).
All vectorized numpy over whole images.
"""

from __future__ import annotations

import numpy as np

# (dy, dx, weight): edge neighbours dominate, diagonal ones only fill corners, so a
# gutter texel continues the covered texel straight inside it (clamp-to-edge).
_NEIGHBOURS = [(dy, dx, 1.0 if dy == 0 or dx == 0 else 1e-3)
               for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]


def dilate(values: np.ndarray, covered: np.ndarray, rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Grow covered regions by `rings` texels: each new texel takes the weighted mean of its
    covered 8-neighbours (inside values only; edge neighbours weigh most). values (H, W, C), covered (H, W) bool.
    Returns new (values, covered); texels never reached keep their values and stay uncovered.
    Neighbours are read as views into copies with a border of one uncovered zero texel, not as
    shifted copies: a ring allocates nothing per neighbour."""
    h, w = covered.shape
    border_values = np.zeros((h + 2, w + 2) + values.shape[2:], dtype=np.float64)
    border_covered = np.zeros((h + 2, w + 2), dtype=bool)
    inside = (slice(1, h + 1), slice(1, w + 1))
    border_values[inside] = np.where(covered[..., None], values, 0)
    border_covered[inside] = covered
    values, covered = border_values[inside], border_covered[inside]  # views: updated in place
    total = np.empty_like(values)
    count = np.empty(covered.shape, dtype=np.float64)
    neighbour_weight = np.empty(covered.shape, dtype=np.float64)
    for _ in range(rings):
        total.fill(0.0)
        count.fill(0.0)
        for dy, dx, weight in _NEIGHBOURS:
            # out[y, x] = in[y - dy, x - dx]
            near = (slice(1 - dy, h + 1 - dy), slice(1 - dx, w + 1 - dx))
            np.multiply(weight, border_covered[near], out=neighbour_weight)
            total += neighbour_weight[..., None] * border_values[near]
            count += neighbour_weight
        grow = ~covered & (count > 0)
        if not grow.any():
            break
        values[grow] = total[grow] / count[grow][:, None]
        covered |= grow
    return values.copy(), covered.copy()


def downsample_weighted(values: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Halve an image by 2x2 weighted means. weight (H, W) >= 0, e.g. the covered fraction of each
    texel; the new weight is the children's mean weight, so chaining levels keeps every level's
    weighted mean equal to the first one's. Odd sizes are padded with weight-0 texels."""
    h, w = weight.shape
    ph, pw = h + h % 2, w + w % 2
    padded_values = np.zeros((ph, pw, values.shape[2]))
    padded_weight = np.zeros((ph, pw))
    padded_weight[:h, :w] = weight
    padded_values[:h, :w] = np.where(weight[..., None] > 0, values, 0) * weight[..., None]
    weight_sum = padded_weight.reshape(ph // 2, 2, pw // 2, 2).sum(axis=(1, 3))
    total = padded_values.reshape(ph // 2, 2, pw // 2, 2, -1).sum(axis=(1, 3))
    level = np.where(weight_sum[..., None] > 0, total / np.where(weight_sum > 0, weight_sum, 1)[..., None], 0.0)
    return level, weight_sum / 4


def pad_tiles(tiles: np.ndarray, gutter: int) -> np.ndarray:
    """(N, S, S, C) tiles -> (N, S + 2g, S + 2g, C) with each gutter filled from its own tile
    by `dilate` (edge texels continued outward), so filtered reads at tile edges stay correct."""
    n, s, _, c = tiles.shape
    size = s + 2 * gutter
    values = np.zeros((n, size, size, c))
    values[:, gutter:gutter + s, gutter:gutter + s] = tiles
    covered = np.zeros((size, size), dtype=bool)
    covered[gutter:gutter + s, gutter:gutter + s] = True
    # all tiles side by side with a gap of 2g so one dilate call serves every tile
    strip = values.transpose(1, 0, 2, 3).reshape(size, n * size, c)
    strip_covered = np.tile(covered, (1, n))
    filled, _ = dilate(strip, strip_covered, gutter)
    return filled.reshape(size, n, size, c).transpose(1, 0, 2, 3)
