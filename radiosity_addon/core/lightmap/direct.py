"""Direct light texel by texel: every texel of every lightmap gathers the lamps', the sun's, the
emitters' and the sky's light with its own visibility (`shooting.TexelReceivers`), so shadows and
penumbrae are as sharp as the lightmap can show; the smooth rest of the light (what the surfaces
reflect) comes from the solve's elements.

A texel's point is the world point its centre shows on the patch whose UV footprint holds it (a
texel a footprint only grazes: the footprint's nearest point), so every sample lies on a
surface and takes that surface's plane for the visibility lookup.

A texel is the mean over its square, not its centre: Cycles bakes a texel by jittering each
sample across it (a one-texel box), kept inside the face the centre lies on. Where the direct
light bends sharply across a texel (a shadow's or a light's edge: `sharp_texels`), the texel's
light is the mean of N x N points spread over its square inside its face (`footprint_points`;
N is `LightmapSettings.direct_subsamples`); elsewhere the light is smooth enough that the centre
is that mean to within SHARP_CONTRAST / 24 (half a per cent). Centres alone go wrong where the
light bends within a texel: on the Cornell box, the ceiling around the lamp whose back lights it
from 5 mm (a third of a texel) held nearly all of the bake's error.
"""

from __future__ import annotations

import math

import numpy as np

from ..gpu import GPU, open_gpu
from ..scene import Patches, Scene
from ..scene.geometry import bilinear
from ..settings import VISIBILITY_VARIANTS, LightmapSettings
from ..solution import Solution
from ..shooting import direct_shooters, emitter_shooters, light_at_receivers
from ..shooting.shooters import DIRECTIONAL
from ..shooting.sky import SKY_MAP_RESOLUTION, element_frames, sky_shooters
from ..uvspace import rasterize

REFLECTION_FLOOR = 1e-4  # emitters reflecting less than this share of the brightest emission are not shot again
MIN_MAP_RESOLUTION = 64  # the coarsest visibility map `matched_map_resolution` gives
MAP_RESOLUTION_STEP = 16  # ... and its multiple (a hemi-cube's top face is a quarter of it, times 2)
SUN_MAP_RESOLUTION = 2048  # the finest sun's map `sun_map_resolution` gives (16 MiB of depth and items)
SUN_DISC_DIRECTIONS = 16  # directions a sun's disc is shot from at most (its penumbra in 16 steps)


def matched_map_resolution(diameter: float, finest_texel: float, cap: int) -> int:
    """Pixels across the direct light's visibility maps, no finer than the lightmaps can show: a map
    R pixels across (a hemi-cube's unfolded cross, its top face R / 2 pixels over 90 degrees) has
    pixels 4 d / R wide at distance d along its axis, so at the scene's `diameter` D (the farthest a
    texel can be from a shooter) a pixel is one of the finest texels t when R = 4 D / t. `cap`
    (`LightmapSettings.direct_map_resolution`) bounds it: a 55 cm box at 64 texels/m needs ~340
    pixels, not `final`'s 1024, which a 7 m room at that density does need (its 4 D / t is ~3 000)."""
    needed = 4.0 * diameter / max(finest_texel, 1e-30)
    stepped = MAP_RESOLUTION_STEP * int(np.ceil(min(needed, 1e9) / MAP_RESOLUTION_STEP))
    return int(min(cap, max(MIN_MAP_RESOLUTION, stepped)))


def sun_map_resolution(diameter: float, finest_texel: float, matched: int) -> int:
    """Pixels across a sun's map for lightmaps whose finest texel is `finest_texel`: its one
    orthographic map spans the scene's `diameter`, so 4 diameter / texel pixels give every texel
    four across (a chair's 3.5 cm leg casts its shadow, a leaf's cut-out its edge); one map per
    sun, so SUN_MAP_RESOLUTION bounds it rather than the preset's cap, and it is never coarser
    than the other shots' `matched` (`matched_map_resolution`)."""
    needed = 4.0 * diameter / max(finest_texel, 1e-30)
    stepped = MAP_RESOLUTION_STEP * int(np.ceil(min(needed, 1e9) / MAP_RESOLUTION_STEP))
    return int(max(matched, min(SUN_MAP_RESOLUTION, stepped)))


