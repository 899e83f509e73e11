"""Shots in batches: the records the shooting passes read ("shot" include, a uniform block of
MAX_SHOTS), and the visibility each batch is looked up in.

With the "hemicube" visibility variant a batch holds up to `capacity` shooters (patches, pieces of
emitters and area lamps, point lamps): their hemi-cubes are drawn into one atlas by one instanced
call and one dispatch gathers all of them, so the per-draw and per-dispatch overhead is shared.
A sun (an orthographic map) and the sky (fractions) shoot alone, as does every shooter with the
hemispherical map variants (one map at a time).
"""

from __future__ import annotations

import hashlib

import numpy as np

from ..gpu import Resources, texture_unit, uniform_block
from ..timing import pulse
from ..scene import Patches, Scene, subdivide, surface_patches
from ..visibility import VARIANTS, HemicubeAtlas, VisibilityMap
from .shooters import DIRECTIONAL, SKY, Shooter

MAX_SHOTS = 64  # records per uniform block: 64 x (176 + 64) bytes, within GL's 16 KiB guarantee
SHOT_VEC4S = 11  # vec4s per record (struct Shot)
GROUP_VEC4S = 4  # vec4s per group of pieces (the whole polygon's corners), after the records
MAX_HEMICUBE_RESOLUTION = 1024  # a hemi-cube's top face, in pixels (its tile is 3 x taller)


def piece_groups(shooters: list[Shooter]) -> tuple[np.ndarray, list[np.ndarray]]:
    """(len(shooters),) group of each shooter, 1 + an index into the list of the groups' whole
    polygons (0: none): consecutive pieces of one polygon (`Shooter.whole`) that are all in
    `shooters`, so that a pass can take the polygon's exact factor once and the pieces only for
    visibility."""
    groups = np.zeros(len(shooters), dtype=np.int64)
    wholes = []
    k = 0
    while k < len(shooters):
        whole, count = shooters[k].whole, shooters[k].pieces
        if whole is not None and all(s.whole is whole for s in shooters[k:k + count]) and k + count <= len(shooters):
            wholes.append(whole)
            groups[k:k + count] = len(wholes)
            k += count
        else:
            k += 1
    return groups, wholes


def singles_then_groups(shooters: list[Shooter]) -> list[Shooter]:
    """`shooters` reordered: those in no group first, then the groups (`piece_groups`), as the
    texel pass reads them."""
    groups, _ = piece_groups(shooters)
    return [shooters[k] for k in np.argsort(groups > 0, kind="stable")]


def shot_records(shooters: list[Shooter], slots: list[int]) -> np.ndarray:
    """(MAX_SHOTS * 11 + MAX_SHOTS * 4, 4) float32: the records of `shooters` (hemi-cube `slots`,
    -1: the bound map), then the corners of their groups' whole polygons (`piece_groups`)."""
    records = np.zeros((MAX_SHOTS, SHOT_VEC4S, 4), dtype=np.float32)
    corners = np.zeros((MAX_SHOTS, GROUP_VEC4S, 4), dtype=np.float32)
    groups, wholes = piece_groups(shooters)
    for g, whole in enumerate(wholes):
        corners[g, :, :3] = whole
        members = np.flatnonzero(groups == g + 1)
        corners[g, :2, 3] = members[0], members[-1] + 1  # the group's shots: [first, end)
    for k, (shooter, slot) in enumerate(zip(shooters, slots)):
        x, y, pole = shooter.axes
        records[k, 0] = (*shooter.position, shooter.area)
        records[k, 1] = (*x, shooter.kind)
        records[k, 2] = (*y, shooter.patch)
        records[k, 3] = (*pole, groups[k])
        records[k, 4:8, :3] = shooter.polygon
        records[k, 8, :3] = shooter.radiosity
        records[k, 9] = (*shooter.light_direction, shooter.spot_cos_half)
        records[k, 10] = (shooter.spot_smooth, slot, shooter.ortho_extent, float(shooter.cluster))
    return np.concatenate([records.reshape(-1, 4), corners.reshape(-1, 4)])


