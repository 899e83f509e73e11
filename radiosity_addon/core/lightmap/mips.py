"""Gutters and mip levels of a lightmap: dilated from the inside, coverage-aware downsampling
(`imaging`), and the filled image a renderer that builds its own mipmaps needs."""

from __future__ import annotations

import numpy as np

from ..imaging import dilate, downsample_weighted


def mip_levels(values: np.ndarray, coverage: np.ndarray, gutter: int) -> tuple[list, list]:
    """RGBA float32 levels down to 1 x 1, and each level's chart coverage (the fraction of the
    texel on charts). Each level is the coverage-weighted 2x2 mean of the previous level's chart
    texels (not its gutter), so every level's coverage-weighted mean is level 0's; then it is
    dilated by `gutter` texels. Odd sizes halve rounding up (padded with uncovered texels);
    OpenGL's mip sizes, floor(w / 2), agree while sizes stay even (see `gl_mip_count`)."""
    coverage = np.asarray(coverage, dtype=np.float64)
    levels, coverages = [], []
    while True:
        filled, reached = dilate(values, coverage > 0, gutter)
        levels.append(np.concatenate([filled, reached[..., None]], axis=2).astype(np.float32))
        coverages.append(coverage.astype(np.float32))
        if coverage.shape == (1, 1):
            return levels, coverages
        values, coverage = downsample_weighted(values, coverage)  # a 1-texel axis stays 1


def gl_mip_count(levels: list[np.ndarray]) -> int:
    """How many leading levels have OpenGL's sizes (max(1, floor(w / 2^k)), same for h)."""
    height, width = levels[0].shape[:2]
    count = 0
    for k, level in enumerate(levels):
        if level.shape[:2] != (max(1, height >> k), max(1, width >> k)):
            break
        count += 1
    return count


def filled_image(levels: list) -> np.ndarray:
    """Level 0 of a coverage-aware mip chain with every uncovered texel filled from the finest
    level that covers it (push-pull); alpha keeps the coverage.

    Blender builds its own mipmaps by plain averaging, so texels outside the charts and their
    gutters must hold nearby values, not black, or distant mips darken the chart borders."""
    coarsest = levels[-1]
    rgb = coarsest[..., :3].astype(np.float32)
    covered = coarsest[..., 3] > 0
    rgb[~covered] = rgb[covered].mean(axis=0) if covered.any() else 0.0
    for level in reversed(levels[:-1]):
        height, width = level.shape[:2]
        coarse = np.repeat(np.repeat(rgb, 2, axis=0), 2, axis=1)[:height, :width]
        coarse = np.pad(coarse, ((0, height - coarse.shape[0]), (0, width - coarse.shape[1]), (0, 0)), mode="edge")
        rgb = np.where((level[..., 3] > 0)[..., None], level[..., :3], coarse)
    return np.ascontiguousarray(np.concatenate([rgb, levels[0][..., 3:4]], axis=2), dtype=np.float32)
