"""The world colour as a shooter: each element gathers ρ · L · its sky fraction, the
cosine-weighted part of its hemisphere that sees no surface, from hemi-cubes at its centre."""

from __future__ import annotations

import numpy as np

from ..gpu import Resources
from ..scene import Patches
from ..scene.geometry import bilinear, tangent_frames
from ..visibility import HemicubeRenderer
from .elements import element_parameters

SKY_HEMICUBE_RESOLUTION = 64


def element_frames(patches: Patches, elements: int, rows: np.ndarray | None = None):
    """Hemi-cube frames at every element centre of the patches `rows` (None: all), flattened in
    element order [p, j, i]."""
    rows = np.arange(len(patches)) if rows is None else rows
    per_patch = elements * elements
    centres = bilinear(patches.corners[rows], *element_parameters(elements)).reshape(-1, 3)
    normals = np.repeat(patches.normal[rows], per_patch, axis=0)
    edges = np.repeat(patches.corners[rows, 1] - patches.corners[rows, 0], per_patch, axis=0)
    return tangent_frames(centres, normals, edges)


def sky_fractions(res: Resources, patches: Patches, hemicube_frames, resolution: int,
                  scene_diameter: float) -> np.ndarray:
    """Cosine-weighted fraction of the hemisphere at each frame that sees no surface (front or back)."""
    with res.gpu.resources() as scoped:
        renderer = HemicubeRenderer(scoped, patches, resolution, scene_diameter)
        count = len(hemicube_frames[0])
        fractions = np.empty(count)
        for first in range(0, count, renderer.slots):
            batch = tuple(v[first:first + renderer.slots] for v in hemicube_frames)
            fractions[first:first + len(batch[0])] = 1.0 - renderer.coverage(batch).sum(axis=1)
    return np.clip(fractions, 0.0, 1.0)
