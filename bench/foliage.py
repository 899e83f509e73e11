"""The production terrace's foliage numbers (bench/production.py): on the sun-lit floor under the
leaf-card canopy, how the dappled shadow compares with Cycles' — the shadowed area's mean and the
pattern's texel RMS. The area is the floor's texels whose ray to the sun crosses the canopy's box
(its cards' centres), MARGIN inside its sides, so every texel in it looks up through the leaves."""

from __future__ import annotations

import numpy as np

from .compare import covered
from .production import CANOPY_HIGH, CANOPY_LOW

MARGIN = 0.4  # metres inside the canopy box's sides: its edge, where half the rays miss the leaves, is left out
FLOOR = "Floor"


def canopy_shadow(positions: np.ndarray, towards_sun: np.ndarray) -> np.ndarray:
    """(H, W) bool: floor texels at `positions` (H, W, 3; NaN where none) whose ray towards the sun
    (`towards_sun`, a unit vector) crosses the canopy box's middle height within MARGIN of its inside."""
    towards_sun = np.asarray(towards_sun, dtype=np.float64)
    middle = (CANOPY_LOW[2] + CANOPY_HIGH[2]) / 2
    with np.errstate(invalid="ignore"):
        reach = (middle - positions[..., 2]) / towards_sun[2]
        crossing = positions + reach[..., None] * towards_sun
        inside = np.ones(positions.shape[:2], dtype=bool)
        for axis in (0, 1):
            inside &= (crossing[..., axis] > CANOPY_LOW[axis] + MARGIN) & (crossing[..., axis] < CANOPY_HIGH[axis] - MARGIN)
    return inside & np.isfinite(positions).all(axis=-1)


def foliage_numbers(ours: np.ndarray, reference: np.ndarray, shadow: np.ndarray) -> dict:
    """{"texels", "shadow_mean_ratio" (ours over the reference's mean in the area), "pattern_rms"
    (texel RMS over the area, relative to the reference's RMS there)} of two floor lightmaps."""
    area = shadow & covered(ours) & covered(reference)
    a, b = ours[..., :3][area], reference[..., :3][area]
    if not area.any():
        return {"texels": 0, "shadow_mean_ratio": None, "pattern_rms": None}
    return {"texels": int(area.sum()), "shadow_mean_ratio": float(a.mean() / b.mean()),
            "pattern_rms": float(np.sqrt(((a - b) ** 2).sum() / (b ** 2).sum()))}
