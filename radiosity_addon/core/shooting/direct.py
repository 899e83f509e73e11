"""Light from lamps, the emitters and the world, straight to what receives it: the piece both
methods share.

Progressive refinement shoots the lamps and the sky into its element textures before its first
patch shot (what receivers reflect of it becomes unshot radiosity); the hemi-cube method measures
all of the direct light at points of every patch (`direct_light_at_elements`: lamps, the sun and
the emitters in pieces, each with its own visibility, and the sky) and solves only for what is
reflected, (I − ρF) R = ρ D, B = E + R; refinement's probe is the same measurement.

The direct light — lamps, the sun and the emissive patches, not the sky — is also what the
lightmaps recompute texel by texel (`direct_shooters`, `texel_pass`): the solve records how much
of its element light it is, so only the smooth rest is interpolated.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..gpu import Resources
from ..scene import Patches, Scene, surface_patches
from ..scene.geometry import tangent_frames
from ..scene.geometry import reversed_corners
from .lamps import AREA_LAMP_MAX_SPLIT, lamp_shooters, polygon_shooters
from .shooters import Shooter
from .shooting_pass import ShootingPass
from .shots import MAX_SHOTS, surface_visibility
from .sky import (SKY_DIRECTIONS, SKY_HEMICUBE_RESOLUTION, SKY_MAP_RESOLUTION, element_frames, sky_fractions,
                  sky_shooters)
from .texel_pass import TexelReceivers


@dataclass
class DirectLightWork:
    """What shooting the lamps and the sky cost (the report's effects)."""
    lamps: int = 0
    lamp_visibility_maps: int = 0
    sky_maps: int = 0  # the sky's orthographic maps (shooting.sky)
    emitter_pieces: int = 0  # the hemi-cube method's direct light: the emitters' shots


SKY_PROBE = 2  # points along a patch side where the direct light's measurement takes the sky fraction
MAX_SPLIT_EMITTERS = 64  # emitting polygons split into pieces for the texel pass; beyond, one shot each
SOLVE_EMITTER_PIECES = 256  # the solve's element light needs fewer: about this many pieces in all


def lamps_as_shooters(scene: Scene, max_split: int = AREA_LAMP_MAX_SPLIT, sun_directions: int = 1) -> list[Shooter]:
    """Every lamp's shots (an area lamp in at most `max_split` x `max_split` pieces, a sun with an
    angle in `sun_directions` over its disc)."""
    low, high = scene.bounds
    return [shooter for lamp in scene.lamps
            for shooter in lamp_shooters(lamp, (low + high) / 2, scene.diameter, max_split, sun_directions)]


def emitter_pieces(scene: Scene, patches: Patches, occlusion: bool = True,
                   budget: int = SOLVE_EMITTER_PIECES) -> list[Shooter]:
    """The solve's shots of the emitters' own emission (`emitting_polygons`, strongest first), in
    pieces so that the elements' shadows keep their penumbra: about `budget` pieces for the
    polygons facing one way and as many for their backs (8 x 8 at most each); whole where nothing
    occludes. They shoot for no patch: the emission is not in the residual (`ElementTextures`)."""
    polygons = emitting_polygons(scene, patches)
    power = [np.linalg.norm(np.cross(c[2] - c[0], c[3] - c[1])) / 2 * e.sum() for c, e, *_ in polygons]
    fronts = sum(1 for _, _, _, back, _ in polygons if not back)
    split = int(np.clip(np.sqrt(budget / max(fronts, 1)), 1, AREA_LAMP_MAX_SPLIT)) if occlusion else 1
    return [piece for k in np.argsort(-np.asarray(power), kind="stable")
            for piece in polygon_shooters(polygons[k][0], polygons[k][1], scene.diameter, max_split=split)]


def emitting_polygons(scene: Scene, patches: Patches) -> list[tuple[np.ndarray, np.ndarray, int, bool, np.ndarray]]:
    """(corners (4, 3), emission (3,), patch or -1, a back, the patches it is) of what emits:
    each side of an emissive surface whole when its patches all emit alike (its light does not
    depend on how refinement split it), else its patches one by one (a textured emission)."""
    emitting = np.flatnonzero(np.any(patches.emission > 0, axis=1))
    side = patches.surface[emitting] * 2 + patches.is_back[emitting]
    order = np.argsort(side, kind="stable")
    groups = np.split(emitting[order], np.flatnonzero(np.diff(side[order])) + 1) if len(emitting) else []
    polygons = []
    for group in groups:
        emission = patches.emission[group]
        if len(group) > 1 and np.allclose(emission, emission[0], rtol=1e-6, atol=0.0):
            surface = int(patches.surface[group[0]])
            corners = scene.corners[surface:surface + 1]
            if patches.is_back[group[0]]:
                corners = reversed_corners(corners, scene.corner_count[surface:surface + 1] == 3)
            polygons.append((corners[0], emission[0], -1, bool(patches.is_back[group[0]]), group))
        else:
            polygons.extend((patches.corners[p], patches.emission[p], int(p), bool(patches.is_back[p]), group[k:k + 1])
                            for k, p in enumerate(group))
    return polygons


def piece_means(pieces: list[Shooter], centres: np.ndarray, areas: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(len(pieces), 3) the area-weighted mean of `values` (n, 3) over the patches (centres (n, 3),
    areas (n,)) nearest each piece's centre; a piece nearest to none takes the mean of all."""
    positions = np.array([piece.position for piece in pieces])
    nearest = np.argmin(((centres[:, None] - positions[None]) ** 2).sum(axis=2), axis=1)
    weight = np.bincount(nearest, areas, len(pieces))
    sums = np.stack([np.bincount(nearest, areas * values[:, c], len(pieces)) for c in range(3)], axis=1)
    overall = (areas[:, None] * values).sum(axis=0) / max(float(areas.sum()), 1e-300)
    return np.where(weight[:, None] > 0, sums / np.maximum(weight, 1e-300)[:, None], overall)


def emitter_shooters(scene: Scene, patches: Patches, max_split: int, reflected: np.ndarray | None = None,
                     emission: bool = True) -> list[Shooter]:
    """The emitting polygons' shots in pieces, at most `max_split` x `max_split` each (one piece
    each when there are more than MAX_SPLIT_EMITTERS of them), each sending its emission (unless
    not `emission`) plus the mean over its patches of `reflected` (P, 3): what an emitter
    reflects lights what faces it as sharply as what it emits (a ceiling 5 mm over a light's
    back gets both, the light's texels change within a gap of its outline). Polygons that would
    send nothing are left out."""
    polygons = emitting_polygons(scene, patches)
    size = scene.diameter if len(polygons) <= MAX_SPLIT_EMITTERS else np.inf
    shooters = []
    for corners, emitted, patch, _, members in polygons:
        pieces = polygon_shooters(corners, emitted if emission else np.zeros(3), size, patch=patch, max_split=max_split)
        if reflected is not None:
            extra = piece_means(pieces, patches.center[members], patches.area[members], reflected[members])
            pieces = [replace(piece, radiosity=piece.radiosity + more) for piece, more in zip(pieces, extra)]
        if any(np.any(piece.radiosity > 0) for piece in pieces):
            shooters.extend(pieces)
    return shooters


def direct_shooters(scene: Scene, patches: Patches, max_split: int = AREA_LAMP_MAX_SPLIT,
                    reflected: np.ndarray | None = None, sun_directions: int = 1) -> list[Shooter]:
    """Every shot of the lightmaps' direct light: the lamps' (a sun with an angle in
    `sun_directions`), and the emitting polygons' in pieces (`emitter_shooters`, with what they
    reflect of `reflected` (P, 3) when given)."""
    return (lamps_as_shooters(scene, max_split, sun_directions)
            + emitter_shooters(scene, patches, max_split, reflected))


def shoot_lamps(scene: Scene, shooting: ShootingPass) -> DirectLightWork:
    """Shoot every lamp once."""
    before = shooting.visibility_source.maps_rendered
    shooting.shoot_all(lamps_as_shooters(scene))
    return DirectLightWork(lamps=len(scene.lamps), lamp_visibility_maps=shooting.visibility_source.maps_rendered - before)


def shoot_sky(res: Resources, scene: Scene, patches: Patches, elements: int, shooting: ShootingPass,
              work: DirectLightWork) -> None:
    """Every element gathers the world colour times its sky fraction (`sky_light`)."""
    sky = scene.world_color
    if np.any(sky > 0):
        points = element_frames(patches, elements)[0]
        owners = np.repeat(np.arange(len(patches)), elements * elements)
        fractions = sky_light(res, scene, patches, points, owners, np.ones(3))[:, 0]
        work.sky_maps = SKY_DIRECTIONS
        shooting.shoot_sky(sky, fractions)


def sky_light(res: Resources, scene: Scene, patches: Patches, points: np.ndarray, owners: np.ndarray,
              color) -> np.ndarray:
    """(N, 3) the light a uniform sky of `color` sends to `points` on the patches `owners`: their sky
    fractions from a hemi-cube of the surfaces at each point where the points are fewer than the
    sky's directions, else from the directions' maps (`sky.sky_shooters`). Each costs the surfaces
    drawn once per hemi-cube or once per direction (about alike a time), and both are within 2 %
    of the exact fraction (tests/core/test_lights.py)."""
    if len(points) <= SKY_DIRECTIONS:
        frames = tangent_frames(points, patches.normal[owners], patches.corners[owners, 1] - patches.corners[owners, 0])
        fractions = sky_fractions(res, surface_patches(scene, patches), frames, SKY_HEMICUBE_RESOLUTION, scene.diameter)
        return fractions[:, None] * np.asarray(color, dtype=np.float64)
    low, high = scene.bounds
    return light_at_points(res, scene, patches, points, owners, sky_shooters(color, (low + high) / 2, scene.diameter),
                           "hemicube", SKY_MAP_RESOLUTION, True)


def light_at_points(res: Resources, scene: Scene, patches: Patches, points: np.ndarray, owners: np.ndarray,
                    shooters: list[Shooter], visibility: str, resolution: int, occlusion: bool,
                    capacity: int = MAX_SHOTS) -> np.ndarray:
    """(N, 3) light H that `points` (N, 3) lying on the patches `owners` (N,) gather from
    `shooters` (lamps, the sun, emitters' pieces), each shot with its own visibility map of
    `resolution` (the `visibility` variant): the texel pass, for lightmap texels and for
    refinement's probe points alike."""
    return light_at_receivers(res, scene, patches, points, patches.normal[owners], patches.plane[owners], shooters,
                              visibility, resolution, occlusion, capacity)


def light_at_receivers(res: Resources, scene: Scene, patches: Patches, points: np.ndarray, normals: np.ndarray,
                       planes: np.ndarray, shooters: list[Shooter], visibility: str, resolution: int, occlusion: bool,
                       capacity: int = MAX_SHOTS, clusters=None) -> np.ndarray:
    """(N, 3) light H that `points` (N, 3) with `normals` (N, 3), looked up as points of the
    surface sides `planes` (N,) (`Patches.plane`), gather from `shooters` (`light_at_points`);
    with `clusters` the clusters' faces are drawn for their rectangles (`surface_visibility`)."""
    if not shooters or len(points) == 0:
        return np.zeros((len(points), 3))
    with res.gpu.resources() as scoped:
        shots = surface_visibility(scoped, scene, patches, resolution, visibility, occlusion, capacity, clusters)
        receivers = TexelReceivers(scoped, points, normals, planes, "exact", shots)
        receivers.shoot_all(shooters)
        return receivers.read_light()


def patch_scale_shots(scene: Scene, patches: Patches, occlusion: bool, pieces: int) -> list[Shooter]:
    """The direct light's shots where it is measured on patches (refinement's probe, the hemi-cube
    method's direct light): lamps (an area lamp in up to `pieces` x `pieces`), the sun, and the
    emitters in about `pieces`² pieces a side."""
    return lamps_as_shooters(scene, pieces) + emitter_pieces(scene, patches, occlusion, pieces * pieces)


def direct_light_at_elements(res: Resources, scene: Scene, patches: Patches, rows: np.ndarray, shooters: list[Shooter],
                             visibility: str, visibility_res: int, occlusion: bool, elements: int,
                             capacity: int = MAX_SHOTS) -> tuple[np.ndarray, np.ndarray]:
    """(len(rows), S, S, 3) direct light H at the S x S element centres of the patches `rows` from
    `shooters` (`patch_scale_shots`), each with its own visibility, and (the same shape) from the sky:
    the world colour times each point's sky fraction, measured at SKY_PROBE x SKY_PROBE points a patch
    (each element takes its quarter's: the sky's light bends slowly, and a hemi-cube per point
    costs as much as the scene's surfaces)."""
    frames = element_frames(patches, elements, rows)
    points, owners = frames[0], np.repeat(rows, elements * elements)
    light = light_at_points(res, scene, patches, points, owners, shooters, visibility, visibility_res, occlusion,
                            capacity=capacity)
    shape = (len(rows), elements, elements, 3)
    sky = np.zeros(shape)
    if np.any(scene.world_color > 0) and len(points):
        probed = min(elements, SKY_PROBE)
        at = element_frames(patches, probed, rows)[0]
        measured = sky_light(res, scene, patches, at, np.repeat(rows, probed * probed), scene.world_color)
        nearest = np.arange(elements) * probed // elements  # the probed point of each element's quarter
        sky = measured.reshape(len(rows), probed, probed, 3)[:, nearest][:, :, nearest]
    return light.reshape(shape), sky


@dataclass
class MeasuredDirectLight:
    """Direct light measured at the S x S element centres of every patch (refinement's probe), for
    the hemi-cube method to take instead of measuring it again: from `shooters` and from the sky,
    (P, S, S, 3) each; `known` (P,) False for patches made after the last measurement."""
    shots: np.ndarray
    sky: np.ndarray
    known: np.ndarray
    shooters: list
    elements: int


def same_shots(a: list[Shooter], b: list[Shooter]) -> bool:
    return len(a) == len(b) and all(
        np.array_equal(x.polygon, y.polygon) and np.array_equal(x.radiosity, y.radiosity) for x, y in zip(a, b))
