"""Faces grouped into the surfaces the solve works on: a production mesh's small faces become
clusters about the patch size, each solved as one planar rectangle (its proxy); large faces stay
as they are.

Radiosity needs unknowns about the patch size, not one per polygon: a sculpted or subdivided
object of 100k triangles holds a few hundred patches' worth of light. The faces remain what the
lightmaps are made of (their texels are the receivers of the direct light, and their triangles
what that light's visibility rasterizes); only the solve sees proxies.

How faces are grouped (all vectorized, O(F log F)):
1. Candidates: faces whose longest edge is under the patch size (a larger face is split into patches
   of its own).
2. Regions: candidates of one object and one kind (two-sidedness, emission, opacity texture)
   joined across shared edges (corners welded like `topology`) where they bend less than
   CREASE_DEGREES: a subdivided box gives six regions, a smooth or noisy sculpt one.
3. Splits, round by round, until none applies: a cluster longer than the patch size is cut into
   ceil(length / size) slices across its longer axis; a cluster whose normals turn (area-weighted
   normal coherence under COHERENCE, and farther from its plane than FLATNESS of its width: a bend,
   not noise) is halved across the direction its normals turn in, down to MIN_BENT_SIZE.
4. Each cluster's connected pieces are clusters of their own.

A cluster of several faces is solved as a rectangle in its mean plane through its area centroid,
along its faces' dominant edge direction or its principal axes (whichever bounds it tighter),
scaled to the faces' projected area |sum of a n| (their total area where they are flat), so it
emits and receives the power they do; it takes their area-weighted reflectance and emission. A subdivided rectangle therefore comes back as the
rectangle it was made from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..timing import pulse
from .geometry import tangent_axes
from .model import Scene
from .rows import row_labels
from .topology import QUANTUM, connected_labels

MERGE_SIZE = 1.0  # faces whose longest edge is under this fraction of the patch size may be merged
CREASE_DEGREES = 60.0  # adjacent faces bent further apart than this belong to different regions
COHERENCE = 0.95  # |sum a n| / sum a under this (a spherical cap wider than ~50 degrees): a cluster is bent
FLATNESS = 0.05  # ... when its corners also stray from its plane by more than this fraction of its width
MIN_BENT_SIZE = 0.125  # of the patch size: a bent cluster narrower than this stays whole
UV_QUANTUM = 1e-6  # texture UVs closer than this are the same
SIZE_SLACK = 1.0 + 1e-6  # a cluster this close to the patch size is not cut
MAX_ROUNDS = 64
ABSORB_DEGREES = 60.0  # a speck joins a neighbouring cluster whose normal is within this of its own
ABSORB_ROUNDS = 32


@dataclass(eq=False)
class FaceClusters:
    """A scene's faces and the surfaces the solve works on (`proxies`): every face belongs to one
    proxy; a proxy is either a face as it is or a rectangle standing for several."""
    faces: Scene
    proxies: Scene
    proxy_of_face: np.ndarray  # (F,) the proxy each face belongs to
    face_of_proxy: np.ndarray  # (Q,) the face a proxy is, -1 for a merged cluster

    @property
    def merged(self) -> np.ndarray:
        """(Q,) bool: the proxies standing for several faces."""
        return self.face_of_proxy < 0

    @property
    def is_identity(self) -> bool:
        return self.proxies is self.faces

    def proxy_backs(self, face_backs: np.ndarray) -> np.ndarray:
        """(Q,) a proxy's back is simulated when any of its faces' is."""
        if self.is_identity:
            return face_backs
        counts = np.bincount(self.proxy_of_face, weights=face_backs.astype(np.float64),
                             minlength=len(self.proxies))
        return counts > 0


def identity_clusters(scene: Scene) -> FaceClusters:
    """Every face its own surface (nothing merged): the solve sees the scene as it is."""
    index = np.arange(len(scene))
    return FaceClusters(faces=scene, proxies=scene, proxy_of_face=index, face_of_proxy=index)


def cluster_faces(scene: Scene, patch_size: float, subdiv: int | None = None) -> FaceClusters:
    """The proxies of `scene` for patches about `patch_size` across (module doc). With `subdiv`
    (every surface N x N) the surfaces are taken as they are."""
    if subdiv is not None or len(scene) < 2:
        return identity_clusters(scene)
    corners = scene.corners
    edges = np.linalg.norm(np.roll(corners, -1, axis=1) - corners, axis=2)
    candidate = edges.max(axis=1) < MERGE_SIZE * patch_size
    if candidate.sum() < 2:
        return identity_clusters(scene)
    faces = np.flatnonzero(candidate)
    kind = _kinds(scene, faces)
    pairs, smooth = _adjacent_pairs(scene, faces, kind)
    pulse()
    regions = connected_labels(len(faces), pairs[smooth]) if smooth.any() else np.arange(len(faces))
    label = _split(scene, faces, _compact(regions), patch_size)
    # each cluster's connected pieces apart (a slice through a U gives two)
    same = smooth & (label[pairs[:, 0]] == label[pairs[:, 1]])
    pieces = connected_labels(len(faces), pairs[same]) if same.any() else np.arange(len(faces))
    label = _compact(label.astype(np.int64) * len(faces) + pieces)
    label = _absorb_small(scene, faces, label, pairs, patch_size)
    sizes = np.bincount(label)
    several = sizes[label] >= 2
    if not several.any():
        return identity_clusters(scene)
    return _proxies(scene, faces[several], _compact(label[several]))


def _compact(label: np.ndarray) -> np.ndarray:
    return np.unique(label, return_inverse=True)[1].ravel()


def _kinds(scene: Scene, faces: np.ndarray) -> np.ndarray:
    """(n,) an integer per candidate: faces of different kinds never share a cluster (another
    object, two-sidedness, emission or opacity texture)."""
    emission = scene.emission[faces]
    scale = max(float(np.abs(scene.emission).max()), 1e-30)
    quantized = np.rint(emission / scale * 1e9).astype(np.int64)
    opacity = scene.opacity_index[faces] if scene.opacity_index is not None else np.full(len(faces), -1)
    return row_labels(np.column_stack([scene.object_index[faces], scene.two_sided[faces].astype(np.int64),
                                       quantized, opacity]))


def _adjacent_pairs(scene: Scene, faces: np.ndarray, kind: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(M, 2) positions in `faces` of candidates of one kind sharing an edge (corners welded at
    QUANTUM of the scene's size: a triangle soup's faces meet as a mesh's do), and (M,) bool
    whether they bend less than CREASE_DEGREES there."""
    size = max(scene.diameter, 1e-30)
    corners = scene.corners[faces]
    points = np.round(corners.reshape(-1, 3) / (QUANTUM * size)).astype(np.int64)
    if scene.opacity is not None:  # textured faces meet only where their texture's UVs do too (no seam inside)
        uv = np.where((scene.opacity.index[faces] >= 0)[:, None, None], scene.opacity.uv[faces], 0.0)
        points = np.concatenate([points, np.round(uv.reshape(-1, 2) / UV_QUANTUM).astype(np.int64)], axis=1)
    ids = row_labels(points).reshape(-1, 4)
    start, end = ids, np.roll(ids, -1, axis=1)
    keep = start != end
    owner = np.repeat(np.arange(len(faces)), 4).reshape(-1, 4)[keep]
    low, high = np.minimum(start, end)[keep], np.maximum(start, end)[keep]
    # uses of one edge (of one kind) are the faces meeting there
    order = np.lexsort((high, low, kind[owner]))
    key = np.stack([kind[owner][order], low[order], high[order]], axis=1)
    same_as_next = np.all(key[1:] == key[:-1], axis=1)
    a, b = owner[order[:-1][same_as_next]], owner[order[1:][same_as_next]]
    normals = scene.normal[faces]
    smooth = np.einsum("nd,nd->n", normals[a], normals[b]) > math.cos(math.radians(CREASE_DEGREES))
    return np.stack([a, b], axis=1), smooth


