"""Lightmaps: element (or patch) radiosity laid into per-object images in UV space.

Per object (docs/architecture.md, Lightmaps):
1. Resolution from a texel density, a per-object override and a cap (`size`).
2. UVs: the scene's `uv` (the Blender exporter's `Lightmap` map) or, when an object has
   none, an automatic layout (`charts`).
3. Values: patch lattices continuous across patch borders, chart borders and smooth edges
   (`lattice`), of the light H (content "light") or the radiosity B (content "combined"; an
   object with a material map gets B = E + ρH per texel from its texels' albedo and emission).
4. The GPU rasterizes every patch's footprint into the atlas (`rasterize`).
5. Gutters are dilated from the inside and the mip chain is coverage-aware (`mips`).

Images are float32 linear radiance, RGBA, row 0 at v = 0 (the bottom), the order of
Blender's `image.pixels` and of OpenGL textures. Alpha is coverage: 1 on charts and their
gutters, 0 elsewhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SceneError, SolveError
from ..gpu import GPU, open_gpu
from ..scene import Scene
from ..settings import LightmapSettings
from ..solution import Solution
from ..shooting.sky import element_frames
from ..uvspace import rasterize
from . import charts
from .contact import in_contact
from .direct import (direct_light, emitters_reflected_light, emitters_reflection, footprint_points,
                     matched_map_resolution, sharp_texels, texel_axes, texel_points)
from .lattice import continuous_lattice, element_values
from .mips import filled_image, mip_levels
from .size import resolve_size

UV_TOLERANCE = 1e-3  # how far given UVs may stray outside [0, 1]


@dataclass
class Lightmap:
    object_name: str
    levels: list[np.ndarray]  # mip chain down to 1 x 1, (h_k, w_k, 4) float32; levels[0] is the image
    coverage: list[np.ndarray]  # per level, (h_k, w_k) float32: fraction of the texel on charts (alpha adds gutters)
    patch_index: np.ndarray  # (H, W) int32: patch whose footprint holds the texel centre, -1 if none
    surfaces: np.ndarray  # (n,) indices of the object's surfaces
    surface_uv: np.ndarray  # (n, 4, 2) corner UVs the map was baked with (triangles repeat c2)
    texel_density: float  # achieved texels per scene unit: sqrt(texels inside faces / face area)
    content: str = "light"  # "light": H (shown as E + ρ H), "combined": B

    @property
    def rgba(self) -> np.ndarray:
        return self.levels[0]

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in texels."""
        return self.rgba.shape[1], self.rgba.shape[0]

    def filled_image(self) -> np.ndarray:
        """Level 0 with every texel outside the charts filled from coarser levels (for renderers
        that build their own mipmaps, like Blender): float32 (H, W, 4), alpha = coverage."""
        return filled_image(self.levels)


def uv_polygon_area(uv: np.ndarray) -> np.ndarray:
    """(n,) areas of UV polygons (n, 4, 2) (shoelace; a repeated corner adds nothing)."""
    x, y = uv[..., 0], uv[..., 1]
    return 0.5 * np.abs((x * np.roll(y, -1, axis=-1) - y * np.roll(x, -1, axis=-1)).sum(axis=-1))


def _given_uvs(scene: Scene, name: str, indices: np.ndarray) -> bool:
    """True if the object's surfaces all carry UVs, False if none do; mixed or out-of-range is an error."""
    with_uv = scene.has_uv[indices]
    if not with_uv.any():
        return False
    if not with_uv.all():
        missing = scene.names[indices[np.flatnonzero(~with_uv)[0]]]
        raise SceneError(f"object '{name}': surface '{missing}' has no lightmap 'uv' but others of the"
                         " object do; give every surface of an object UVs, or none")
    uv = scene.uv[indices]
    outside = np.flatnonzero((uv.min(axis=(1, 2)) < -UV_TOLERANCE) | (uv.max(axis=(1, 2)) > 1 + UV_TOLERANCE))
    if len(outside):
        raise SceneError(f"surface '{scene.names[indices[outside[0]]]}': lightmap UVs leave the [0, 1] square")
    if uv_polygon_area(uv).sum() <= 0:
        raise SceneError(f"object '{name}': its lightmap UVs have zero area")
    return True


