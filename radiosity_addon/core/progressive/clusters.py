"""Clusters of patches that shoot as one (clustering, Smits et al. 1994), so that the number of
shots stops growing with the number of patches.

Progressive refinement's cost is shots × receiving elements. Without clusters every patch that
holds a share of the light shoots, so shots grow with the patches and the solve with their square.
Here the patches are grouped once per solve into nested levels of clusters: patches of one object
whose centres share a cell of a uniform grid, whose normals share a bin (an octahedral grid of
NORMAL_BINS × NORMAL_BINS over directions, about 20° wide) and whose planes lie within a slab of
PLANE_SLAB cells. The coarsest cell is the smallest of a geometric series that gives at most
`target` clusters, found by bisection (so their count depends on the scene's extent, not on its
tessellation); each finer level halves it, down to the level whose clusters hold FINEST_MEMBERS
patches or fewer on average (at most MAX_CLUSTER_LEVELS levels): a denser scene gets more levels,
not more patches shooting alone.

A cluster shoots the sum of its members' unshot power as one polygon: a rectangle in the plane of
its eye patch (the member nearest the centroid of the members' unshot power), along that patch's
edges, with the centroid and variances of that power (so a strip of patches shoots as a strip,
and a half-lit cluster from its lit half), seen from the eye patch's visibility map. Every
member's residual is cleared by the shot and no member receives from it. That is exact for far
receivers and approximate within about a cell, so only weak clusters shoot as one
(`ClusteredSelection`): a patch shoots with the coarsest of its clusters whose power is under
CLUSTER_POWER × the emitted light / the coarsest level's cluster count (× tolerance /
CLUSTER_TOLERANCE below that tolerance), or alone (the sun's patch on the floor, a wall beside
a lamp). One bound for every level: a finer cluster is smaller, so at the same power it errs less
than a coarser one that already shoots as one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import Patches
from ..scene.gaps import emitter_gaps
from ..scene.geometry import tangent_frames
from ..shooting import Shooter
from .selection import strongest

NORMAL_BINS = 8  # per side of the octahedral grid of normal directions
CELL_GROWTH = 1.25  # ratio between the cell sizes tried
CLUSTER_POWER = 1.0  # a cluster shoots as one below this many mean cluster powers of the emitted light
CLUSTER_TOLERANCE = 3e-2  # ... at this tolerance or above (where it was measured); at a finer one, that share
MAX_CLUSTER_LEVELS = 7  # nested levels of clusters at most, each cell twice the next finer one's (shot.glsl's PatchPlane holds 7)
FINEST_MEMBERS = 2.0  # levels are added until a cluster of the finest holds this many patches on average
PLANE_SLAB = 0.125  # members lie within this many cells of one plane (a painting and the wall behind it part)


def octahedral_bins(normals: np.ndarray, bins: int = NORMAL_BINS) -> np.ndarray:
    """(P,) bin of each unit normal on an octahedral grid of bins × bins."""
    n = normals / np.abs(normals).sum(axis=1, keepdims=True)
    u, v = n[:, 0].copy(), n[:, 1].copy()
    lower = n[:, 2] < 0
    u[lower], v[lower] = ((1 - np.abs(n[lower, 1])) * np.sign(n[lower, 0] + 1e-30),
                          (1 - np.abs(n[lower, 0])) * np.sign(n[lower, 1] + 1e-30))
    i = np.clip(((u + 1) / 2 * bins).astype(np.int64), 0, bins - 1)
    j = np.clip(((v + 1) / 2 * bins).astype(np.int64), 0, bins - 1)
    return j * bins + i


class ClusterGrid:
    """The patches' place on the clusters' grids, for any cell side: their centres from the
    grid's origin, their planes' distances, normal bins and owners, and the bounds of each, found
    once (a grid's keys then cost one pass over the patches, no search for bounds)."""

    def __init__(self, centers: np.ndarray, normals: np.ndarray, owner: np.ndarray):
        self.local = centers - centers.min(axis=0) if len(centers) else centers
        self.plane = (normals * centers).sum(axis=1)
        self.normal_bin = octahedral_bins(normals)
        self.owner = owner
        self.extent = self.local.max(axis=0) if len(centers) else np.zeros(3)
        self.plane_range = (float(self.plane.min(initial=0.0)), float(self.plane.max(initial=0.0)))
        self.owners = int(owner.max(initial=0)) + 1
        self.counts: dict[float, int] = {}

    def columns(self, cell: float) -> list[tuple[np.ndarray, int, int]]:
        """Each patch's (cell x, y, z, normal bin, plane slab, owner) for cells of side `cell`, as
        (column, lowest value, span) for `packed_keys`."""
        cells = np.floor(self.local / cell).astype(np.int64)
        slab = PLANE_SLAB * cell
        offset = np.floor(self.plane / slab).astype(np.int64)
        low, high = (int(np.floor(bound / slab)) for bound in self.plane_range)
        spans = [int(np.floor(e / cell)) + 1 for e in self.extent]
        return [(cells[:, 0], 0, spans[0]), (cells[:, 1], 0, spans[1]), (cells[:, 2], 0, spans[2]),
                (self.normal_bin, 0, NORMAL_BINS * NORMAL_BINS), (offset, low, high - low + 1),
                (self.owner, 0, self.owners)]

    def count(self, cell: float) -> int:
        """How many clusters cells of side `cell` give (a sort, no inverse; each side once)."""
        if cell not in self.counts:
            self.counts[cell] = int(np.unique(packed_keys(self.columns(cell))).size)
        return self.counts[cell]


def packed_keys(columns: list[tuple[np.ndarray, int, int]]) -> np.ndarray:
    """(P,) one int64 per row whose order is the lexicographic order of the rows' tuples of
    integer (column, lowest value, span): mixed radix, renumbered first whenever the key would
    overflow."""
    key, bound = np.zeros(len(columns[0][0]), dtype=np.int64), 1
    for column, low, span in columns:
        if bound * span >= 2 ** 62:
            key = np.unique(key, return_inverse=True)[1].ravel()
            bound = int(key.max(initial=0)) + 1
        key, bound = key * span + (np.asarray(column, dtype=np.int64) - low), bound * span
    return key


def coarser(columns: list[tuple[np.ndarray, int, int]]) -> list[tuple[np.ndarray, int, int]]:
    """The columns for cells twice as wide: floor(floor(x) / 2) = floor(x / 2), and a cell side
    halved or doubled is exact in floating point, so these are the columns `ClusterGrid.columns`
    gives for the doubled side, bit for bit."""
    result = [(column // 2, low // 2, (low + span - 1) // 2 - low // 2 + 1)
              for column, low, span in columns[:3]]
    result.append(columns[3])
    column, low, span = columns[4]
    result.append((column // 2, low // 2, (low + span - 1) // 2 - low // 2 + 1))
    result.append(columns[5])
    return result


def grouped(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index 0 .. G-1 of each row's key in the keys' order, one row of each group)."""
    inverse = np.unique(key, return_inverse=True)[1].ravel()
    one_row = np.empty(int(inverse.max(initial=-1)) + 1, dtype=np.int64)
    one_row[inverse] = np.arange(len(key))
    return inverse, one_row


@dataclass
class PatchClusters:
    of_patch: np.ndarray  # (P,) cluster of each patch
    members: np.ndarray  # (C,) member counts
    by_cluster: np.ndarray  # (P,) patch indices grouped by cluster: cluster c's are [starts[c], starts[c + 1])
    starts: np.ndarray  # (C + 1,)
    cell: float  # the grid's cell side

    def __len__(self) -> int:
        return len(self.members)

    def power(self, patch_power: np.ndarray) -> np.ndarray:
        """(C,) summed over members."""
        return np.bincount(self.of_patch, weights=patch_power, minlength=len(self))

    def members_of(self, cluster: int) -> np.ndarray:
        return self.by_cluster[self.starts[cluster]:self.starts[cluster + 1]]


def cluster_owners(scene, patches: Patches) -> np.ndarray:
    """(P,) who may cluster with whom (`build_clusters`' `owner`): each patch's object, numbered in
    the names' order (from the index: a Surface per face cost more than the clusters), except
    that a patch facing an emitter across a gap narrower than itself, or an emitter's side facing
    one (a ceiling over a light hung just under it, and that light's back), is alone: a cluster's
    one polygon, from one eye, cannot keep light within a gap's width of where it was (a cavity
    clustered so comes out too bright)."""
    name_rank = np.argsort(np.argsort(np.array(scene.object_names, dtype=object)))
    owner = name_rank[scene.object_index][patches.surface]
    alone = np.flatnonzero(emitter_gaps(patches) < np.sqrt(patches.area))
    owner[alone] = owner.max(initial=0) + 1 + np.arange(len(alone))
    return owner


def build_clusters(patches: Patches, target: int, owner: np.ndarray | None = None,
                   max_levels: int = MAX_CLUSTER_LEVELS) -> list[PatchClusters]:
    """Nested levels of clusters, finest first; the coarsest has about `target` clusters at most
    (fewer when the patches are fewer), each finer one cells half as wide, the finest the first
    whose clusters hold FINEST_MEMBERS patches or fewer on average (or the `max_levels`th).
    Patches of different `owner`s (P,) (their objects: a book and the shelf it stands in) never
    cluster.
    About ten sorts of the patches whatever the number of levels: the coarsest cell and the
    finest level by bisection over counts, then the finest level grouped and each coarser
    one grouped from the finer one's clusters (its cells nest in theirs), not from the patches."""
    owner = np.zeros(len(patches), dtype=np.int64) if owner is None else np.asarray(owner, dtype=np.int64)
    grid = ClusterGrid(patches.center, patches.normal, owner)
    extent = float(np.max(grid.extent)) if len(patches) else 0.0
    smallest = max(extent, 1e-6) / 64
    last = int(np.ceil(np.log(256) / np.log(CELL_GROWTH)))  # smallest × CELL_GROWTH^last ≥ 4 × extent
    low, high = 0, last  # bisection: the counts fall as the cells grow (a few sorts, not one per size)
    while low < high:
        middle = (low + high) // 2
        low, high = (low, middle) if grid.count(smallest * CELL_GROWTH ** middle) <= target else (middle + 1, high)
    cell = smallest * CELL_GROWTH ** low
    # the finest level: the first, coarse to fine, whose clusters hold FINEST_MEMBERS or fewer on
    # average (counts grow as cells shrink: bisection again)
    fine = lambda k: len(patches) <= FINEST_MEMBERS * grid.count(cell / 2 ** k)  # noqa: E731
    low, high = 1, max_levels - 1
    if max_levels == 1 or fine(0):
        low = high = 0
    while low < high:
        middle = (low + high) // 2
        low, high = (low, middle) if fine(middle) else (middle + 1, high)
    columns = grid.columns(cell / 2 ** low)
    of_patch, one_row = grouped(packed_keys(columns))
    by_cluster = np.argsort(of_patch, kind="stable")
    result = []
    for k in range(low, -1, -1):  # finest first; cells of side cell / 2^k
        members = np.bincount(of_patch, minlength=len(one_row))
        result.append(PatchClusters(of_patch=of_patch, members=members, by_cluster=by_cluster,
                                    starts=np.concatenate([[0], np.cumsum(members)]), cell=cell / 2 ** k))
        if k:  # the next coarser level from one row of each of this level's clusters
            columns = coarser([(column[one_row], lowest, span) for column, lowest, span in columns])
            parent, one_row = grouped(packed_keys(columns))
            of_patch = parent[of_patch]
            by_cluster = regrouped(result[-1], parent)
    return result


def regrouped(finer: "PatchClusters", parent: np.ndarray) -> np.ndarray:
    """The patches grouped by coarser cluster, from `finer`'s grouping and each finer cluster's
    `parent`: the finer clusters' runs taken parent by parent (a sort of the clusters, not of the
    patches), so within a coarser cluster patches come finer cluster by finer cluster."""
    order = np.argsort(parent, kind="stable")
    counts = finer.members[order]
    run_start = np.repeat(finer.starts[order] - (np.cumsum(counts) - counts), counts)
    return finer.by_cluster[run_start + np.arange(len(finer.by_cluster))]


def spread_rectangle(center: np.ndarray, x: np.ndarray, y: np.ndarray, points: np.ndarray, area: np.ndarray,
                     weight: np.ndarray):
    """The rectangle along x and y (the eye patch's edges: a grid of patches stays inside it) with
    the centroid and variances of `weight`ed squares of `area` at `points` in the plane (center;
    x, y), cut to the squares' extent (a steep gradient must not push it past the members):
    (its centre, its two half sides)."""
    weight = weight / weight.sum()
    reach = 0.5 * np.sqrt(area)  # half a member's side
    middle, sides = center, []
    for axis in (x, y):
        along = (points - center) @ axis
        mean = weight @ along
        # a uniform rectangle of side s has the variance s²/12, a member square of area A A/12
        half = 0.5 * np.sqrt(12 * (weight @ ((along - mean) ** 2 + area / 12.0)))
        low, high = max(mean - half, float((along - reach).min())), min(mean + half, float((along + reach).max()))
        middle = middle + 0.5 * (low + high) * axis
        sides.append(0.5 * (high - low) * axis)
    return middle, sides[0], sides[1]


class ClusterShooters:
    """Clusters as shooters (`Shooter.cluster`): a rectangle with the spread of the members'
    unshot power, on the plane of the member nearest its centroid, seen from that member."""

    def __init__(self, patches: Patches, clusters: PatchClusters, level: int = 1):
        self.clusters, self.level = clusters, level
        self.center, self.normal, self.area = patches.center, patches.normal, patches.area
        self.edge = patches.corners[:, 1] - patches.corners[:, 0]

    def shooter(self, cluster: int, power: np.ndarray, patch_power: np.ndarray) -> Shooter:
        """Cluster `cluster` shooting `power` (3,) (its members' unshot power; `patch_power` (P,)
        places it)."""
        members = self.clusters.members_of(cluster)
        weight = patch_power[members]
        weight = weight if weight.sum() > 0 else self.area[members]
        centroid = (weight @ self.center[members]) / weight.sum()
        eye = int(members[np.argmin(np.linalg.norm(self.center[members] - centroid, axis=1))])
        normal = self.normal[eye]
        _, x, y, _ = tangent_frames(self.center[eye:eye + 1], normal[None], self.edge[eye:eye + 1])
        center = centroid - np.dot(centroid - self.center[eye], normal) * normal  # onto the eye's plane
        center, a, b = spread_rectangle(center, x[0], y[0], self.center[members], self.area[members], weight)
        polygon = np.array([center - a - b, center + a - b, center + a + b, center - a + b])  # counter-clockwise
        area = 4.0 * float(np.linalg.norm(a) * np.linalg.norm(b))
        return Shooter(position=self.center[eye], axes=(x[0], y[0], normal), polygon=polygon, area=area,
                       radiosity=np.asarray(power, dtype=np.float64) / area, patch=cluster, cluster=self.level)


class ClusteredSelection:
    """The next shooters when patches cluster, in `levels` (finest first, each nested in the next):
    each patch shoots with the coarsest of its clusters that is weak — two members or more, power
    under CLUSTER_POWER × the emitted light / the coarsest level's cluster count (× tolerance /
    CLUSTER_TOLERANCE below that tolerance) — or alone when none is; the strongest of these
    candidates shoot. A strong coarse cluster thus splits into finer ones before it splits into
    patches."""

    def __init__(self, patches: Patches, levels: list[PatchClusters], emitted: float,
                 tolerance: float = CLUSTER_TOLERANCE):
        self.levels = levels
        # a finer tolerance asks for less of the clusters' approximation too
        self.threshold = CLUSTER_POWER * emitted / len(levels[-1]) * min(1.0, tolerance / CLUSTER_TOLERANCE)
        self.area = patches.area
        self.shooters = [ClusterShooters(patches, level, k) for k, level in enumerate(levels, start=1)]

    def choose(self, residuals, count: int) -> tuple[np.ndarray, list[Shooter]]:
        """(patches that shoot alone, strongest first; the clusters' shooters)."""
        unit_level = np.zeros(len(self.area), dtype=np.int64)
        powers = []
        for k, level in enumerate(self.levels, start=1):
            power = level.power(residuals.power)
            weak = (power < self.threshold) & (level.members >= 2)
            unit_level = np.where(weak[level.of_patch], k, unit_level)  # coarser levels override
            powers.append(power)
        candidates = [np.where(unit_level == 0, residuals.power, 0.0)]
        for k, (level, power) in enumerate(zip(self.levels, powers), start=1):
            unit = np.zeros(len(level), dtype=bool)
            unit[level.of_patch[unit_level == k]] = True
            candidates.append(np.where(unit, power, 0.0))
        offsets = np.cumsum([0] + [len(c) for c in candidates])
        chosen = strongest(np.concatenate(candidates), count)
        alone = chosen[chosen < offsets[1]]
        shooters = []
        for index in chosen[chosen >= offsets[1]]:
            k = int(np.searchsorted(offsets, index, side="right")) - 1  # its level
            cluster = int(index - offsets[k])
            members = self.levels[k - 1].members_of(cluster)
            power = self.area[members] @ residuals.mean[members]
            shooters.append(self.shooters[k - 1].shooter(cluster, power, residuals.power))
        return alone, shooters