class _ClusterStats:
    """Per cluster of the candidates: area, mean normal, coherence, an in-plane frame."""

    def __init__(self, area: np.ndarray, normal: np.ndarray, label: np.ndarray):
        self.count = int(label.max()) + 1
        self.area = np.bincount(label, weights=area, minlength=self.count)
        summed = np.stack([np.bincount(label, weights=area * normal[:, d], minlength=self.count) for d in range(3)], 1)
        length = np.linalg.norm(summed, axis=1)
        self.coherence = length / np.maximum(self.area, 1e-300)
        first = np.zeros(self.count, dtype=np.int64)
        first[label[::-1]] = np.arange(len(label))[::-1]
        self.normal = np.where(length[:, None] > 1e-12 * self.area[:, None], summed / np.maximum(length, 1e-300)[:, None],
                               normal[first])
        self.u, self.v = tangent_axes(self.normal, np.zeros_like(self.normal))


def _segment_extremes(label: np.ndarray, values: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Per label in [0, count) the min and max of `values` (every label present)."""
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(count))
    sorted_values = values[order]
    return np.minimum.reduceat(sorted_values, starts), np.maximum.reduceat(sorted_values, starts)


def _principal_angle(label: np.ndarray, weight: np.ndarray, x: np.ndarray, y: np.ndarray, count: int) -> np.ndarray:
    """Per cluster the angle of the major axis of the weighted (x, y) scatter."""
    total = np.maximum(np.bincount(label, weights=weight, minlength=count), 1e-300)
    mean_x = np.bincount(label, weights=weight * x, minlength=count) / total
    mean_y = np.bincount(label, weights=weight * y, minlength=count) / total
    dx, dy = x - mean_x[label], y - mean_y[label]
    sxx = np.bincount(label, weights=weight * dx * dx, minlength=count)
    syy = np.bincount(label, weights=weight * dy * dy, minlength=count)
    sxy = np.bincount(label, weights=weight * dx * dy, minlength=count)
    return 0.5 * np.arctan2(2 * sxy, sxx - syy)


def _orientation(label: np.ndarray, corners: np.ndarray, stats: "_ClusterStats") -> tuple:
    """Per cluster the in-plane axes (a, b) its faces are bounded tightest along, of two: their
    edges' dominant direction (a grid's rows and columns, found 4-fold: invariant to quarter turns)
    and their corners' principal axes; and the corners' extents along them (low_a, high_a, low_b,
    high_b), measured from the origin."""
    count = stats.count
    own = np.repeat(label, 4)
    flat = corners.reshape(-1, 3)
    x, y = np.einsum("nd,nd->n", flat, stats.u[own]), np.einsum("nd,nd->n", flat, stats.v[own])
    edge = (np.roll(corners, -1, axis=1) - corners).reshape(-1, 3)
    ex, ey = np.einsum("nd,nd->n", edge, stats.u[own]), np.einsum("nd,nd->n", edge, stats.v[own])
    length = np.hypot(ex, ey)
    four = 4 * np.arctan2(ey, ex)
    edge_angle = 0.25 * np.arctan2(np.bincount(own, weights=length * np.sin(four), minlength=count),
                                   np.bincount(own, weights=length * np.cos(four), minlength=count))
    principal = _principal_angle(own, np.ones(len(own)), x, y, count)
    best = None
    for angle in (edge_angle, principal):
        cos, sin = np.cos(angle)[own], np.sin(angle)[own]
        low_a, high_a = _segment_extremes(own, cos * x + sin * y, count)
        low_b, high_b = _segment_extremes(own, -sin * x + cos * y, count)
        found = [angle, low_a, high_a, low_b, high_b, (high_a - low_a) * (high_b - low_b)]
        if best is None:
            best = found
        else:
            tighter = found[5] < best[5] * (1 - 1e-9)
            best = [np.where(tighter, new, old) for new, old in zip(found, best)]
    angle = best[0]
    a = np.cos(angle)[:, None] * stats.u + np.sin(angle)[:, None] * stats.v
    return a, np.cross(stats.normal, a), best[1:5]


def _split(scene: Scene, faces: np.ndarray, label: np.ndarray, patch_size: float) -> np.ndarray:
    """Clusters cut until none is longer than the patch size or bent (module doc, step 3). Each
    round looks only at the clusters the last one cut."""
    label = label.astype(np.int64).copy()
    active = np.arange(len(faces))
    for _ in range(MAX_ROUNDS):
        pulse()
        if len(active) == 0:
            break
        local = _compact(label[active])
        piece = _pieces(scene, faces[active], local, patch_size)
        split = np.bincount(local, weights=piece, minlength=int(local.max()) + 1) > 0
        moved = split[local]
        if not moved.any():
            break
        changed = active[moved]
        label[changed] = label.max() + 1 + _compact(local[moved] * (int(piece.max()) + 1) + piece[moved])
        active = changed
    return _compact(label)


def _pieces(scene: Scene, faces: np.ndarray, label: np.ndarray, patch_size: float) -> np.ndarray:
    """(n,) the piece of its cluster each face goes to this round (0 everywhere: no cut): slices
    across a too long cluster's longer axis, halves across a bent one's turn."""
    corners = scene.corners[faces]
    centre = corners.mean(axis=1)
    area = scene.area[faces]
    normal = scene.normal[faces]
    stats = _ClusterStats(area, normal, label)
    count = stats.count
    a, b, (low_ca, high_ca, low_cb, high_cb) = _orientation(label, corners, stats)
    # lengths by face centres: slices of ceil(length / size) leave every slice under the size
    along_a, along_b = np.einsum("nd,nd->n", centre, a[label]), np.einsum("nd,nd->n", centre, b[label])
    low_a, high_a = _segment_extremes(label, along_a, count)
    low_b, high_b = _segment_extremes(label, along_b, count)
    length_a, length_b = high_a - low_a, high_b - low_b
    longer_a = length_a >= length_b
    length = np.maximum(length_a, length_b)
    too_long = length > patch_size * SIZE_SLACK
    # bent: normals turning, and corners off the mean plane by more than noise
    height = np.einsum("nkd,nd->nk", corners, stats.normal[label]).ravel()
    plane = np.bincount(label, weights=area * np.einsum("nd,nd->n", centre, stats.normal[label]),
                        minlength=count) / np.maximum(stats.area, 1e-300)
    low_h, high_h = _segment_extremes(np.repeat(label, 4), height, count)
    stray = np.maximum(np.abs(low_h - plane), np.abs(high_h - plane))
    width = np.minimum(high_ca - low_ca, high_cb - low_cb)
    several = np.bincount(label, minlength=count) >= 2
    bent = (~too_long & several & (stats.coherence < COHERENCE) & (stray > FLATNESS * width)
            & (np.maximum(high_ca - low_ca, high_cb - low_cb) > MIN_BENT_SIZE * patch_size))
    piece = np.zeros(len(label), dtype=np.int64)
    cut = too_long[label]
    if cut.any():
        axis_value = np.where(longer_a[label], along_a, along_b)
        low = np.where(longer_a, low_a, low_b)
        slices = np.ceil(length / patch_size).astype(np.int64)
        width_of_slice = length / np.maximum(slices, 1)
        index = np.floor((axis_value - low[label]) / np.maximum(width_of_slice[label], 1e-300)).astype(np.int64)
        piece[cut] = np.clip(index, 0, slices[label] - 1)[cut]
    turn = bent[label]
    if turn.any():  # halves across the direction the normals turn in
        nu, nv = np.einsum("nd,nd->n", normal, stats.u[label]), np.einsum("nd,nd->n", normal, stats.v[label])
        heading = _principal_angle(label, area, nu, nv, count)
        d = np.cos(heading)[:, None] * stats.u + np.sin(heading)[:, None] * stats.v
        along_d = np.einsum("nd,nd->n", centre, d[label])
        low_d, high_d = _segment_extremes(label, along_d, count)
        piece[turn] = (along_d > 0.5 * (low_d + high_d)[label])[turn]
    return piece


def _absorb_small(scene: Scene, faces: np.ndarray, label: np.ndarray, pairs: np.ndarray, patch_size: float) -> np.ndarray:
    """Clusters smaller than MIN_BENT_SIZE² of the patch size's square (specks a rough surface's
    creases cut off) joined to an adjacent larger cluster, the one whose normal agrees best (within
    ABSORB_DEGREES), round by round until none is left that can join one: a rough surface keeps
    about as many clusters as a smooth one."""
    if len(pairs) == 0:
        return label
    small_area = (MIN_BENT_SIZE * patch_size) ** 2
    limit = math.cos(math.radians(ABSORB_DEGREES))
    area, normal = scene.area[faces], scene.normal[faces]
    for _ in range(ABSORB_ROUNDS):
        pulse()
        stats = _ClusterStats(area, normal, label)
        a, b = label[pairs[:, 0]], label[pairs[:, 1]]
        across = a != b
        a, b = np.concatenate([a[across], b[across]]), np.concatenate([b[across], a[across]])
        # a small cluster joins a larger one (ties: the lower label), so no two join each other
        bigger = (stats.area[b] > stats.area[a]) | ((stats.area[b] == stats.area[a]) & (b < a))
        take = (stats.area[a] < small_area) & bigger
        score = np.einsum("nd,nd->n", stats.normal[a], stats.normal[b])
        # nor may it bend what it joins past COHERENCE: the pieces of a bowl cut as bent stay apart
        summed = (stats.normal * (stats.coherence * stats.area)[:, None])
        joined = np.linalg.norm(summed[a] + summed[b], axis=1) / (stats.area[a] + stats.area[b])
        take &= (score > limit) & (joined >= np.minimum(COHERENCE, stats.coherence[b]))
        a, b, score = a[take], b[take], score[take]
        if len(a) == 0:
            return label
        order = np.lexsort((-score, a))
        first = np.ones(len(order), dtype=bool)
        first[1:] = a[order][1:] != a[order][:-1]
        target = np.arange(stats.count)
        target[a[order][first]] = b[order][first]
        while True:  # a cluster joining one that joins another goes where that one goes
            onward = target[target]
            if np.array_equal(onward, target):
                break
            target = onward
        label = _compact(target[label])
    return label


def _proxies(scene: Scene, faces: np.ndarray, label: np.ndarray) -> FaceClusters:
    """The solve's scene: every face not in `faces` as it is, then one rectangle per cluster."""
    count = int(label.max()) + 1
    area = scene.area[faces]
    stats = _ClusterStats(area, scene.normal[faces], label)
    corners = scene.corners[faces]
    centroid_of_face = np.einsum("nkd->nd", corners) / 4.0
    total = np.maximum(stats.area, 1e-300)
    centroid = np.stack([np.bincount(label, weights=area * centroid_of_face[:, d], minlength=count)
                         for d in range(3)], 1) / total[:, None]
    axis_x, axis_y, (low_x, high_x, low_y, high_y) = _orientation(label, corners - centroid[label][:, None], stats)
    box = (high_x - low_x) * (high_y - low_y)
    # the box scaled about its middle to the faces' projected area |sum a n|: what they exchange with
    # anything farther than their bumps (a rough surface's true area would stick out past its outline)
    scale = np.sqrt(stats.area * stats.coherence / np.maximum(box, 1e-300))
    middle_x, middle_y = 0.5 * (low_x + high_x), 0.5 * (low_y + high_y)
    half_x, half_y = 0.5 * (high_x - low_x) * scale, 0.5 * (high_y - low_y) * scale
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64)  # counter-clockwise about the normal
    rect_x = middle_x[:, None] + signs[None, :, 0] * half_x[:, None]
    rect_y = middle_y[:, None] + signs[None, :, 1] * half_y[:, None]
    rectangles = centroid[:, None] + rect_x[..., None] * axis_x[:, None] + rect_y[..., None] * axis_y[:, None]

    def mean(values: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(label, weights=area * values[:, c], minlength=count) for c in range(3)], 1) / total[:, None]

    first = np.zeros(count, dtype=np.int64)
    first[label[::-1]] = faces[::-1]
    kept = np.ones(len(scene), dtype=bool)
    kept[faces] = False
    kept = np.flatnonzero(kept)
    proxy_of_face = np.empty(len(scene), dtype=np.int64)
    proxy_of_face[kept] = np.arange(len(kept))
    proxy_of_face[faces] = len(kept) + label
    objects = scene.object_index[first]
    names = [scene.names[i] for i in kept] + [f"{scene.object_names[o]}~{k}" for k, o in enumerate(objects)]
    opacity = None
    if scene.opacity is not None:
        opacity = scene.opacity.with_proxies(kept, faces, label, corners, rectangles)
    proxies = Scene(
        names=names,
        corners=np.concatenate([scene.corners[kept], rectangles]),
        corner_count=np.concatenate([scene.corner_count[kept], np.full(count, 4, dtype=np.int64)]),
        reflectance=np.concatenate([scene.reflectance[kept], mean(scene.reflectance[faces])]),
        emission=np.concatenate([scene.emission[kept], mean(scene.emission[faces])]),
        object_index=np.concatenate([scene.object_index[kept], objects]),
        object_names=scene.object_names,
        uv=np.concatenate([scene.uv[kept], np.zeros((count, 4, 2))]),
        has_uv=np.concatenate([scene.has_uv[kept], np.zeros(count, dtype=bool)]),
        two_sided=np.concatenate([scene.two_sided[kept], scene.two_sided[first]]),
        extras=scene.extras,
        material_maps=scene.material_maps,
        opacity=opacity,
    )
    face_of_proxy = np.concatenate([kept, np.full(count, -1, dtype=np.int64)])
    return FaceClusters(faces=scene, proxies=proxies, proxy_of_face=proxy_of_face, face_of_proxy=face_of_proxy)


