"""The world colour as shooters: a uniform sky L lights a point with L times its sky fraction, the
cosine-weighted part of its hemisphere that sees no surface. That fraction is gathered from
SKY_DIRECTIONS suns spread evenly over the sphere (a Fibonacci lattice), each of irradiance
L 4π / SKY_DIRECTIONS and with its own orthographic visibility map of the scene's surfaces: a
point's light is then sum_k L (4π / N) cos θ_k V_k / π, the sky integral's even sampling. Its cost
is N maps of the surfaces and N passes over the points: linear in both, where a hemi-cube at every
point drew the whole scene once per point."""

from __future__ import annotations

import numpy as np

from ..timing import pulse

from ..gpu import Resources
from ..scene import Patches
from ..scene.geometry import bilinear, tangent_frame, tangent_frames
from .shooters import DIRECTIONAL, Shooter
from ..visibility import HemicubeRenderer
from .elements import element_parameters

SKY_HEMICUBE_RESOLUTION = 64
SKY_DIRECTIONS = 1024  # suns the world's light comes from (half light an upward face): within 2 % of the exact fraction
SKY_MAP_RESOLUTION = 256  # pixels across each of their orthographic maps


def sky_shooters(color, scene_centre: np.ndarray, scene_diameter: float, count: int = SKY_DIRECTIONS) -> list:
    """The world colour `color` as `count` suns (module doc)."""
    k = np.arange(count) + 0.5
    height = 1.0 - 2.0 * k / count
    around = np.pi * (1.0 + 5.0 ** 0.5) * k
    ring = np.sqrt(1.0 - height ** 2)
    towards = np.stack([ring * np.cos(around), ring * np.sin(around), height], axis=1)  # towards the sky
    irradiance = np.asarray(color, dtype=np.float64) * 4.0 * np.pi / count
    return [Shooter(position=scene_centre + d * scene_diameter, axes=(*tangent_frame(-d), -d), polygon=np.zeros((4, 3)),
                    area=0.0, radiosity=irradiance, kind=DIRECTIONAL, light_direction=tuple(-d),
                    ortho_extent=scene_diameter / 2) for d in towards]


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
            pulse()
            batch = tuple(v[first:first + renderer.slots] for v in hemicube_frames)
            fractions[first:first + len(batch[0])] = 1.0 - renderer.coverage(batch).sum(axis=1)
    return np.clip(fractions, 0.0, 1.0)