def patch_planes(patches: Patches, cluster_of: np.ndarray | None = None, planes: np.ndarray | None = None) -> bytes:
    """shot.glsl's PatchPlane per patch: its plane's equation (n, n . x) as float32, its plane id
    (patches of one side of a surface are coplanar: a visibility lookup accepts any of them;
    `planes` (P,) instead of `patches.plane`) and its shooter clusters (`cluster_of` (P, levels ≤ 7),
    finest first, -1 without), its four corners (a triangle repeats its last)."""
    equation = np.concatenate([patches.normal, np.einsum("pd,pd->p", patches.normal, patches.center)[:, None]],
                              axis=1).astype(np.float32)
    ids = np.full((len(patches), 8), -1, dtype=np.int32)  # id, coarser_id
    ids[:, 0] = patches.plane if planes is None else planes
    if cluster_of is not None:
        cluster_of = np.asarray(cluster_of).reshape(len(patches), -1)
        if cluster_of.shape[1] > 7:
            raise ValueError(f"{cluster_of.shape[1]} levels of shooter clusters: PatchPlane holds 7")
        ids[:, 1:1 + cluster_of.shape[1]] = cluster_of
    corners = np.concatenate([patches.corners, np.zeros((len(patches), 4, 1))], axis=2).astype(np.float32)
    return np.concatenate([equation.view(np.int32), ids, corners.reshape(len(patches), 16).view(np.int32)],
                          axis=1).tobytes()


def shoot_in_batches(shoot, visibility: "ShotVisibility", shooters: list[Shooter]) -> int:
    """`shoot(batch)` for every batch `visibility` makes of `shooters`; returns the batches."""
    batches = visibility.batches(shooters)
    for batch in batches:
        shoot(batch)
        pulse()
    return len(batches)


