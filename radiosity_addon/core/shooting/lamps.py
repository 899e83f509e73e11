"""Lamps as shooters: a point lamp two hemispheres from its position, a spot of cone <= 180°
one, a sun one orthographic view from outside the scene, an area lamp its polygon in pieces."""

from __future__ import annotations

import math

import numpy as np

from ..scene import Lamp
from ..scene.geometry import bilinear, polygon_area_vector, tangent_frame
from .shooters import DIRECTIONAL, POINT_LAMP, POLYGON, Shooter

AREA_LAMP_PIECE = 1 / 64  # longest side of an area lamp's or emitter's pieces, as a fraction of the scene's size
AREA_LAMP_MAX_SPLIT = 8  # pieces per side at most


def lamp_shooters(lamp: Lamp, scene_centre: np.ndarray, scene_diameter: float,
                  max_split: int = AREA_LAMP_MAX_SPLIT, sun_directions: int = 1) -> list[Shooter]:
    """The shots of one lamp (see the module doc); a sun with an angle in `sun_directions`."""
    if lamp.type in ("point", "spot"):
        cone = lamp.type == "spot"
        cos_half = math.cos(lamp.spot_size / 2) if cone else -2.0
        axis = lamp.direction if cone else np.array([0.0, 0.0, 1.0])
        poles = [axis] if cone and lamp.spot_size <= math.pi else [axis, -axis]
        return [Shooter(position=lamp.position, axes=(*tangent_frame(pole), pole), polygon=np.zeros((4, 3)),
                        area=0.0, radiosity=lamp.intensity, kind=POINT_LAMP, light_direction=tuple(axis),
                        spot_cos_half=cos_half, spot_smooth=(1 - cos_half) * lamp.spot_blend if cone else 0.0)
                for pole in poles]
    if lamp.type == "sun":
        directions = sun_disc(lamp.direction, lamp.angle, sun_directions if lamp.angle > 0 else 1)
        irradiance = lamp.color * lamp.strength / len(directions)
        return [Shooter(position=scene_centre - d * scene_diameter, axes=(*tangent_frame(d), d),
                        polygon=np.zeros((4, 3)), area=0.0, radiosity=irradiance, kind=DIRECTIONAL,
                        light_direction=tuple(d), ortho_extent=scene_diameter / 2) for d in directions]
    return polygon_shooters(lamp.vertices, lamp.area_radiance, scene_diameter, max_split=max_split)


def sun_disc(direction: np.ndarray, angle: float, count: int) -> np.ndarray:
    """(count, 3) unit directions of light spread evenly over a sun's disc of angular diameter
    `angle` around `direction` (a Vogel spiral: equal areas of the disc, as Cycles samples it
    uniformly), so a leaf's shadow has the penumbra it has in Cycles; one: `direction` itself."""
    direction = np.asarray(direction, dtype=np.float64)
    if count <= 1:
        return direction[None]
    k = np.arange(count) + 0.5
    radius = math.tan(angle / 2) * np.sqrt(k / count)
    around = math.pi * (3.0 - math.sqrt(5.0)) * k
    u, v = tangent_frame(direction)
    spread = direction + radius[:, None] * (np.cos(around)[:, None] * u + np.sin(around)[:, None] * v)
    return spread / np.linalg.norm(spread, axis=1, keepdims=True)


def polygon_shooters(corners: np.ndarray, radiance: np.ndarray, scene_diameter: float, patch: int = -1,
                     max_split: int = AREA_LAMP_MAX_SPLIT) -> list[Shooter]:
    """An emitting polygon (4, 3) (a triangle repeats its last corner) split into pieces, each with
    its own visibility map, so shadows keep their penumbra (one map from the centre turns a nearby
    object's penumbra into umbra): pieces at most AREA_LAMP_PIECE of the scene, `max_split` x
    `max_split` at most.
    `patch`: the patch the polygon is (left out of its own maps), -1 for a lamp."""
    normal = polygon_area_vector(corners)
    normal = normal / np.linalg.norm(normal)
    sides = np.linalg.norm(np.roll(corners, -1, axis=0) - corners, axis=1)
    split = int(np.clip(np.ceil(sides.max() / (scene_diameter * AREA_LAMP_PIECE)), 1, max_split))
    grid = np.arange(split + 1) / split
    s0, t0 = np.meshgrid(grid[:-1], grid[:-1])
    offsets = np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) / split
    pieces = bilinear(corners[None], s0.ravel()[:, None] + offsets[:, 0], t0.ravel()[:, None] + offsets[:, 1])[0]
    x_axis = tangent_frame(normal, corners[1] - corners[0])
    areas = np.linalg.norm(0.5 * np.cross(pieces[:, 2] - pieces[:, 0], pieces[:, 3] - pieces[:, 1]), axis=1)
    count = int((areas > 0).sum())
    whole = np.array(corners, dtype=np.float64) if count > 1 else None
    return [Shooter(position=piece.mean(axis=0), axes=(*x_axis, normal), polygon=piece, area=float(area),
                    radiosity=np.asarray(radiance, dtype=np.float64), kind=POLYGON, patch=patch, whole=whole,
                    pieces=count)
            for piece, area in zip(pieces, areas) if area > 0]
