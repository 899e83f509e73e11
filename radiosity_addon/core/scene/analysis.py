"""Scene analysis: which effects a scene calls for, decided cheaply and conservatively before
any GPU work, so a solve simulates only those (the report's `effects`).

- channels: 1 when every reflectance and emission (and lamp and world colour) is grey, else 3;
- occlusion: False when no surface can hide any part of another — every surface lies in
  the closed front half-space of every other one (the inside of a convex room, two
  facing panels), so segments between surfaces stay inside a convex region bounded by
  their planes and cannot cross a third surface, and no sun or sky comes from outside;
- interreflection: False when no two reflective surfaces can see each other (a surface
  must have a vertex strictly in front of the other's plane, both ways): light then
  bounces at most once, B = E + ρ F E;
- rows: patches with zero reflectance receive nothing they could reflect, so neither a
  hemi-cube nor a linear-solve row is spent on them;
- back sides: a two-sided surface's back (Blender's faces all are) is simulated unless nothing
  lies strictly behind its plane (then whatever its back sends out or receives meets no
  surface), or it belongs to a closed, consistently oriented, outward-facing mesh with no
  emitter inside its bounds (the back faces the mesh's own dark inside).

The pairwise plane tests stop at the first pair that decides them (a furnished room: within
the first chunk) and answer "present" (simulate it) once they would cost more than
PAIR_BUDGET vertex-plane tests, so they never grow quadratically with the scene.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from .geometry import reversed_corners
from .model import Scene
from .topology import components

PLANE_TOLERANCE = 1e-6  # relative to the scene diameter
ROWS_PER_CHUNK = 256
CHUNK_TESTS = 2_000_000  # vertex-plane tests per chunk at most (a chunk's arrays stay near 16 MB each)
PAIR_BUDGET = 50_000_000  # vertex-plane tests before the analysis gives up and simulates


@dataclass(frozen=True)
class SceneEffects:
    emitters: int
    channels: int
    occlusion: bool
    interreflection: bool
    back_sides: int = 0  # two-sided surfaces whose back is simulated
    back_sides_skipped: int = 0  # two-sided surfaces whose back can neither send nor receive

    @classmethod
    def everything(cls, emitters: int, back_sides: int = 0) -> "SceneEffects":
        """The full simulation (what a solve does with skips disabled)."""
        return cls(emitters=emitters, channels=3, occlusion=True, interreflection=True, back_sides=back_sides)


def _plane_heights(scene: Scene, planes: slice, points: np.ndarray) -> np.ndarray:
    """heights[i, ...] = signed distance of `points` (..., 3) above the plane of surface i in `planes`."""
    anchors, normals = scene.corners[planes, 0], scene.normal[planes]
    flat = points.reshape(-1, 3)
    heights = flat @ normals.T - np.einsum("id,id->i", anchors, normals)[None, :]
    return heights.T.reshape((len(normals),) + points.shape[:-1])


def _chunks(count: int, width: int):
    """Slices of up to ROWS_PER_CHUNK rows, fewer where each row tests `width` points, so that a
    chunk's arrays have at most CHUNK_TESTS entries whatever the scene's size (a fixed number of
    rows, each against every corner, would take memory in proportion to the scene)."""
    rows = int(min(ROWS_PER_CHUNK, max(1, CHUNK_TESTS // max(width, 1))))
    for start in range(0, count, rows):
        yield slice(start, min(start + rows, count))


def is_grey(scene: Scene) -> bool:
    colours = [scene.reflectance, scene.emission, np.zeros((0, 3))]
    colours += [lamp.color[None] for lamp in scene.lamps] + [scene.world_color[None]]
    values = np.concatenate(colours)
    return bool(np.all(np.abs(values - values[:, :1]) <= 1e-12 * np.maximum(1.0, np.abs(values))))


def _inside_every_front(scene: Scene, points: np.ndarray) -> bool:
    """Do `points` (N, 3) lie in the closed front half-space of every surface?"""
    if len(points) == 0:
        return True
    tolerance = PLANE_TOLERANCE * scene.diameter
    return all(np.all(_plane_heights(scene, rows, points) >= -tolerance) for rows in _chunks(len(scene), len(points)))


def can_occlude(scene: Scene) -> bool:
    """Surfaces lying in front of every other surface's plane bound a convex region; lamps inside
    it (point, spot, area corners) reach everything unblocked. A sun and the sky come from
    outside: walls of such a room do block them (a card over a floor hides the sky from it), so
    either always counts as possible occlusion."""
    tolerance = PLANE_TOLERANCE * scene.diameter
    if len(scene) ** 2 * 4 > PAIR_BUDGET:
        return True  # too big to prove convex within the budget: simulate occlusion
    if any(np.any(_plane_heights(scene, rows, scene.corners) < -tolerance) for rows in _chunks(len(scene), 4 * len(scene))):
        return True
    lamps = scene.lamps
    if any(lamp.type == "sun" for lamp in lamps) or np.any(scene.world_color > 0):
        return True
    points = [lamp.position[None] for lamp in lamps if lamp.position is not None]
    points += [lamp.vertices for lamp in lamps if lamp.vertices is not None]
    return not _inside_every_front(scene, np.concatenate(points) if points else np.zeros((0, 3)))


def can_interreflect(scene: Scene) -> bool:
    """Two reflective surfaces, each with a vertex strictly in front of the other's plane."""
    reflective = np.flatnonzero(np.any(scene.reflectance > 0, axis=1))
    if len(reflective) < 2:
        return False
    tolerance = PLANE_TOLERANCE * scene.diameter
    corners = scene.corners[reflective]
    budget = PAIR_BUDGET
    for rows in _chunks(len(reflective), 4 * len(reflective)):
        if budget <= 0:
            return True  # undecided within the budget: simulate interreflection
        chosen = reflective[rows]
        # j rises in front of i, and i in front of j (vertices of i above j's plane)
        sees = np.any(_plane_heights(scene, chosen, corners) > tolerance, axis=2)  # (rows, R)
        seen = np.any(_plane_heights(scene, reflective, corners[rows]) > tolerance, axis=2).T  # (rows, R)
        mutual = sees & seen
        mutual[np.arange(len(chosen)), np.arange(rows.start, rows.stop)] = False
        if mutual.any():
            return True
        budget -= 2 * len(chosen) * len(reflective) * 4
    return False