def hemicube_resolution(visibility_res: int) -> int:
    """A hemi-cube's top face for a visibility resolution: its unfolded cross (2 R) spans as many
    pixels as a hemispherical map across."""
    return int(np.clip(visibility_res // 4 * 2, 8, MAX_HEMICUBE_RESOLUTION))


class ShotVisibility:
    """Visibility for batches of shots, and the uniform block that carries their records.
    `prepare(shooters)` renders what the batch needs and binds it; `batches(shooters)` splits a
    list into batches this can take."""

    def __init__(self, res: Resources, patches: Patches, resolution: int, variant: str, scene_diameter: float,
                 occlusion: bool = True, capacity: int = MAX_SHOTS, kept_as: tuple | None = None,
                 skip_of: np.ndarray | None = None, item_planes: np.ndarray | None = None):
        """The item buffers show `patches`; `kept_as` (a key naming them, e.g. `surface_visibility`'s):
        the atlas and the map are the GPU's kept ones for it (`GPU.kept`), not this scope's; `skip_of`:
        a shooter's patch -> the item a map leaves out for it (`patches.drawn`; -1: none);
        `item_planes`: the plane each item is a point of for a lookup (None: `patches.plane`)."""
        self.res, self.patches, self.resolution, self.occlusion = res, patches, resolution, occlusion
        self.variant, self.diameter = VARIANTS[variant], scene_diameter
        self.name = variant
        self.kept_as = kept_as
        self.skip_of = patches.drawn if skip_of is None else skip_of
        self.atlas = None
        self._map = None
        self.item_planes = item_planes
        if self.variant.hemicube:
            self.capacity = min(capacity, MAX_SHOTS)
            if occlusion:
                self.atlas = self._own_or_kept(
                    ("atlas", hemicube_resolution(resolution), self.capacity),
                    lambda scope: HemicubeAtlas(scope, patches, hemicube_resolution(resolution), scene_diameter,
                                                max_slots=self.capacity, backs_hide=True))
                self.capacity = min(self.capacity, self.atlas.slots)
        else:
            self.capacity = 1
        self.block = res.buffer(reserve=MAX_SHOTS * (SHOT_VEC4S + GROUP_VEC4S) * 16)
        self.maps_rendered = 0
        self.batch_kinds, self.batch_single_kinds, self.batch_lookup = 15, 15, 3  # set by prepare

    @property
    def map(self) -> VisibilityMap:
        """The hemispherical (or a sun's orthographic) map, made when first needed."""
        if self._map is None:
            variant = "plain" if self.variant.hemicube else self.name  # a sun's map needs no tessellation
            self._map = self._own_or_kept(
                ("map", variant, self.resolution),
                lambda scope: VisibilityMap(scope, self.patches, self.resolution, variant, self.diameter))
        return self._map

    def _own_or_kept(self, what: tuple, make):
        if self.kept_as is None:
            return make(self.res)
        return self.res.gpu.kept(("shot visibility", self.kept_as, self.diameter, *what), make)

    @staticmethod
    def alone(shooter: Shooter) -> bool:
        return shooter.kind in (DIRECTIONAL, SKY)

    def batches(self, shooters: list[Shooter]) -> list[list[Shooter]]:
        """Consecutive batches of at most `capacity`; a sun or the sky alone; the pieces of one
        polygon in one batch where they fit in one (`piece_groups`)."""
        batches, current = [], []
        for shooter in shooters:
            first_piece = shooter.whole is not None and not (current and current[-1].whole is shooter.whole)
            breaks_group = first_piece and len(current) + shooter.pieces > self.capacity >= shooter.pieces
            if self.alone(shooter) or len(current) == self.capacity or breaks_group:
                if current:
                    batches.append(current)
                current = []
            if self.alone(shooter):
                batches.append([shooter])
            else:
                current.append(shooter)
        return batches + ([current] if current else [])

    def prepare(self, shooters: list[Shooter]) -> dict:
        """Render the batch's visibility, write and bind its records; returns the passes' uniforms."""
        if len(shooters) > self.capacity and not (len(shooters) == 1):
            raise ValueError(f"a batch of {len(shooters)} shots exceeds {self.capacity}")
        slots = [-1] * len(shooters)
        groups, wholes = piece_groups(shooters)
        uniforms = {"shot_count": len(shooters), "item_resolution": self.resolution,
                    "hemicube_resolution": 1, "hemicube_tiles_per_row": 1,
                    "single_count": int(np.argmax(groups > 0)) if len(wholes) else len(shooters),
                    "group_count": len(wholes)}
        # what the batch holds, for the passes' variants ("shot": SHOT_KINDS, VISIBILITY_LOOKUP)
        self.batch_kinds = sum(1 << kind for kind in {shooter.kind for shooter in shooters})
        self.batch_single_kinds = sum(1 << kind for kind in {s.kind for s, group in zip(shooters, groups) if group == 0})
        self.batch_lookup = 2  # the map (also for the sky, which looks nothing up)
        if self.occlusion:
            if self.atlas is not None and not any(self.alone(s) for s in shooters):
                slots = list(range(len(shooters)))
                self.atlas.draw(tuple(np.array(v, dtype=np.float64) for v in zip(
                    *[(s.position, *s.axes) for s in shooters])))
                self.atlas.bind(texture_unit("HEMICUBES"))
                uniforms.update(hemicube_resolution=self.atlas.resolution,
                                hemicube_tiles_per_row=self.atlas.tiles_per_row)
                self.batch_lookup = 1
                self.maps_rendered += len(shooters)
            elif shooters[0].kind != SKY:
                (shooter,) = shooters
                skip = int(self.skip_of[shooter.patch]) if shooter.patch >= 0 else -1
                self.map.render(shooter.position, shooter.axes, skip, shooter.ortho_extent)
                self.map.bind()
                self.maps_rendered += 1
        self.block.write(shot_records(shooters, slots).tobytes())
        self.block.bind_to_uniform_block(uniform_block("SHOTS"))
        return uniforms

    @property
    def defines(self) -> dict:
        """The "shot" include's defines."""
        return {"MAX_SHOTS": MAX_SHOTS, "SEARCH_RADIUS": self.variant.search_radius,
                "OCCLUDER_MARGIN": float(self.variant.occluder_margin), "OCCLUSION": int(self.occlusion)}


def surface_visibility(res: Resources, scene: Scene, patches: Patches, resolution: int, variant: str,
                       occlusion: bool = True, capacity: int = MAX_SHOTS, clusters=None) -> ShotVisibility:
    """The texel pass's visibility for receivers on `patches`: item buffers of the surfaces
    (`surface_patches`: one item per surface side), not of the patches. A texel pass looks up
    only the receiver's plane and, for what shows in front of it, that item's plane and outline,
    which a surface gives as its patches together would; so its maps cost the surfaces' triangles
    however finely refinement split them, and they are the same for every split: kept on the GPU
    for the job (`GPU.kept`), and not drawn again for the same shots (the emitters' pieces of every
    refinement round, the direct light and the lightmaps at one resolution). With `clusters`
    (`scene.face_clusters`, whose proxies `scene` holds) the items are the faces themselves, each a
    point of its cluster's plane: what the lightmaps' texels see has the faces' own shape and
    outlines, and any face of a texel's cluster is seen as its plane."""
    planes = skip_of = None
    if clusters is not None and not clusters.is_identity:
        surfaces = subdivide(clusters.faces, subdiv=1)
        pulse()  # a dense scene's faces take seconds to lay out and draw
        planes = clusters.proxy_of_face
        skip_of = clusters.face_of_proxy[np.asarray(patches.surface)]  # a cluster's piece leaves nothing out
    else:
        surfaces = surface_patches(scene, patches)
        skip_of = np.asarray(patches.surface)  # item k is surface k's front
    digest = hashlib.sha1(np.ascontiguousarray(surfaces.corners).tobytes())
    digest.update(np.ascontiguousarray(surfaces.twin).tobytes())
    if planes is not None:
        digest.update(np.ascontiguousarray(planes).tobytes())
    if surfaces.opacity is not None:
        digest.update(surfaces.opacity.digest())
    return ShotVisibility(res, surfaces, resolution, variant, scene.diameter, occlusion, capacity,
                          kept_as=("surfaces", digest.hexdigest()), skip_of=skip_of, item_planes=planes)
