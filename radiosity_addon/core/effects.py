"""Scene analysis: which effects a scene calls for, decided cheaply and conservatively
before any GPU work, so a solve simulates only those (the report's `effects`).

- channels: 1 when every reflectance and emission (and lamp and world colour) is grey, else 3;
- occlusion: False when no surface can hide any part of another — every surface lies in
  the closed front half-space of every other one (the inside of a convex room, two
  facing panels), so segments between surfaces stay inside a convex region bounded by
  their planes and cannot cross a third surface;
- interreflection: False when no two reflective surfaces can see each other (a surface
  must have a vertex strictly in front of the other's plane, both ways): light then
  bounces at most once, B = E + ρ F E;
- rows: patches with zero reflectance receive nothing they could reflect, so neither a
  hemi-cube nor a linear-solve row is spent on them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .lights import scene_lamps, world_color
from .scene import Scene

PLANE_TOLERANCE = 1e-6  # relative to the scene diameter
ROWS_PER_CHUNK = 256


@dataclass(frozen=True)
class SceneEffects:
    emitters: int
    channels: int
    occlusion: bool
    interreflection: bool

    @classmethod
    def everything(cls, emitters: int) -> "SceneEffects":
        """The full simulation (what a solve does with skips disabled)."""
        return cls(emitters=emitters, channels=3, occlusion=True, interreflection=True)


def _surface_vertices(scene: Scene) -> np.ndarray:
    """(S, 4, 3) vertices, triangles padded by repeating their last vertex."""
    return np.stack([np.concatenate([s.vertices, s.vertices[-1:]])[:4] for s in scene.surfaces])


def _front_heights(scene: Scene):
    """Yield (rows, heights) with heights[i, j, k] = signed distance of vertex k of surface j
    above the plane of surface i, for chunks of surfaces i (bounded memory)."""
    vertices = _surface_vertices(scene)
    normals = np.stack([s.normal for s in scene.surfaces])
    anchors = vertices[:, 0]
    for start in range(0, len(vertices), ROWS_PER_CHUNK):
        rows = slice(start, start + ROWS_PER_CHUNK)
        offsets = vertices[None, :, :, :] - anchors[rows, None, None, :]
        yield rows, np.einsum("ijkd,id->ijk", offsets, normals[rows])


def is_grey(scene: Scene) -> bool:
    colours = [s.reflectance for s in scene.surfaces] + [s.emission for s in scene.surfaces]
    colours += [lamp.color for lamp in scene_lamps(scene)] + [world_color(scene)]
    values = np.stack(colours)
    return bool(np.all(np.abs(values - values[:, :1]) <= 1e-12 * np.maximum(1.0, np.abs(values))))


def _inside_every_front(scene: Scene, points: np.ndarray) -> bool:
    """Do `points` (N, 3) lie in the closed front half-space of every surface?"""
    if len(points) == 0:
        return True
    normals = np.stack([s.normal for s in scene.surfaces])
    anchors = np.stack([s.vertices[0] for s in scene.surfaces])
    heights = np.einsum("snd,sd->sn", points[None, :, :] - anchors[:, None, :], normals)
    return bool(np.all(heights >= -PLANE_TOLERANCE * scene.diameter))


def can_occlude(scene: Scene) -> bool:
    """Surfaces lying in front of every other surface's plane bound a convex region; lamps inside
    it (point, spot, area corners) reach everything unblocked. A sun comes from outside: walls
    of such a room do block it, so a sun always counts as possible occlusion."""
    tolerance = PLANE_TOLERANCE * scene.diameter
    if any(np.any(heights < -tolerance) for _, heights in _front_heights(scene)):
        return True
    lamps = scene_lamps(scene)
    if any(lamp.type == "sun" for lamp in lamps):
        return True
    points = [lamp.position[None] for lamp in lamps if lamp.position is not None]
    points += [lamp.vertices for lamp in lamps if lamp.vertices is not None]
    return not _inside_every_front(scene, np.concatenate(points) if points else np.zeros((0, 3)))


def can_interreflect(scene: Scene) -> bool:
    reflective = np.array([np.any(s.reflectance > 0) for s in scene.surfaces])
    if reflective.sum() < 2:
        return False
    tolerance = PLANE_TOLERANCE * scene.diameter
    sees = np.zeros((len(reflective), len(reflective)), dtype=bool)
    for rows, heights in _front_heights(scene):
        sees[rows] = np.any(heights > tolerance, axis=2)  # surface j rises in front of i
    mutual = sees & sees.T & reflective[:, None] & reflective[None, :]
    np.fill_diagonal(mutual, False)
    return bool(mutual.any())


def emitter_count(scene: Scene) -> int:
    """Emissive surfaces, lamps, and the world when it has a colour."""
    surfaces = sum(bool(np.any(s.emission > 0)) for s in scene.surfaces)
    return int(surfaces + len(scene_lamps(scene)) + bool(np.any(world_color(scene) > 0)))


def analyse(scene: Scene) -> SceneEffects:
    return SceneEffects(
        emitters=emitter_count(scene),
        channels=1 if is_grey(scene) else 3,
        occlusion=can_occlude(scene),
        interreflection=can_interreflect(scene),
    )


def effects_for(scene: Scene, skip_unneeded: bool) -> SceneEffects:
    """What to simulate: the analysis, or everything when skips are disabled."""
    return analyse(scene) if skip_unneeded else SceneEffects.everything(emitter_count(scene))


def effects_summary(report: dict) -> str:
    """One line saying what a solve simulated and skipped (the Blender panel shows it)."""
    effects = report.get("effects", {})
    said = [f"{effects.get('channels_solved', effects.get('channels', 3))} channel(s)",
            "occlusion" if effects.get("occlusion", True) else "no occlusion (skipped)",
            "interreflection" if effects.get("interreflection", True) else "direct light only",
            f"{effects.get('emitters', 0)} emitter(s)"]
    work = report.get("shots")
    if work is not None:
        said.append(f"{work} shots")
    elif "hemicubes" in effects:
        said.append(f"{effects['hemicubes']} hemi-cubes")
    total = report.get("timings", {}).get("total")
    if total is not None:
        said.append(f"{total:.1f} s")
    return " · ".join(said)