def emitter_count(scene: Scene) -> int:
    """Emissive surfaces, lamps, and the world when it has a colour."""
    surfaces = int(np.any(scene.emission > 0, axis=1).sum())
    return surfaces + len(scene.lamps) + int(bool(np.any(scene.world_color > 0)))


def check_has_emitter(scene: Scene) -> None:
    """Refuse a scene with no emissive surface, no lamp that emits and no world colour."""
    if emitter_count(scene) == 0:
        raise SceneError(
            "scene: nothing emits light; give at least one surface a positive emission"
            " (an emissive material), a lamp or a world colour before baking"
        )


def _something_behind(scene: Scene, candidates: np.ndarray) -> np.ndarray:
    """(len(candidates),) bool: some surface corner lies strictly behind the candidate's plane
    (exactly when the pairs fit the budget, else tested on the scene's bounding box corners)."""
    tolerance = PLANE_TOLERANCE * scene.diameter
    if len(candidates) * len(scene) * 4 <= PAIR_BUDGET:
        points = scene.corners.reshape(-1, 3)
    else:
        low, high = scene.bounds
        points = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])
    behind = np.zeros(len(candidates), dtype=bool)
    for rows in _chunks(len(candidates), len(points)):
        behind[rows] = np.any(_plane_heights(scene, candidates[rows], points) < -tolerance, axis=1)
    return behind


