"""Lightmaps: element (or patch) radiosity laid into per-object images in UV space.

Per object (DESIGN.md, Lightmaps):
1. Resolution from a texel density (texels per scene unit), a per-object
   override and a cap; sizes are multiples of 8 so at least the first three
   mip levels have OpenGL's sizes too (powers of two, optionally: all do).
2. UVs: the scene's `uv` (the Blender exporter's `Lightmap` map) or, when an
   object has none, an automatic layout (`uv_layout`).
3. Values: every patch carries a lattice of its element centres plus border
   points on its edges and corners; a border point's value is the mean of the
   values the patches meeting there give it (same object and world point, and
   the same UV point or a bend under 30°), so bilinear interpolation over the
   lattice is continuous across patch borders, across face borders within a
   chart, and across smooth edges between charts. Hemi-cube results (one
   value per patch) are the case S = 1.
4. The GPU rasterizes every patch's footprint into the atlas
   (`lightmap_texel_radiosity.frag`): texel centres inside a footprint get its
   interpolated value; a texel footprints only graze takes the value of the
   nearest footprint at its nearest point.
5. Gutters are dilated from the inside (`padding.dilate`) and the mip chain is
   coverage-aware (`padding.downsample_weighted`), each level dilated again.

Images are float32 linear radiance, RGBA, row 0 at v = 0 (the bottom), the
order of Blender's `image.pixels` and of OpenGL textures. Alpha is coverage:
1 on charts and their gutters, 0 elsewhere.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from . import gl, uv_layout
from .padding import dilate, downsample_weighted
from .patches import bilinear
from .scene import Scene, SceneError
from .solution import Solution, SolveError

TEXEL_DENSITY = 128.0  # texels per scene unit (metre): 7.8 mm texels
MAX_SIZE = 2048
GUTTER = 2  # texels dilated around every chart, at every mip level
SIZE_MULTIPLE = 8  # sizes round up to this so levels 1-3 halve exactly, as GL's floor(w / 2) does
MIN_SIZE = 8
UV_TOLERANCE = 1e-3  # how far given UVs may stray outside [0, 1]
SMOOTH_EDGE_DEGREES = 30.0  # faces meeting flatter than this share values at their edge (Blender's auto smooth)


@dataclass
class Lightmap:
    object_name: str
    levels: list[np.ndarray]  # mip chain down to 1 x 1, (h_k, w_k, 4) float32; levels[0] is the image
    coverage: list[np.ndarray]  # per level, (h_k, w_k) float32: fraction of the texel on charts (alpha adds gutters)
    patch_index: np.ndarray  # (H, W) int32: patch whose footprint holds the texel centre, -1 if none
    surface_uv: dict[int, np.ndarray]  # surface index -> (k, 2) vertex UVs the map was baked with
    texel_density: float  # achieved texels per scene unit: sqrt(texels inside faces / face area)

    @property
    def rgba(self) -> np.ndarray:
        return self.levels[0]

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in texels."""
        return self.rgba.shape[1], self.rgba.shape[0]


def element_values(solution: Solution) -> np.ndarray:
    """(P, S, S, 3) radiosity: the elements, or the patch values as S = 1 (a grey one-channel
    result is repeated into three)."""
    if solution.element_radiosity is not None:
        values = np.asarray(solution.element_radiosity, dtype=np.float64)
    else:
        values = np.asarray(solution.patch_radiosity, dtype=np.float64)[:, None, None, :]
    return np.broadcast_to(values, values.shape[:3] + (3,)) if values.shape[3] == 1 else values


def lattice_parameters(elements: int) -> np.ndarray:
    """(S + 2,) patch parameters of the lattice: 0, the element centres, 1."""
    return np.concatenate([[0.0], (np.arange(elements) + 0.5) / elements, [1.0]])


