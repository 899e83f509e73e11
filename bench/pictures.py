"""Lightmaps to look at beside Cycles': a mean can hide a black halo, a picture cannot.

One PNG per object: our lightmap | Cycles' reference | the signed difference, relative to the
reference (grey: equal; red: ours brighter; blue: ours darker; full colour at ±DIFFERENCE_RANGE).
Both lightmaps share one exposure (the reference's EXPOSURE_PERCENTILE texel maps to white), texels
neither bake covered are black, and each lightmap texel becomes PIXELS_PER_TEXEL² pixels up to
SMALLEST_SIDE pixels.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radiosity_addon.core import tone_map, write_png
from .compare import covered

DIFFERENCE_RANGE = 0.5  # the relative difference shown at full colour
EXPOSURE_PERCENTILE = 99.0
SMALLEST_SIDE = 256  # pixels: small lightmaps are enlarged to it (whole texels)
GAP = 4  # pixels between the three panels
# the difference's floor: a texel's reference under this share of its object's mean counts as this
# (a relative difference of nearly black texels says nothing)
DARK_FLOOR = 0.05


def luminance(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def difference_colours(ours: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8: the signed relative difference of luminance on `mask`, black elsewhere."""
    theirs = luminance(reference[..., :3])
    floor = DARK_FLOOR * (theirs[mask].mean() if mask.any() else 1.0)
    relative = (luminance(ours[..., :3]) - theirs) / np.maximum(theirs, max(floor, 1e-12))
    level = np.clip(relative / DIFFERENCE_RANGE, -1.0, 1.0)[..., None]
    grey, red, blue = np.array([128, 128, 128]), np.array([230, 40, 30]), np.array([30, 80, 230])
    colours = np.where(level > 0, grey + level * (red - grey), grey - level * (blue - grey))
    return np.where(mask[..., None], colours, 0).astype(np.uint8)


def side_by_side(ours: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(H', W', 3) uint8, row 0 at the top: ours | reference | difference, for RGBA lightmaps whose
    row 0 is the bottom (Blender's images)."""
    mask = covered(ours) & covered(reference)
    values = reference[..., :3][mask]
    white = np.percentile(values, EXPOSURE_PERCENTILE) if len(values) else 1.0
    exposure = 1.0 / max(float(white), 1e-12)
    panels = [np.where(mask[..., None], tone_map(image[..., :3], exposure), 0).astype(np.uint8)
              for image in (ours, reference)]
    panels.append(difference_colours(ours, reference, mask))
    scale = max(1, -(-SMALLEST_SIDE // max(mask.shape)))
    panels = [np.repeat(np.repeat(panel[::-1], scale, axis=0), scale, axis=1) for panel in panels]
    gap = np.full((panels[0].shape[0], GAP, 3), 255, np.uint8)
    return np.concatenate([panels[0], gap, panels[1], gap, panels[2]], axis=1)


def write_pictures(directory: Path, prefix: str, ours: dict, reference: dict) -> list[Path]:
    """DIRECTORY/<prefix><object>.png for every object both have; returns the paths."""
    written = []
    for name in sorted(set(ours) & set(reference)):
        path = Path(directory) / f"{prefix}{name.replace(' ', '_')}.png"
        write_png(path, side_by_side(ours[name], reference[name]))
        written.append(path)
    return written