@dataclass
class Layouts:
    """Where every baked object's lightmap goes: its size, and its surfaces' UVs."""
    objects: dict  # object name -> surface indices
    sizes: dict  # object name -> (width, height)
    object_of_surface: np.ndarray  # (S,) index into `objects`, -1 for surfaces not baked
    surface_uv: np.ndarray  # (S, 4, 2) the given UVs, and the automatic ones made here
    laid_out: np.ndarray  # (S,) bool: surfaces given automatic UVs here
    uv_maps: np.ndarray  # (S, 2, 4) their affine maps: uv = M @ [x, y, z, 1]


def plan_layouts(scene: Scene, settings: LightmapSettings, objects=None) -> Layouts:
    """Sizes and UVs of the lightmaps of `objects` (default: all), before any value is known."""
    settings.validate()
    all_objects = scene.object_surfaces
    overrides = {name: size for name, size in settings.resolution_overrides.items() if size}
    unknown = sorted((set(overrides) | set(objects or ())) - set(all_objects))
    if unknown:
        raise SolveError(f"no object '{unknown[0]}' in the scene to bake a lightmap for")
    chosen = set(all_objects if objects is None else objects)
    objects = {name: indices for name, indices in all_objects.items() if name in chosen}
    scene_size = max(scene.diameter, 1e-30)
    pad = settings.gutter + 1  # a chart's grazed texels, then its gutter
    layouts = Layouts(objects=objects, sizes={}, object_of_surface=np.full(len(scene), -1, dtype=np.int64),
                      surface_uv=scene.uv.copy(), laid_out=np.zeros(len(scene), dtype=bool),
                      uv_maps=np.zeros((len(scene), 2, 4)))
    for number, (name, indices) in enumerate(objects.items()):
        layouts.object_of_surface[indices] = number
        override = overrides.get(name)
        if _given_uvs(scene, name, indices):
            side = settings.texel_density * math.sqrt(scene.area[indices].sum() / uv_polygon_area(scene.uv[indices]).sum())
            layouts.sizes[name] = resolve_size((math.ceil(side),) * 2, override, settings.max_size,
                                               settings.power_of_two, name)
            continue
        surfaces = {int(i): scene.surface(i) for i in indices}
        object_charts = charts.make_charts(surfaces, list(surfaces), scene_size)
        natural = charts.natural_size(object_charts, settings.texel_density, pad)
        size = resolve_size(natural, override, settings.max_size, settings.power_of_two, name)
        scale = charts.largest_fitting_scale(object_charts, size, pad, name)
        layout = charts.place_charts(object_charts, size, scale, pad)
        layouts.laid_out[indices] = True
        layouts.uv_maps[indices] = [layout.uv_maps[int(i)] for i in indices]
        layouts.surface_uv[indices] = np.einsum("sij,skj->ski", layouts.uv_maps[indices, :, :3],
                                                scene.corners[indices]) + layouts.uv_maps[indices, None, :, 3]
        layouts.sizes[name] = size
    return layouts


def lightmap_sizes(scene: Scene, settings: LightmapSettings | None = None, objects=None) -> dict:
    """{object: (width, height)} of the lightmaps `bake_lightmaps` would make."""
    return plan_layouts(scene, settings or LightmapSettings(), objects).sizes