def _sum_within_groups(group: np.ndarray, joins, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For every item i, the sum of values[j] and the count over the items j of its group with
    joins(i, j) true (each item joins itself). Items are compared at every offset within their
    group: a loop over the largest group size (a handful), vectorized over all items."""
    order = np.argsort(group, kind="stable")
    sorted_group = group[order]
    total, count = values.copy(), np.ones(len(group))
    for offset in range(1, len(group)):
        same = sorted_group[offset:] == sorted_group[:-offset]
        if not same.any():
            break
        i, j = order[:-offset][same], order[offset:][same]
        joined = joins(i, j)
        i, j = i[joined], j[joined]
        np.add.at(total, i, values[j])
        np.add.at(total, j, values[i])
        np.add.at(count, i, 1)
        np.add.at(count, j, 1)
    return total, count


def continuous_lattice(corners: np.ndarray, patch_uv: np.ndarray, values: np.ndarray, group: np.ndarray,
                       normals: np.ndarray, world_quantum: float, uv_quantum: float) -> np.ndarray:
    """(P, S+2, S+2, 3) lattice values [patch, t row, s column].

    Inside: the element values. Border points: each patch proposes its nearest
    element's value there (one proposal per patch and place: its own lattice
    points at one place, e.g. along a triangle's collapsed edge, are averaged
    first); then a patch's border value is the mean of the proposals of the
    patches of its `group` (object) at the same world point that either share
    the UV point there (same chart: the image must be continuous) or bend
    from it by less than SMOOTH_EDGE_DEGREES (a smooth surface split into
    faces, e.g. Blender's Lightmap Pack making each face its own chart: no
    seams between them). Creases keep their own values: light differs there."""
    count, elements = values.shape[:2]
    clamp = np.clip(np.arange(elements + 2) - 1, 0, elements - 1)
    lattice = values[:, clamp][:, :, clamp].copy()
    params = lattice_parameters(elements)
    s, t = np.meshgrid(params, params)  # [t row, s column]
    border = np.ones_like(s, dtype=bool)
    border[1:-1, 1:-1] = False
    per_patch = int(border.sum())
    world = np.round(bilinear(corners, s[border], t[border]).reshape(-1, 3) / world_quantum)
    uv = np.round(bilinear(patch_uv, s[border], t[border]).reshape(-1, 2) / uv_quantum)
    owner = np.repeat(np.arange(count), per_patch)
    keys = np.concatenate([group[owner][:, None], world, uv], axis=1).astype(np.int64)
    _, place = np.unique(keys, axis=0, return_inverse=True)  # same object, world and UV point
    place = place.ravel()
    _, pair_of_point = np.unique(owner * (place.max() + 1) + place, return_inverse=True)
    pair_of_point = pair_of_point.ravel()
    points_per_pair = np.bincount(pair_of_point)
    proposals = lattice[:, border].reshape(-1, 3)
    pair_value = np.stack([np.bincount(pair_of_point, proposals[:, c]) for c in range(3)], axis=1)
    pair_value /= points_per_pair[:, None]
    first = np.zeros(len(points_per_pair), dtype=np.int64)
    first[pair_of_point[::-1]] = np.arange(len(pair_of_point))[::-1]  # a point of each pair
    pair_patch, pair_place = owner[first], place[first]
    _, pair_world = np.unique(keys[first, :4], axis=0, return_inverse=True)  # object and world point
    smooth = math.cos(math.radians(SMOOTH_EDGE_DEGREES))

    def joins(i, j):
        return (pair_place[i] == pair_place[j]) | (
            np.einsum("ij,ij->i", normals[pair_patch[i]], normals[pair_patch[j]]) > smooth)

    total, joined = _sum_within_groups(pair_world.ravel(), joins, pair_value)
    lattice[:, border] = (total / joined[:, None])[pair_of_point].reshape(count, per_patch, 3)
    return lattice


def resolve_size(natural: tuple[int, int], override, max_size: int, power_of_two: bool,
                 object_name: str) -> tuple[int, int]:
    """Final (width, height): the override or the natural size, rounded and capped."""
    if override is not None:
        try:
            size = (override, override) if isinstance(override, numbers.Real) else tuple(override)
            valid = len(size) == 2 and all(int(n) == n >= MIN_SIZE for n in size)
        except (TypeError, ValueError):
            valid = False
        if not valid:
            raise SolveError(f"object '{object_name}': lightmap resolution {override!r} must be an integer"
                             f" (or width, height) of at least {MIN_SIZE}")
        size = tuple(int(n) for n in size)
    else:
        size = tuple(max(MIN_SIZE, -(-int(n) // SIZE_MULTIPLE) * SIZE_MULTIPLE) for n in natural)
    if power_of_two:
        size = tuple(1 << (n - 1).bit_length() for n in size)
        cap = 1 << (max_size.bit_length() - 1)
    else:
        cap = max_size
    return tuple(min(n, cap) for n in size)


def _object_surfaces(scene: Scene) -> dict[str, list[int]]:
    objects: dict[str, list[int]] = {}
    for index, surface in enumerate(scene.surfaces):
        objects.setdefault(surface.object_name, []).append(index)
    return objects


def _uv_polygon_area(uv: np.ndarray) -> float:
    x, y = uv[:, 0], uv[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _given_uvs(scene: Scene, name: str, indices: list[int]) -> bool:
    """True if the object's surfaces all carry UVs, False if none do; mixed or out-of-range is an error."""
    with_uv = [scene.surfaces[i].uv is not None for i in indices]
    if not any(with_uv):
        return False
    if not all(with_uv):
        missing = scene.surfaces[indices[with_uv.index(False)]].name
        raise SceneError(f"object '{name}': surface '{missing}' has no lightmap 'uv' but others of the"
                         " object do; give every surface of an object UVs, or none")
    for i in indices:
        uv = scene.surfaces[i].uv
        if uv.min() < -UV_TOLERANCE or uv.max() > 1 + UV_TOLERANCE:
            raise SceneError(f"surface '{scene.surfaces[i].name}': lightmap UVs leave the [0, 1] square")
    if sum(_uv_polygon_area(scene.surfaces[i].uv) for i in indices) <= 0:
        raise SceneError(f"object '{name}': its lightmap UVs have zero area")
    return True