def with_face_values(clusters: FaceClusters, faces: Scene) -> FaceClusters:
    """`clusters` with its faces' reflectance and emission (e.g. material-map means) carried to the
    proxies: a merged cluster takes its faces' area-weighted means."""
    if clusters.is_identity:
        return identity_clusters(faces)
    proxies = clusters.proxies
    kept = clusters.face_of_proxy >= 0
    reflectance, emission = proxies.reflectance.copy(), proxies.emission.copy()
    reflectance[kept], emission[kept] = faces.reflectance[clusters.face_of_proxy[kept]], faces.emission[clusters.face_of_proxy[kept]]
    weight = faces.area
    total = np.maximum(np.bincount(clusters.proxy_of_face, weights=weight, minlength=len(proxies)), 1e-300)
    for target, source in ((reflectance, faces.reflectance), (emission, faces.emission)):
        means = np.stack([np.bincount(clusters.proxy_of_face, weights=weight * source[:, c], minlength=len(proxies))
                          for c in range(3)], 1) / total[:, None]
        target[~kept] = means[~kept]
    proxies = replace(proxies, reflectance=reflectance, emission=emission, material_maps=faces.material_maps)
    return FaceClusters(faces=faces, proxies=proxies, proxy_of_face=clusters.proxy_of_face,
                        face_of_proxy=clusters.face_of_proxy)
