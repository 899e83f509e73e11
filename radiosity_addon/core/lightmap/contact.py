"""Texels in contact: a texel whose point lies on a face of other geometry that touches its own
face to face — the underside of a ceiling slab over the walls' tops, a wall's foot on the floor, a
book's bottom on its shelf — sees nothing but the back of what touches it. Cycles bakes it black;
without this test it would take its patch's interpolated light (a leak through the contact).

Touching faces are found among nearby faces (`scene.neighbours.near_pairs`, linear in the scene):
fronts facing each other (normals opposite within PARALLEL) closer than the contact distance:
CONTACT_DISTANCE of the scene's diameter, and where the lightmaps are coarser, half a texel (a
sofa set 2 mm over the floor lets no light under it that a texel could show, and Cycles bakes it
black; an emitter hung 2 cm under a ceiling of 16 mm texels does not touch it).
A texel is in contact when its point lies inside such a partner's polygon. Faces the solve took in
clusters are searched only where their clusters' rectangles touch (`touching_clusters`): a dense
mesh's faces are many, and few of them rest on anything."""

from __future__ import annotations

import numpy as np

from ..scene import Scene
from ..timing import pulse
from ..scene.neighbours import near_pairs, range_chunks

CONTACT_DISTANCE = 1e-4  # planes closer than this (times the scene's diameter) touch
CONTACT_TEXELS = 0.5  # ... or closer than this share of a lightmap texel
PARALLEL = 0.999  # -cos between the normals of two faces that touch face to face
POINT_CHUNK = 1 << 20  # (texel, partner) tests at once


NORMAL_CELLS = 20  # normals are binned on a grid this fine: a face can touch only faces in the cells around its opposite


def _facing_somewhere(normals: np.ndarray) -> np.ndarray:
    """(n,) bool: some face's normal lies in the bins around each face's opposite normal (a dense
    mesh's faces mostly have none: only they are searched for partners)."""
    cells = np.rint(normals * NORMAL_CELLS).astype(np.int64)
    code = lambda c: ((c[:, 0] + 64) * 256 + (c[:, 1] + 64)) * 256 + (c[:, 2] + 64)  # noqa: E731
    present = np.unique(code(cells))
    found = np.zeros(len(normals), dtype=bool)
    for offset in np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), -1).reshape(-1, 3):
        found |= np.isin(code(-cells + offset), present)
    return found


def contact_distance(scene: Scene, texel: float = 0.0) -> float:
    """How far apart facing faces touch (module doc), for lightmap texels `texel` wide."""
    return max(CONTACT_DISTANCE * scene.diameter, CONTACT_TEXELS * texel)