def _rasterize(ctx, corners_texels: np.ndarray, lattice: np.ndarray, size: tuple[int, int]):
    """GPU pass: (H, W, 3) float32 values and (H, W) int32 signed local patch ids (see the shader)."""
    width, height = size
    count, side = lattice.shape[:2]
    low = np.floor(corners_texels.min(axis=1)) - 1  # one texel more: grazed texels count too
    high = np.ceil(corners_texels.max(axis=1)) + 1
    box = np.stack([low, np.stack([high[:, 0], low[:, 1]], 1), high,
                    low, high, np.stack([low[:, 0], high[:, 1]], 1)], axis=1)  # (P, 6, 2)
    vertices = np.empty(count * 6, dtype=[("texel", "f4", 2), ("patch", "i4")])
    vertices["texel"] = box.reshape(-1, 2)
    vertices["patch"] = np.repeat(np.arange(count, dtype=np.int32), 6)
    lattice_rgba = np.zeros((count, side, side, 4), dtype=np.float32)
    lattice_rgba[..., :3] = lattice

    program = gl.program(ctx, "lightmap_patch_bounds.vert", "lightmap_texel_radiosity.frag")
    program["size"].value = (float(width), float(height))
    program["elements"].value = side - 2
    resources = [program]
    try:
        corner_buffer = ctx.buffer(corners_texels.astype(np.float32).tobytes())
        lattice_buffer = ctx.buffer(lattice_rgba.tobytes())
        vbo = ctx.buffer(vertices.tobytes())
        vao = ctx.vertex_array(program, [(vbo, "2f 1i", "in_texel", "in_patch")])
        radiance = ctx.texture((width, height), 4, dtype="f4")
        patch_ids = ctx.texture((width, height), 1, dtype="i4")
        depth = ctx.depth_renderbuffer((width, height))
        fbo = ctx.framebuffer([radiance, patch_ids], depth)
        resources += [corner_buffer, lattice_buffer, vbo, vao, radiance, patch_ids, depth, fbo]
        fbo.use()
        fbo.viewport = (0, 0, width, height)
        fbo.clear(depth=1.0)
        ctx.enable_only(ctx.DEPTH_TEST)  # no culling: mirrored UV charts wind clockwise
        ctx.depth_func = "<"
        corner_buffer.bind_to_storage_buffer(0)
        lattice_buffer.bind_to_storage_buffer(1)
        vao.render()
        values = np.frombuffer(fbo.read(components=4, dtype="f4", attachment=0), dtype=np.float32)
        ids = np.frombuffer(fbo.read(components=1, dtype="i4", attachment=1), dtype=np.int32)
    finally:
        for resource in reversed(resources):
            resource.release()
    return values.reshape(height, width, 4)[..., :3], ids.reshape(height, width)


