"""The benchmark's scenes: the bundled Cornell box (reference: a converged Cycles bake) and two
analytic scenes whose exact answer is known in float64 at every point.

- `furnace`: a closed unit cube, inward faces, uniform ρ and E: B = E / (1 − ρ) everywhere.
- `plates`: a black emitting unit square facing a reflecting one at distance 1 (nothing else):
  B(x) = ρ · E · F(x → emitter), F by Lambert's contour integral (exact for a point).
"""

from __future__ import annotations

import numpy as np

from ..core.scene import Scene, scene_from_dict
from .texels import sample_parameters, surface_points

FURNACE_REFLECTANCE = 0.9
FURNACE_EMISSION = 1.0
PLATES_REFLECTANCE = 0.8
PLATES_EMISSION = 1.0

CUBE_FACES = {  # inward-facing (counter-clockwise seen from inside)
    "bottom": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    "top": [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]],
    "front": [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]],
    "back": [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]],
    "left": [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]],
    "right": [[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0]],
}


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


def point_to_polygon_form_factor(points: np.ndarray, normal: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Lambert's exact form factor from differential areas at `points` (…, 3) with `normal` to a polygon
    (k, 3) fully in front of them: F = |Σ_edges γ_k n · (r_k × r_k+1)/|r_k × r_k+1|| / 2π."""
    r = polygon[None] - points.reshape(-1, 1, 3)
    r_next = np.roll(r, -1, axis=1)
    cross = np.cross(r, r_next)
    unit_cross = cross / np.linalg.norm(cross, axis=2, keepdims=True)
    cosine = (r * r_next).sum(axis=2) / (np.linalg.norm(r, axis=2) * np.linalg.norm(r_next, axis=2))
    gamma = np.arccos(np.clip(cosine, -1, 1))
    total = (gamma * (unit_cross @ normal)).sum(axis=1)
    return np.abs(total).reshape(points.shape[:-1]) / (2 * np.pi)


def exact_texels(name: str, scene: Scene, resolution: int) -> np.ndarray:
    """(surfaces, R, R, 3) exact answer averaged over each texel, for the analytic scenes."""
    texels = np.zeros((len(scene.surfaces), resolution, resolution, 3))
    if name == "furnace":
        texels[:] = FURNACE_EMISSION / (1 - FURNACE_REFLECTANCE)
        return texels
    if name == "plates":
        receiver, emitter = scene.surfaces
        s, t = sample_parameters(resolution)
        factor = point_to_polygon_form_factor(surface_points(receiver, s, t), receiver.normal, emitter.vertices)
        texels[0] = (PLATES_REFLECTANCE * PLATES_EMISSION * factor.mean(axis=2))[..., None]
        texels[1] = PLATES_EMISSION
        return texels
    raise KeyError(f"no exact answer for scene '{name}'")


ANALYTIC_SCENES = {"furnace": furnace_scene, "plates": plates_scene}