def bake_lightmaps(scene: Scene, solution: Solution, settings: LightmapSettings | None = None,
                   gpu: GPU | None = None, objects=None) -> dict[str, Lightmap]:
    """One `Lightmap` per object of `scene` (or of `objects`, names of some of them: objects
    that only occlude need none), keyed by object name (see core/__init__.py)."""
    settings = settings or LightmapSettings()
    layouts = plan_layouts(scene, settings, objects)
    objects, object_of_surface, surface_uv = layouts.objects, layouts.object_of_surface, layouts.surface_uv
    # the direct light's maps resolve no finer than the finest texel (an object's area over its
    # lightmap's texels: an upper bound on its texels' density, so the maps err on the fine side)
    finest_texel = min((math.sqrt(scene.area[indices].sum() / math.prod(layouts.sizes[name]))
                        for name, indices in objects.items()), default=math.inf)
    settings = replace(settings, direct_map_resolution=matched_map_resolution(
        scene.diameter, finest_texel, settings.direct_map_resolution))
    patches = solution.patches
    light = settings.content == "light"
    report = solution.report
    per_texel = settings.direct_per_texel and solution.patch_direct is not None and report is not None
    mapped = np.isin(patches.surface, [i for name in scene.material_maps for i in scene.object_surfaces.get(name, ())])
    # what is interpolated: the light H (less its direct part when texels get that), or B for
    # "combined" where no material map turns H into B texel by texel
    reflected = None
    if per_texel:
        values = element_values(solution, light=True) - element_values(solution, direct=True)
        reflected = emitters_reflection(patches, solution.patch_radiosity)
        if reflected is not None:  # the texels take it from the emitters' pieces too (`add_direct_light`)
            values = values - reflected_light_at_elements(gpu, solution, settings, reflected, values.shape[1])
    elif light or mapped.any():
        values = element_values(solution, light=True)
        if not light:
            values = np.where(mapped[:, None, None, None], values, element_values(solution))
    else:
        values = element_values(solution)
    if len(values) != len(patches):
        raise SolveError("the solution does not belong to this scene (patch counts differ)")
    scene_size = max(scene.diameter, 1e-30)

    # patch corner UVs: the given ones were subdivided with the patches; automatic ones are affine in position
    patch_uv = np.array(patches.uv, dtype=np.float64)
    auto = layouts.laid_out[patches.surface]
    maps = layouts.uv_maps[patches.surface[auto]]
    patch_uv[auto] = np.einsum("pij,pkj->pki", maps[..., :3], patches.corners[auto]) + maps[:, None, :, 3]

    group = np.where(patches.is_back, -1, object_of_surface[patches.surface])  # a lightmap holds the front
    baked = np.flatnonzero(group >= 0)
    lattice = np.zeros((len(patches),) + (values.shape[1] + 2,) * 2 + (3,))
    lattice[baked] = continuous_lattice(patches.corners[baked], patch_uv[baked], values[baked], group[baked],
                                        patches.normal[baked], world_quantum=1e-6 * scene_size, uv_quantum=1e-6)
    rasters = {}
    axes = np.zeros((len(patches), 3, 2))  # each patch's world step per texel, in its object's lightmap
    with open_gpu(gpu) as lightmap_gpu:
        for name, indices in objects.items():
            size = layouts.sizes[name]
            mine = np.flatnonzero(np.isin(patches.surface, indices) & ~patches.is_back)
            corners_texels = patch_uv[mine] * np.asarray(size, dtype=np.float64)
            texel_values, signed_ids = rasterize(lightmap_gpu, corners_texels, lattice[mine], size)
            if not (signed_ids != 0).any():
                raise SolveError(f"object '{name}': its faces cover no texel of a {size[0]}x{size[1]}"
                                 " lightmap; raise the texel density or its resolution")
            points = texel_points(lightmap_gpu, patches, mine, corners_texels, size)
            axes[mine] = texel_axes(patches, mine, corners_texels)
            rasters[name] = (texel_values.astype(np.float64), signed_ids, mine, points)
        if per_texel:
            add_direct_light(lightmap_gpu, solution, rasters, settings, axes, reflected)
        clear_contacts(scene, patches, rasters, holds_b=~mapped if not (per_texel or light) else None)
    lightmaps = {}
    for name, (texel_values, signed_ids, mine, points) in rasters.items():
        size, indices = layouts.sizes[name], objects[name]
        material = scene.material_maps.get(name)
        if not light and material is not None:
            texel_values = combined_texels(texel_values, material, size, name)
        elif not light and per_texel:  # B = E + ρ H with each texel's patch values
            owner = np.maximum(points[1], 0)
            texel_values = patches.emission[owner] + patches.reflectance[owner] * texel_values
        covered = signed_ids != 0
        inside = signed_ids > 0
        patch_index = np.where(inside, mine[np.maximum(signed_ids, 1) - 1], -1).astype(np.int32)
        levels, coverage = mip_levels(texel_values, covered, settings.gutter)
        lightmaps[name] = Lightmap(object_name=name, levels=levels, coverage=coverage, patch_index=patch_index,
                                   surfaces=indices, surface_uv=surface_uv[indices],
                                   texel_density=math.sqrt(inside.sum() / scene.area[indices].sum()),
                                   content=settings.content)
    return lightmaps