def sun_disc_directions(scene: Scene, finest_texel: float) -> int:
    """Directions over a sun's disc for texels `finest_texel` wide: enough that its penumbra at
    the scene's diameter (the farthest an occluder can be) is about a direction per texel
    across, SUN_DISC_DIRECTIONS at most; 1 where the penumbra is under a texel."""
    angle = max((lamp.angle for lamp in scene.lamps if lamp.type == "sun"), default=0.0)
    across = scene.diameter * math.tan(angle) / max(finest_texel, 1e-30)
    return int(np.clip(math.ceil(min(across, 1e3) ** 2), 1, SUN_DISC_DIRECTIONS)) if across >= 1 else 1


def map_resolutions(scene: Scene, finest_texel: float, cap: int) -> tuple[int, tuple[int, int]]:
    """(pixels across the direct light's maps, (pixels across a sun's map, directions over a sun's
    disc)) for lightmaps whose finest texel is `finest_texel`, the maps' pixels at most `cap`."""
    matched = matched_map_resolution(scene.diameter, finest_texel, cap)
    sun = (sun_map_resolution(scene.diameter, finest_texel, matched), sun_disc_directions(scene, finest_texel))
    return matched, sun


def texel_points(gpu: GPU, corners: np.ndarray, corners_texels: np.ndarray, size) -> tuple:
    """(positions (H, W, 3), owner (H, W): the index into `corners` of the quad (n, 4, 3) holding
    the texel, -1 for none, covered (H, W)) of one lightmap whose quads have UV corners in texels
    `corners_texels` (n, 4, 2)."""
    params = np.array([0.0, 0.5, 1.0])
    s, t = np.meshgrid(params, params)
    lattice = bilinear(corners, s, t)  # (n, 3, 3, 3): the bilinear map is exact on it
    positions, signed_ids = rasterize(gpu, corners_texels, lattice, size)
    covered = signed_ids != 0
    owner = np.where(covered, np.abs(signed_ids) - 1, -1)
    return positions.astype(np.float64), owner, covered


SHARP_CONTRAST = 0.12  # second difference over the brightest of three texels above which the middle one is sharp


def texel_axes(corners: np.ndarray, corners_texels: np.ndarray) -> np.ndarray:
    """(n, 3, 2): the world step of one texel along x and along y on each quad (n, 4, 3), from its
    first three corners (its UV map is affine on them); zeros where the UVs are degenerate."""
    world = corners
    uv = np.asarray(corners_texels, dtype=np.float64)
    edges_uv = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)  # (n, 2, 2): columns
    edges_world = np.stack([world[:, 1] - world[:, 0], world[:, 2] - world[:, 0]], axis=2)  # (n, 3, 2)
    det = edges_uv[:, 0, 0] * edges_uv[:, 1, 1] - edges_uv[:, 0, 1] * edges_uv[:, 1, 0]
    usable = np.abs(det) > 1e-12
    inverse = np.zeros_like(edges_uv)
    safe = np.where(usable, det, 1.0)
    inverse[:, 0, 0], inverse[:, 1, 1] = edges_uv[:, 1, 1] / safe, edges_uv[:, 0, 0] / safe
    inverse[:, 0, 1], inverse[:, 1, 0] = -edges_uv[:, 0, 1] / safe, -edges_uv[:, 1, 0] / safe
    return np.where(usable[:, None, None], edges_world @ inverse, 0.0)