def _emitters_inside(scene: Scene, parts) -> np.ndarray:
    """(components,) bool: an emitter of another component (an emissive surface's corner) or a lamp
    (position, area corners) lies within the component's bounding box."""
    emissive = np.flatnonzero(np.any(scene.emission > 0, axis=1))
    points = [scene.corners[emissive].reshape(-1, 3)]
    owners = [np.repeat(parts.label[emissive], 4)]
    lamp_points = [lamp.position[None] for lamp in scene.lamps if lamp.position is not None]
    lamp_points += [lamp.vertices for lamp in scene.lamps if lamp.vertices is not None]
    if lamp_points:
        points.append(np.concatenate(lamp_points))
        owners.append(np.full(len(points[-1]), -1))
    points, owners = np.concatenate(points), np.concatenate(owners)
    lit = np.zeros(parts.count, dtype=bool)
    if len(points) == 0:
        return lit
    for rows in _chunks(parts.count, 3 * len(points)):
        ids = np.arange(rows.start, rows.stop)
        inside = np.all((points[None] >= parts.low[rows, None]) & (points[None] <= parts.high[rows, None]), axis=2)
        lit[rows] = np.any(inside & (owners[None] != ids[:, None]), axis=1)
    return lit


def simulated_backs(scene: Scene, skip_unneeded: bool = True) -> np.ndarray:
    """(S,) bool: the two-sided surfaces whose back side the solve simulates (module doc)."""
    two_sided = scene.two_sided.copy()
    if not skip_unneeded or not two_sided.any():
        return two_sided
    candidates = np.flatnonzero(two_sided)
    keep = _something_behind(scene, candidates)
    parts = components(scene)
    dark_inside = parts.closed & (parts.volume > 0) & ~_emitters_inside(scene, parts)
    keep &= ~dark_inside[parts.label[candidates]]
    backs = np.zeros(len(scene), dtype=bool)
    backs[candidates[keep]] = True
    return backs


def with_backs(scene: Scene, backs: np.ndarray) -> Scene:
    """The scene with the simulated backs as surfaces of their own (reversed), for the plane tests."""
    if not backs.any():
        return scene
    flipped = reversed_corners(scene.corners[backs], scene.is_triangle[backs])
    index = np.concatenate([np.arange(len(scene)), np.flatnonzero(backs)])
    return Scene(names=[scene.names[i] for i in index], corners=np.concatenate([scene.corners, flipped]),
                 corner_count=scene.corner_count[index], reflectance=scene.reflectance[index],
                 emission=scene.emission[index], object_index=scene.object_index[index],
                 object_names=scene.object_names, uv=scene.uv[index], has_uv=scene.has_uv[index],
                 two_sided=np.zeros(len(index), dtype=bool), extras=scene.extras,
                 opacity=None if scene.opacity is None else scene.opacity.rows(index))


def analyse(scene: Scene, backs: np.ndarray | None = None) -> SceneEffects:
    backs = simulated_backs(scene) if backs is None else backs
    sided = with_backs(scene, backs)
    return SceneEffects(
        emitters=emitter_count(scene),
        channels=1 if is_grey(scene) else 3,
        occlusion=can_occlude(sided),
        interreflection=can_interreflect(sided),
        back_sides=int(backs.sum()),
        back_sides_skipped=int(scene.two_sided.sum() - backs.sum()),
    )


def effects_for(scene: Scene, skip_unneeded: bool, backs: np.ndarray | None = None) -> tuple[SceneEffects, np.ndarray]:
    """What to simulate — the analysis, or everything when skips are disabled — and the mask of
    surfaces whose back is simulated (`backs` when given: decided on the faces the surfaces stand for)."""
    backs = simulated_backs(scene, skip_unneeded) if backs is None else backs
    if not skip_unneeded:
        return SceneEffects.everything(emitter_count(scene), int(backs.sum())), backs
    return analyse(scene, backs), backs
