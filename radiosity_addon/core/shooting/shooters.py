"""Shooters: what a shot carries — a patch's unshot radiosity, a lamp, the sun, the sky — as
geometry (position, frame, polygon, area) and power. The shooting pass needs nothing else."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Patches
from ..scene.geometry import bilinear, tangent_axes

# shooter kinds, as shoot_to_elements.comp knows them
POLYGON, POINT_LAMP, DIRECTIONAL, SKY = 0, 1, 2, 3


@dataclass
class Shooter:
    position: np.ndarray  # (3,) eye of its visibility map
    axes: tuple  # (x, y, normal) orthonormal
    polygon: np.ndarray  # (4, 3) corners, counter-clockwise from the front
    area: float
    radiosity: np.ndarray  # (3,) unshot radiosity being shot (a point lamp: intensity; a sun: irradiance)
    patch: int = -1  # the patch whose residual this shot clears (a cluster's index when `cluster`)
    kind: int = POLYGON
    light_direction: tuple = (0.0, 0.0, -1.0)  # spot axis / sun travel direction
    spot_cos_half: float = -1.0  # -1: no cone
    spot_smooth: float = 0.0
    ortho_extent: float = 0.0  # > 0: orthographic visibility map (sun)
    cluster: int = 0  # > 0: `patch` is a cluster of patches at this level (progressive.clusters), all of whose residuals it shoots
    whole: np.ndarray | None = None  # (4, 3): the emitting polygon this is one of `pieces` pieces of (None: whole)
    pieces: int = 1

    @property
    def power(self) -> np.ndarray:
        return self.area * self.radiosity


class PatchShooters:
    """Patches as shooters: their geometry computed once per solve, a `Shooter` per shot."""

    def __init__(self, patches: Patches):
        self.corners = patches.corners
        self.normal = patches.normal
        self.center = patches.center
        self.area = patches.area
        self.x, self.y = tangent_axes(self.normal, self.corners[:, 1] - self.corners[:, 0])

    def shooter(self, index: int, radiosity: np.ndarray, eye_parameters=None) -> Shooter:
        """Patch `index` shooting `radiosity`; its visibility map is rendered from its centre, or
        from the bilinear point at `eye_parameters` (s, t) (the centroid of its unshot power)."""
        normal, x, y = self.normal[index], self.x[index], self.y[index]
        if eye_parameters is None:
            position = self.center[index]
        else:
            position = bilinear(self.corners[index:index + 1], np.float64(eye_parameters[0]),
                                np.float64(eye_parameters[1]))[0]
        return Shooter(position=position, axes=(x, y, normal), polygon=self.corners[index],
                       area=float(self.area[index]), radiosity=np.asarray(radiosity, dtype=np.float64), patch=index)
