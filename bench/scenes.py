"""The benchmark's scenes: the bundled Cornell box (reference: a converged Cycles bake) and two
analytic scenes whose exact answer is known in float64 at every point.

- `furnace`: a closed unit cube, inward faces, uniform ρ and E: B = E / (1 − ρ) everywhere.
- `plates`: a black emitting unit square facing a reflecting one at distance 1 (nothing else):
  B(x) = ρ · E · F(x → emitter), F by Lambert's contour integral (exact for a point).
"""

from __future__ import annotations

import numpy as np

from radiosity_addon.core import Scene, point_to_polygon, scene_from_dict
from .texels import sample_parameters, surface_points

FURNACE_REFLECTANCE = 0.9
FURNACE_EMISSION = 1.0
PLATES_REFLECTANCE = 0.8
PLATES_EMISSION = 1.0

# the unit cube, every face's front inside (counter-clockwise seen from inside)
CUBE_FACES = {
    "floor": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    "ceiling": [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]],
    "x0": [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]],
    "x1": [[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0]],
    "y0": [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]],
    "y1": [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]],
}


def opposed_rectangles_form_factor(a: float, b: float, c: float) -> float:
    """Exact F between opposed equal a x b rectangles at distance c (docs/architecture.md, Oracles)."""
    x, y = a / c, b / c
    return 2 / (np.pi * x * y) * (
        np.log(np.sqrt((1 + x * x) * (1 + y * y) / (1 + x * x + y * y)))
        + x * np.sqrt(1 + y * y) * np.arctan(x / np.sqrt(1 + y * y))
        + y * np.sqrt(1 + x * x) * np.arctan(y / np.sqrt(1 + x * x))
        - x * np.arctan(x) - y * np.arctan(y)
    )


def furnace_scene(reflectance: float = FURNACE_REFLECTANCE, emission: float = FURNACE_EMISSION,
                  scale: float = 1.0) -> Scene:
    return scene_from_dict({"surfaces": [
        {"name": name, "vertices": (np.asarray(v, dtype=float) * scale).tolist(),
         "reflectance": [reflectance] * 3, "emission": [emission] * 3}
        for name, v in CUBE_FACES.items()
    ]})


def plates_scene(distance: float = 1.0) -> Scene:
    return scene_from_dict({"surfaces": [
        {"name": "receiver", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
         "reflectance": [PLATES_REFLECTANCE] * 3, "emission": [0, 0, 0]},
        {"name": "emitter", "vertices": [[0, 0, distance], [0, 1, distance], [1, 1, distance], [1, 0, distance]],
         "reflectance": [0, 0, 0], "emission": [PLATES_EMISSION] * 3},
    ]})


def exact_texels(name: str, scene: Scene, resolution: int) -> np.ndarray:
    """(surfaces, R, R, 3) exact answer averaged over each texel, for the analytic scenes."""
    texels = np.zeros((len(scene.surfaces), resolution, resolution, 3))
    if name == "furnace":
        texels[:] = FURNACE_EMISSION / (1 - FURNACE_REFLECTANCE)
        return texels
    if name == "plates":
        receiver, emitter = scene.surface(0), scene.surface(1)
        s, t = sample_parameters(resolution)
        factor = point_to_polygon_form_factor(surface_points(receiver, s, t), receiver.normal, emitter.vertices)
        texels[0] = (PLATES_REFLECTANCE * PLATES_EMISSION * factor.mean(axis=2))[..., None]
        texels[1] = PLATES_EMISSION
        return texels
    raise KeyError(f"no exact answer for scene '{name}'")


ANALYTIC_SCENES = {"furnace": furnace_scene, "plates": plates_scene}


def point_to_polygon_form_factor(points: np.ndarray, normal: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Lambert's exact form factor from differential areas at `points` (..., 3), all with `normal`,
    to one polygon (k, 3) in front of them (core.point_to_polygon)."""
    flat = points.reshape(-1, 3)
    factor = point_to_polygon(flat, np.broadcast_to(normal, flat.shape), np.asarray(polygon, dtype=float)[None])
    return factor[:, 0].reshape(points.shape[:-1])