def covered_texels(rasters: dict) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The texels every lightmap of `rasters` covers, in one list: their points (N, 3), owner
    patches (N,), and how many belong to each lightmap, in order."""
    covered = [entry[3][2] for entry in rasters.values()]
    points = np.concatenate([entry[3][0][mask] for entry, mask in zip(rasters.values(), covered)])
    owners = np.concatenate([entry[3][1][mask] for entry, mask in zip(rasters.values(), covered)])
    return points, owners, [int(mask.sum()) for mask in covered]


def clear_contacts(scene: Scene, patches, rasters: dict, holds_b: np.ndarray | None) -> None:
    """Texels under a face touching theirs see nothing (`contact`): their light H becomes 0, and
    B = E where a texel holds the interpolated B (`holds_b` per patch; None: nowhere)."""
    points, owners, counts = covered_texels(rasters)
    touched = in_contact(scene, points, patches.surface[owners])
    cleared = np.zeros((len(owners), 3))
    if holds_b is not None:
        cleared = np.where(holds_b[owners][:, None], patches.emission[owners], 0.0)
    start = 0
    for (texel_values, _, _, (_, _, covered)), count in zip(rasters.values(), counts):
        mine = slice(start, start + count)
        start += count
        values = texel_values[covered]
        values[touched[mine]] = cleared[mine][touched[mine]]
        texel_values[covered] = values


def reflected_light_at_elements(gpu: GPU | None, solution: Solution, settings: LightmapSettings,
                                reflected: np.ndarray, elements: int) -> np.ndarray:
    """(P, S, S, 3) the light the elements' centres get from what the emitters reflect
    (`emitters_reflected_light`): the part of the solve's light the texels recompute."""
    patches, report = solution.patches, solution.report
    points = element_frames(patches, elements)[0]
    owners = np.repeat(np.arange(len(patches)), elements * elements)
    with open_gpu(gpu) as own_gpu:
        light = emitters_reflected_light(own_gpu, solution.scene, patches, points, owners, reflected,
                                         report.settings.visibility, settings.direct_map_resolution,
                                         report.effects.occlusion, settings.direct_pieces)
    return light.reshape(len(patches), elements, elements, 3)


def add_direct_light(gpu: GPU, solution: Solution, rasters: dict, settings: LightmapSettings,
                     axes: np.ndarray, reflected: np.ndarray | None = None) -> None:
    """Add every lightmap's direct light texel by texel (one pass over all texels per shot), the
    mean over the texel's square where it is sharp (a second pass over those texels' points;
    `axes` (P, 3, 2): each patch's world step per texel); the emitters send what they reflect of
    `reflected` (P, 3) too, when given."""
    points, owners, counts = covered_texels(rasters)
    report = solution.report
    shoot = lambda at, on: direct_light(  # noqa: E731
        gpu, solution.scene, solution.patches, at, on, report.settings.visibility, settings.direct_map_resolution,
        report.effects.occlusion, settings.direct_pieces, reflected)[0]
    light = shoot(points, owners)
    masks = [entry[3][2] for entry in rasters.values()]
    images, faces, start = [], [], 0
    for mask, count in zip(masks, counts):
        image, face = np.zeros(mask.shape), np.full(mask.shape, -1, dtype=np.int64)
        image[mask] = light[start:start + count].sum(axis=1)
        face[mask] = solution.patches.surface[owners[start:start + count]]
        images.append(image)
        faces.append(face)
        start += count
    sharp = np.flatnonzero(np.concatenate([flags[mask] for flags, mask in zip(sharp_texels(images, faces), masks)]))
    if len(sharp) and settings.direct_subsamples > 1:
        at, texel = footprint_points(solution.scene, solution.patches, points[sharp], owners[sharp],
                                     axes[owners[sharp]], settings.direct_subsamples)
        spread = shoot(at, owners[sharp][texel])
        taken = np.bincount(texel, minlength=len(sharp))
        light[sharp] = np.stack([np.bincount(texel, weights=spread[:, c], minlength=len(sharp))
                                 for c in range(3)], axis=1) / taken[:, None]
    start = 0
    for (texel_values, _, _, (_, _, covered)), count in zip(rasters.values(), counts):
        texel_values[covered] = np.maximum(texel_values[covered] + light[start:start + count], 0.0)
        start += count


def combined_texels(light: np.ndarray, material, size: tuple[int, int], name: str) -> np.ndarray:
    """B = E + ρ H texel by texel, from an object's material map (which has its lightmap's size)."""
    if material.albedo.shape[:2] != (size[1], size[0]):
        raise SolveError(f"object '{name}': its material map is {material.albedo.shape[1]}x{material.albedo.shape[0]}"
                         f" texels, its lightmap {size[0]}x{size[1]}")
    return material.emission + material.albedo * light