def mip_levels(values: np.ndarray, coverage: np.ndarray, gutter: int) -> tuple[list, list]:
    """RGBA float32 levels down to 1 x 1, and each level's chart coverage (the fraction of the
    texel on charts). Each level is the coverage-weighted 2x2 mean of the previous level's chart
    texels (not its gutter), so every level's coverage-weighted mean is level 0's; then it is
    dilated by `gutter` texels. Odd sizes halve rounding up (padded with uncovered texels);
    OpenGL's mip sizes, floor(w / 2), agree while sizes stay even (see `gl_mip_count`)."""
    coverage = np.asarray(coverage, dtype=np.float64)
    levels, coverages = [], []
    while True:
        filled, reached = dilate(values, coverage > 0, gutter)
        levels.append(np.concatenate([filled, reached[..., None]], axis=2).astype(np.float32))
        coverages.append(coverage.astype(np.float32))
        if coverage.shape == (1, 1):
            return levels, coverages
        values, coverage = downsample_weighted(values, coverage)  # a 1-texel axis stays 1


def mip_chain(values: np.ndarray, covered: np.ndarray, gutter: int) -> list[np.ndarray]:
    """The RGBA levels of `mip_levels` (covered: bool mask or coverage fractions)."""
    return mip_levels(values, covered, gutter)[0]


def gl_mip_count(levels: list[np.ndarray]) -> int:
    """How many leading levels have OpenGL's sizes (max(1, floor(w / 2^k)), same for h)."""
    height, width = levels[0].shape[:2]
    count = 0
    for k, level in enumerate(levels):
        if level.shape[:2] != (max(1, height >> k), max(1, width >> k)):
            break
        count += 1
    return count