def touching_faces(scene: Scene, surfaces: np.ndarray, candidates: np.ndarray | None = None,
                   distance: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(surface, partner) pairs: `surfaces` (some of the scene's) and the faces touching their
    fronts face to face within `distance` (None: `contact_distance` of no texel), among
    `candidates` (a mask of faces; None: all)."""
    corners = scene.corners
    centre = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centre[:, None], axis=2).max(axis=1)
    tolerance = contact_distance(scene) if distance is None else distance
    normal = scene.normal
    facing = _facing_somewhere(normal)
    if candidates is not None:
        facing &= candidates
    surfaces = surfaces[facing[surfaces]]
    found_surface, found_partner = [], []
    for query, other in near_pairs(centre, radius + tolerance, surfaces, radius[surfaces] + tolerance,
                                   others=np.flatnonzero(facing)):
        surface = surfaces[query]
        facing = np.einsum("ij,ij->i", normal[surface], normal[other]) < -PARALLEL
        apart = np.abs(np.einsum("ij,ij->i", corners[other, 0] - corners[surface, 0], normal[surface]))
        keep = facing & (apart < tolerance) & (other != surface)
        found_surface.append(surface[keep])
        found_partner.append(other[keep])
    if not found_surface:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(found_surface), np.concatenate(found_partner)


def inside_polygons(points: np.ndarray, corners: np.ndarray, normals: np.ndarray, tolerance: float) -> np.ndarray:
    """(N,) whether each point (N, 3) projects inside its convex polygon (N, 4, 3) (a triangle
    repeats its last corner) along its normal (N, 3), `tolerance` past the edges counting inside."""
    inside = np.ones(len(points), dtype=bool)
    for k in range(4):  # edge k: n . (edge x (p - corner)) >= -tolerance |edge|
        edge = corners[:, (k + 1) % 4] - corners[:, k]
        to_point = points - corners[:, k]
        side = (normals[:, 0] * (edge[:, 1] * to_point[:, 2] - edge[:, 2] * to_point[:, 1])
                + normals[:, 1] * (edge[:, 2] * to_point[:, 0] - edge[:, 0] * to_point[:, 2])
                + normals[:, 2] * (edge[:, 0] * to_point[:, 1] - edge[:, 1] * to_point[:, 0]))
        inside &= side >= -tolerance * np.sqrt((edge * edge).sum(axis=1))
    return inside


def in_contact(scene: Scene, points: np.ndarray, surfaces: np.ndarray, candidates: np.ndarray | None = None,
               distance: float | None = None) -> np.ndarray:
    """(N,) whether each point (N, 3), lying on the front of its surface `surfaces` (N,), is
    covered by a face touching that front within `distance` (`touching_faces`; faces among
    `candidates`, a mask; None: all)."""
    covered = np.zeros(len(points), dtype=bool)
    if len(points) == 0:
        return covered
    tolerance = contact_distance(scene) if distance is None else distance
    edge = CONTACT_DISTANCE * scene.diameter  # a texel just past the partner's edge is not under it
    touched, partner = touching_faces(scene, np.unique(surfaces), candidates, tolerance)
    if len(touched) == 0:
        return covered
    # each surface's points sorted along one axis in its plane (its longest), so that a partner
    # meets only the points across its own extent on that axis: a foot tests the floor's texels
    # in a strip, not all of them
    low, high = scene.corners.min(axis=1), scene.corners.max(axis=1)
    extent = np.where(np.abs(scene.normal) > 0.5, -1.0, high - low)
    axis = np.argmax(extent, axis=1)
    scale = np.maximum(np.take_along_axis(high - low, axis[:, None], 1)[:, 0], 1e-30) * (1 + 1e-9)
    origin = np.take_along_axis(low, axis[:, None], 1)[:, 0]

    def keys(owner, coordinate):
        return owner + np.clip((coordinate - origin[owner]) / scale[owner], 0.0, 1.0 - 1e-9)

    point_keys = keys(surfaces, np.take_along_axis(points, axis[surfaces][:, None], 1)[:, 0])
    pulse()
    order = np.argsort(point_keys, kind="stable")
    sorted_keys = point_keys[order]
    along = axis[touched]
    partner_low = np.take_along_axis(low[partner], along[:, None], 1)[:, 0] - tolerance
    partner_high = np.take_along_axis(high[partner], along[:, None], 1)[:, 0] + tolerance
    start = np.searchsorted(sorted_keys, keys(touched, partner_low), side="left")
    count = np.searchsorted(sorted_keys, keys(touched, partner_high), side="right") - start
    for pair, at in range_chunks(start, count, POINT_CHUNK):
        pulse()
        point = order[at]
        hit = inside_polygons(points[point], scene.corners[partner[pair]], scene.normal[partner[pair]], edge)
        covered[point[hit]] = True
    return covered


def touching_clusters(clusters, distance: float | None = None) -> np.ndarray | None:
    """(F,) the faces whose cluster touches another's within `distance` (scene.face_clusters; a
    face the solve took as it is, its own), the only ones that may touch; None where nothing was
    clustered. A cluster is taken as wide as its faces reach from its rectangle's centre, as
    thick as they stray from its plane and as bent as their normals turn from its (a sofa's
    bottom with a bevel's start in it still meets the floor under it)."""
    if clusters.is_identity:
        return None
    faces, proxies, of = clusters.faces, clusters.proxies, clusters.proxy_of_face
    distance = contact_distance(faces) if distance is None else distance
    centre, normal = proxies.corners.mean(axis=1), proxies.normal
    offsets = faces.corners - centre[of][:, None, :]
    radius, slack, turn = (np.zeros(len(proxies)) for _ in range(3))
    np.maximum.at(radius, of, np.linalg.norm(offsets, axis=2).max(axis=1))
    np.maximum.at(slack, of, np.abs(np.einsum("fkj,fj->fk", offsets, normal[of])).max(axis=1))
    np.maximum.at(turn, of, np.arccos(np.clip(np.einsum("fj,fj->f", faces.normal, normal[of]), -1.0, 1.0)))
    touching = np.zeros(len(proxies), dtype=bool)
    everything = np.arange(len(proxies))
    for query, other in near_pairs(centre, radius + distance, everything, radius + distance):
        surface = everything[query]
        between = np.arccos(np.clip(-np.einsum("ij,ij->i", normal[surface], normal[other]), -1.0, 1.0))
        bend = turn[surface] + turn[other]
        facing = between < np.arccos(PARALLEL) + bend
        apart = np.abs(np.einsum("ij,ij->i", centre[other] - centre[surface], normal[surface]))
        near = apart < distance + slack[surface] + slack[other] + radius[other] * np.sin(np.minimum(between, np.pi / 2))
        keep = facing & near & (other != surface)
        touching[surface[keep]] = touching[other[keep]] = True
    return touching[of]