def sharp_texels(images: list[np.ndarray], faces: list[np.ndarray]) -> list[np.ndarray]:
    """Per lightmap, the texels (H, W) whose centre's value (H, W) may stray from their square's
    mean: the second difference across a texel is 24 times that stray (a linear change averages
    out), so a texel is sharp where, along x or y between two neighbours on its own face (`faces`
    (H, W): the surface each texel shows, -1 none; another face's texel is another chart's or
    across an edge), it exceeds SHARP_CONTRAST of the largest of the three."""
    result = []
    for image, face in zip(images, faces):
        sharp = np.zeros(face.shape, dtype=bool)
        for axis in (0, 1):
            a, f = np.moveaxis(image, axis, 0), np.moveaxis(face, axis, 0)
            same = (f[1:-1] >= 0) & (f[2:] == f[1:-1]) & (f[:-2] == f[1:-1])
            bend = np.abs(a[2:] - 2 * a[1:-1] + a[:-2])
            flags = np.moveaxis(sharp, axis, 0)
            flags[1:-1] |= same & (bend > SHARP_CONTRAST * np.maximum(np.maximum(a[2:], a[1:-1]), a[:-2]))
        result.append(sharp)
    return result


def footprint_points(corners: np.ndarray, normals: np.ndarray, centres: np.ndarray, axes: np.ndarray,
                     count: int, clip: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(points (M, 3), index of their texel (M,)): `count` x `count` points spread evenly over each
    texel's square (its centre `centres` (N, 3), its texel `axes` (N, 3, 2)) and inside the face
    `corners` (N, 4, 3; triangles repeat their last corner) with `normals` (N, 3) it lies on, where
    `clip` (N,; None: everywhere) says so (a face smaller than a texel, among the faces of a
    cluster, leaves its square to its neighbours); a texel none of whose points is inside keeps
    its centre."""
    offsets = (np.arange(count) + 0.5) / count - 0.5
    dx, dy = (grid.ravel() for grid in np.meshgrid(offsets, offsets))
    # the face's edges as inward half-planes, tested in texel steps: side(centre + a x + b y) =
    # side(centre) + a side(x) + b side(y), per texel (N, 4) instead of per point
    inward = np.cross(normals[:, None, :], np.roll(corners, -1, axis=1) - corners)  # (N, 4, 3)
    reach = np.linalg.norm(inward, axis=2)
    at_centre = np.einsum("nkj,nkj->nk", inward, centres[:, None, :] - corners) + 1e-9 * reach * (reach + 1.0)
    along = np.einsum("nkj,njc->nkc", inward, axes)  # (N, 4, 2)
    side = at_centre[:, None, :] + along[:, None, :, 0] * dx[None, :, None] + along[:, None, :, 1] * dy[None, :, None]
    inside = np.all(side >= 0.0, axis=2)  # (N, count²)
    if clip is not None:
        inside |= ~clip[:, None]
    texel, sample = np.nonzero(inside)
    points = centres[texel] + axes[texel, :, 0] * dx[sample, None] + axes[texel, :, 1] * dy[sample, None]
    lone = np.flatnonzero(~inside.any(axis=1))  # slivers thinner than the points' spacing
    return np.concatenate([points, centres[lone]]), np.concatenate([texel, lone])


def emitters_reflection(patches: Patches, radiosity: np.ndarray) -> np.ndarray | None:
    """(P, 3) what each emitting patch reflects, B - E (0 elsewhere), or None where emitters
    reflect nothing worth a pass (under REFLECTION_FLOOR of their emission)."""
    emits = np.any(patches.emission > 0, axis=1)
    if not emits.any():
        return None
    radiosity = np.broadcast_to(np.asarray(radiosity, dtype=np.float64), patches.emission.shape)
    reflected = np.where(emits[:, None], np.maximum(radiosity - patches.emission, 0.0), 0.0)
    return reflected if reflected.max() > REFLECTION_FLOOR * patches.emission.max() else None


def reflected_light_at_elements(gpu: GPU | None, solution: Solution, settings: LightmapSettings,
                                reflected: np.ndarray, elements: int) -> np.ndarray:
    """(P, S, S, 3) the light the elements' centres get from what the emitters reflect
    (`emitters_reflected_light`): the part of the solve's light the texels recompute."""
    patches, report = solution.patches, solution.report
    points = element_frames(patches, elements)[0]
    owners = np.repeat(np.arange(len(patches)), elements * elements)
    with open_gpu(gpu) as own_gpu:
        light = emitters_reflected_light(own_gpu, solution.scene, patches, points, patches.normal[owners],
                                         patches.plane[owners], reflected, report.settings.visibility,
                                         settings.direct_map_resolution, report.effects.occlusion,
                                         settings.direct_pieces)
    return light.reshape(len(patches), elements, elements, 3)


def emitters_reflected_light(gpu: GPU, scene: Scene, patches: Patches, points: np.ndarray, normals: np.ndarray,
                             planes: np.ndarray, reflected: np.ndarray, visibility: str, resolution: int,
                             occlusion: bool, pieces: int) -> np.ndarray:
    """(N, 3) the light at `points` (with `normals`, on the `planes` of the solved surfaces' sides)
    from what the emitters reflect, `reflected` (P, 3), shot from their pieces as `direct_light`
    shoots it: the part of the solve's element light that the texels take from
    `direct_light(..., reflected)` instead."""
    shooters = emitter_shooters(scene, patches, pieces, reflected, emission=False)
    return shot_light(gpu, scene, patches, points, normals, planes, shooters, visibility, resolution, occlusion)


def shot_light(gpu: GPU, scene: Scene, patches: Patches, points: np.ndarray, normals: np.ndarray, planes: np.ndarray,
               shooters: list, visibility: str, resolution: int, occlusion: bool, clusters=None) -> np.ndarray:
    """(N, 3) the light `shooters` send to `points` (the texel pass, `light_at_receivers`; with
    `clusters` the clusters' own faces occlude), in the solve's visibility variant where the texel
    pass has it."""
    variant = visibility if visibility in VISIBILITY_VARIANTS else "hemicube"
    with gpu.resources() as res:
        return light_at_receivers(res, scene, patches, points, normals, planes, shooters, variant, resolution,
                                  occlusion, clusters=clusters)


def sky_light(gpu: GPU, scene: Scene, patches: Patches, points: np.ndarray, normals: np.ndarray, planes: np.ndarray,
              directions: int, occlusion: bool, clusters=None) -> np.ndarray:
    """(N, 3) the light the world colour sends to `points` (as `direct_light` takes them), from
    `directions` of the sky (`shooting.sky`) each with its own map: what a texel's own view of the
    sky lets through (beside a sofa's foot, on a part sunk into another), where the elements' sky
    is a patch's mean."""
    if not np.any(scene.world_color > 0):
        return np.zeros((len(points), 3))
    low, high = scene.bounds
    shooters = sky_shooters(scene.world_color, (low + high) / 2, scene.diameter, directions)
    return shot_light(gpu, scene, patches, points, normals, planes, shooters, "hemicube", SKY_MAP_RESOLUTION,
                      occlusion, clusters)


def direct_light(gpu: GPU, scene: Scene, patches: Patches, points: np.ndarray, normals: np.ndarray,
                 planes: np.ndarray, visibility: str, resolution: int, occlusion: bool, pieces: int,
                 reflected: np.ndarray | None = None, clusters=None,
                 sun_resolution: int | None = None, sun_directions: int = 1) -> tuple[np.ndarray, int]:
    """(N, 3) direct light H at `points` (N, 3) with `normals` (N, 3), looked up as points of the
    solved surfaces' sides `planes` (N,) (`Patches.plane`), and the number of shots (emitters and
    area lamps in up to `pieces` x `pieces` each; the emitters send what they reflect of
    `reflected` (P, 3) too, when given). With `clusters` the clusters' faces occlude in place of
    their rectangles (`shooting.surface_visibility`); suns' maps are `sun_resolution` pixels
    across (None: `resolution`), and a sun with an angle shoots from `sun_directions` over its disc."""
    shooters = direct_shooters(scene, patches, pieces, reflected, sun_directions)
    suns = [shooter for shooter in shooters if shooter.kind == DIRECTIONAL] if sun_resolution else []
    others = [shooter for shooter in shooters if not (suns and shooter.kind == DIRECTIONAL)]
    light = shot_light(gpu, scene, patches, points, normals, planes, others, visibility, resolution, occlusion,
                       clusters)
    if suns:
        light += shot_light(gpu, scene, patches, points, normals, planes, suns, visibility, sun_resolution,
                            occlusion, clusters)
    return light, len(shooters)