def bake_lightmaps(scene: Scene, solution: Solution, texel_density: float = TEXEL_DENSITY,
                   resolution_overrides: dict | None = None, max_size: int = MAX_SIZE,
                   power_of_two: bool = False, ctx=None, gutter: int = GUTTER,
                   objects=None) -> dict[str, Lightmap]:
    """One `Lightmap` per object of `scene` (or of `objects`, names of some of them: objects
    that only occlude need none), keyed by object name (see the module doc)."""
    if not texel_density > 0:
        raise SolveError(f"texel density must be positive, got {texel_density}")
    if max_size < MIN_SIZE:
        raise SolveError(f"the lightmap size cap must be at least {MIN_SIZE}, got {max_size}")
    all_objects = _object_surfaces(scene)
    overrides = dict(resolution_overrides or {})
    unknown = sorted((set(overrides) | set(objects or ())) - set(all_objects))
    if unknown:
        raise SolveError(f"no object '{unknown[0]}' in the scene to bake a lightmap for")
    chosen = set(all_objects if objects is None else objects)
    objects = {name: indices for name, indices in all_objects.items() if name in chosen}
    patches = solution.patches
    values = element_values(solution)
    if len(values) != len(patches):
        raise SolveError("the solution does not belong to this scene (patch counts differ)")
    scene_size = max(scene.diameter, 1e-30)
    pad = gutter + 1  # a chart's grazed texels, then its gutter

    layouts = {}
    object_of_surface = np.full(len(scene.surfaces), -1, dtype=np.int64)  # -1: not baked
    laid_out = np.zeros(len(scene.surfaces), dtype=bool)  # surfaces given automatic UVs here
    uv_maps = np.zeros((len(scene.surfaces), 2, 4))  # their affine maps: uv = M @ [x, y, z, 1]
    for number, (name, indices) in enumerate(objects.items()):
        object_of_surface[indices] = number
        if _given_uvs(scene, name, indices):
            world = sum(scene.surfaces[i].area for i in indices)
            uv_area = sum(_uv_polygon_area(scene.surfaces[i].uv) for i in indices)
            side = texel_density * math.sqrt(world / uv_area)
            size = resolve_size((math.ceil(side),) * 2, overrides.get(name), max_size, power_of_two, name)
            layouts[name] = (size, None)
        else:
            charts = uv_layout.make_charts(scene.surfaces, indices, scene_size)
            natural = uv_layout.natural_size(charts, texel_density, pad)
            size = resolve_size(natural, overrides.get(name), max_size, power_of_two, name)
            scale = uv_layout.largest_fitting_scale(charts, size, pad, name)
            layout = uv_layout.place_charts(charts, size, scale, pad)
            laid_out[indices] = True
            uv_maps[indices] = [layout.uv_maps[i] for i in indices]
            layouts[name] = (size, layout)

    patch_uv = np.array(patches.uv, dtype=np.float64)
    auto = laid_out[patches.surface]
    maps = uv_maps[patches.surface[auto]]
    patch_uv[auto] = np.einsum("pij,pkj->pki", maps[..., :3], patches.corners[auto]) + maps[:, None, :, 3]

    group = object_of_surface[patches.surface]
    baked = np.flatnonzero(group >= 0)
    lattice = np.zeros((len(patches),) + (values.shape[1] + 2,) * 2 + (3,))
    lattice[baked] = continuous_lattice(patches.corners[baked], patch_uv[baked], values[baked], group[baked],
                                        patches.normal[baked], world_quantum=1e-6 * scene_size, uv_quantum=1e-6)
    lightmaps = {}
    with gl.gl_context(ctx) as gl_ctx:
        for name, indices in objects.items():
            size, layout = layouts[name]
            mine = np.flatnonzero(np.isin(patches.surface, indices))
            corners_texels = patch_uv[mine] * np.asarray(size, dtype=np.float64)
            texel_values, signed_ids = _rasterize(gl_ctx, corners_texels, lattice[mine], size)
            covered = signed_ids != 0
            inside = signed_ids > 0
            patch_index = np.where(inside, mine[np.maximum(signed_ids, 1) - 1], -1).astype(np.int32)
            if not covered.any():
                raise SolveError(f"object '{name}': its faces cover no texel of a {size[0]}x{size[1]}"
                                 " lightmap; raise the texel density or its resolution")
            if layout is None:
                surface_uv = {i: scene.surfaces[i].uv for i in indices}
            else:
                surface_uv = {i: layout.surface_uv(i, scene.surfaces[i].vertices) for i in indices}
            area = sum(scene.surfaces[i].area for i in indices)
            levels, coverage = mip_levels(texel_values.astype(np.float64), covered, gutter)
            lightmaps[name] = Lightmap(
                object_name=name,
                levels=levels,
                coverage=coverage,
                patch_index=patch_index,
                surface_uv=surface_uv,
                texel_density=math.sqrt(inside.sum() / area),
            )
    return lightmaps
