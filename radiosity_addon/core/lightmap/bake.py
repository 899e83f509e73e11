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

from ..errors import SolveError
from ..gpu import GPU, open_gpu
from ..scene import Scene
from ..scene.face_clusters import identity_clusters
from ..scene.geometry import bilinear
from ..settings import LightmapSettings
from ..solution import Solution
from ..timing import StagePlan, pulse
from ..uvspace import rasterize
from . import charts
from .contact import contact_distance, in_contact, touching_clusters
from .direct import (SUN_DISC_DIRECTIONS, direct_light, emitters_reflection, footprint_points, map_resolutions,
                     reflected_light_at_elements, sharp_texels, sky_light, texel_axes, texel_points)
from .lattice import continuous_lattice, element_values, lattice_parameters
from .seams import under_near_emitters
from .mips import filled_image, mip_levels
from .scattered import corner_values, element_samples
from .size import chosen_texel_density, given_uvs, resolve_size, uv_polygon_area



@dataclass
class Lightmap:
    object_name: str
    levels: list[np.ndarray]  # mip chain down to 1 x 1, (h_k, w_k, 4) float32; levels[0] is the image
    coverage: list[np.ndarray]  # per level, (h_k, w_k) float32: fraction of the texel on charts (alpha adds gutters)
    patch_index: np.ndarray  # (H, W) int32: patch whose footprint holds the texel centre (on a clustered face: the
    # patch nearest it), -1 if none
    surfaces: np.ndarray  # (n,) indices of the object's surfaces
    surface_uv: np.ndarray  # (n, 4, 2) corner UVs the map was baked with (triangles repeat c2)
    texel_density: float  # achieved texels per scene unit: sqrt(texels inside faces / face area)
    content: str = "light"  # "light": H (shown as E + ρ H), "combined": B
    face_index: np.ndarray | None = None  # (H, W) int32: the face whose footprint holds the texel centre, -1 if none

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


@dataclass
class Layouts:
    """Where every baked object's lightmap goes: its size, and its surfaces' UVs."""
    objects: dict  # object name -> surface indices
    sizes: dict  # object name -> (width, height)
    object_of_surface: np.ndarray  # (S,) index into `objects`, -1 for surfaces not baked
    surface_uv: np.ndarray  # (S, 4, 2) the given UVs, and the automatic ones made here
    laid_out: np.ndarray  # (S,) bool: surfaces given automatic UVs here
    uv_maps: np.ndarray  # (S, 2, 4) their affine maps: uv = M @ [x, y, z, 1]
    texel_density: float  # the settings' or, where they ask for it automatically, the one chosen


def plan_layouts(scene: Scene, settings: LightmapSettings, objects=None) -> Layouts:
    """Sizes and UVs of the lightmaps of `objects` (default: all), before any value is known."""
    settings.validate()
    settings = replace(settings, texel_density=chosen_texel_density(scene, settings, objects))
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
                      uv_maps=np.zeros((len(scene), 2, 4)), texel_density=settings.texel_density)
    for number, (name, indices) in enumerate(objects.items()):
        layouts.object_of_surface[indices] = number
        override = overrides.get(name)
        if given_uvs(scene, name, indices):
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


@dataclass
class ObjectTexels:
    """One lightmap's texels as laid out: what each covered texel shows and the light it holds.
    Its units are what was rasterized: the patches of its faces the solve kept as they are, then
    its faces the solve took in clusters (`scene.face_clusters`)."""
    values: np.ndarray  # (H, W, 3) float64: the light laid out, then added to
    signed_ids: np.ndarray  # (H, W) int32: unit + 1 where a texel's centre lies in it, -(unit + 1) where it only grazes it
    unit_face: np.ndarray  # (U,) the face of each unit
    unit_patch: np.ndarray  # (U,) the patch a unit is, -1 for a face of a cluster
    positions: np.ndarray  # (H, W, 3) the world point each texel shows
    unit_of_texel: np.ndarray  # (H, W) its unit, -1 where none covers it
    covered: np.ndarray  # (H, W) bool
    axes: np.ndarray  # (U, 3, 2) each unit's world step per texel along x and y
    nearest_patch: np.ndarray | None = None  # (H, W) on clustered faces the patch whose elements weigh most at a corner

    def texel_faces(self) -> np.ndarray:
        """(covered texels,) the face each covered texel shows."""
        return self.unit_face[self.unit_of_texel[self.covered]]

    def texel_patches(self) -> np.ndarray:
        """(covered texels,) the patch each covered texel shows, -1 on clustered faces."""
        return self.unit_patch[self.unit_of_texel[self.covered]]


# per texel, per face, per face and direction of a sun (its maps draw every face), per texel and sky direction
LIGHTMAP_SECONDS = {"texel": 1.5e-6, "face": 1.2e-5, "face_sun_direction": 2.9e-6, "texel_sky_direction": 3.7e-8}


def predicted_seconds(scene: Scene, sizes: dict, settings: LightmapSettings | None = None) -> float:
    """About how long `bake_lightmaps` takes for lightmaps of `sizes` ({object: (w, h)}) with
    `settings`: its cost follows their texels (direct light per texel, and the sky's directions
    where it is recomputed per texel) and the faces laid out and drawn."""
    texels = sum(width * height for width, height in sizes.values())
    directions = settings.sky_directions if settings is not None and np.any(scene.world_color > 0) else 0
    sun_directions = sum(SUN_DISC_DIRECTIONS if lamp.angle > 0 else 1 for lamp in scene.lamps if lamp.type == "sun")
    return (LIGHTMAP_SECONDS["texel"] + LIGHTMAP_SECONDS["texel_sky_direction"] * directions) * texels \
        + (LIGHTMAP_SECONDS["face"] + LIGHTMAP_SECONDS["face_sun_direction"] * sun_directions) * len(scene)


def bake_lightmaps(scene: Scene, solution: Solution, settings: LightmapSettings | None = None,
                   gpu: GPU | None = None, objects=None, progress=None) -> dict[str, Lightmap]:
    """One `Lightmap` per object of `scene` (or of `objects`, names of some of them: objects
    that only occlude need none), keyed by object name (see core/__init__.py); `progress` as a
    solve's (its details' "eta": seconds left)."""
    settings = settings or LightmapSettings()
    layouts = plan_layouts(scene, settings, objects)
    plan = StagePlan(progress, {"lightmaps": predicted_seconds(scene, layouts.sizes, settings)})
    with plan.stage("lightmaps", f"laying out {len(layouts.objects)} lightmap(s)"):
        return _bake(scene, solution, settings, gpu, layouts)


def _bake(scene: Scene, solution: Solution, settings: LightmapSettings, gpu: GPU | None,
          layouts: "Layouts") -> dict[str, Lightmap]:
    objects, object_of_surface, surface_uv = layouts.objects, layouts.object_of_surface, layouts.surface_uv
    clusters = solution.clusters if solution.clusters is not None else identity_clusters(scene)
    faces = clusters.faces if len(clusters.faces) == len(scene) else scene
    # the direct light's maps resolve no finer than the finest texel (an object's area over its
    # lightmap's texels: an upper bound on its texels' density, so the maps err on the fine side)
    finest_texel = min((math.sqrt(scene.area[indices].sum() / math.prod(layouts.sizes[name]))
                        for name, indices in objects.items()), default=math.inf)
    resolution, sun_maps = map_resolutions(scene, finest_texel, settings.direct_map_resolution)
    settings = replace(settings, direct_map_resolution=resolution)
    patches = solution.patches
    solved = clusters.proxies
    light = settings.content == "light"
    report = solution.report
    per_texel = settings.direct_per_texel and solution.patch_direct is not None and report is not None
    mapped_objects = [solved.object_names.index(name) for name in scene.material_maps if name in solved.object_names]
    mapped = np.isin(solved.object_index[patches.surface], mapped_objects)
    # what is interpolated: the light H (less its direct part when texels get that, and its sky
    # part where they get that too), or B for "combined" where no material map turns H into B
    reflected = None
    texel_sky = (settings.sky_directions > 0 and per_texel and solution.element_sky is not None
                 and bool(np.any(solution.scene.world_color > 0)))
    if per_texel:
        values = element_values(solution, light=True) - element_values(solution, direct=True)
        if texel_sky:
            values = values - element_values(solution, sky=True)
        reflected = emitters_reflection(patches, solution.patch_radiosity)
        if reflected is not None:  # the texels take it from the emitters' pieces too (`add_direct_light`)
            values = values - reflected_light_at_elements(gpu, solution, settings, reflected, values.shape[1])
        values = np.maximum(values, 0.0)  # what is left of H is light from elsewhere: never below none
    elif light or mapped.any():
        values = element_values(solution, light=True)
        if not light:
            values = np.where(mapped[:, None, None, None], values, element_values(solution))
    else:
        values = element_values(solution)
    if len(values) != len(patches):
        raise SolveError("the solution does not belong to this scene (patch counts differ)")
    scene_size = max(scene.diameter, 1e-30)

    # the faces the solve kept as they are: their patches are laid out by their lattices
    face_of_patch = clusters.face_of_proxy[patches.surface]
    kept = face_of_patch >= 0
    # patch corner UVs: the given ones were subdivided with the patches; automatic ones are affine in position
    patch_uv = np.array(patches.uv, dtype=np.float64)
    auto = kept & layouts.laid_out[np.maximum(face_of_patch, 0)]
    maps = layouts.uv_maps[face_of_patch[auto]]
    patch_uv[auto] = np.einsum("pij,pkj->pki", maps[..., :3], patches.corners[auto]) + maps[:, None, :, 3]

    group = np.where(patches.is_back | ~kept, -1, object_of_surface[np.maximum(face_of_patch, 0)])  # fronts only
    baked = np.flatnonzero(group >= 0)
    joined = np.where(under_near_emitters(solved, patches), group + len(objects), group)  # seams.py
    lattice = np.zeros((len(patches),) + (values.shape[1] + 2,) * 2 + (3,))
    if len(baked):
        lattice[baked] = continuous_lattice(patches.corners[baked], patch_uv[baked], values[baked], joined[baked],
                                            patches.normal[baked], world_quantum=1e-6 * scene_size, uv_quantum=1e-6)
    clustered = clusters.merged[clusters.proxy_of_face]  # (F,) faces solved in a cluster
    sample_object = solved.object_index[patches.surface]
    texels = {}
    with open_gpu(gpu) as lightmap_gpu:
        for number, (name, indices) in enumerate(objects.items()):
            pulse()
            size = layouts.sizes[name]
            mine = np.flatnonzero(group == number)
            loose = indices[clustered[indices]]
            unit_patch = np.concatenate([mine, np.full(len(loose), -1, dtype=np.int64)])
            unit_face = np.concatenate([face_of_patch[mine], loose])
            unit_corners = np.concatenate([patches.corners[mine], scene.corners[loose]])
            corners_texels = np.concatenate([patch_uv[mine], surface_uv[loose]]) * np.asarray(size, dtype=np.float64)
            unit_lattice = lattice[mine]
            hint = None
            if len(loose):  # clustered faces: the elements' light around their corners, laid in between
                object_index = solved.object_names.index(name)
                rows = np.flatnonzero((sample_object == object_index) & ~patches.is_back)
                at_corners, nearest = corner_values(scene.corners[loose], faces.normal[loose],
                                                    element_samples(patches, values, rows), scene_size)
                params = lattice_parameters(values.shape[1])
                s_grid, t_grid = np.meshgrid(params, params)
                unit_lattice = np.concatenate([unit_lattice, bilinear(at_corners, s_grid, t_grid)])
                hint = np.concatenate([np.full(len(mine), -1), nearest[:, 0]])
            texel_values, signed_ids = rasterize(lightmap_gpu, corners_texels, unit_lattice, size)
            if not (signed_ids != 0).any():
                raise SolveError(f"object '{name}': its faces cover no texel of a {size[0]}x{size[1]}"
                                 " lightmap; raise the texel density or its resolution")
            positions, unit_of_texel, covered = texel_points(lightmap_gpu, unit_corners, corners_texels, size)
            entry = ObjectTexels(values=texel_values.astype(np.float64), signed_ids=signed_ids, unit_face=unit_face,
                                 unit_patch=unit_patch, positions=positions, unit_of_texel=unit_of_texel, covered=covered,
                                 axes=texel_axes(unit_corners, corners_texels))
            if hint is not None:
                entry.nearest_patch = np.where(covered, hint[np.maximum(unit_of_texel, 0)], -1)
            texels[name] = entry
        if per_texel:
            add_direct_light(lightmap_gpu, solution, clusters, faces, texels, settings, reflected, texel_sky,
                             sun_maps)
        clear_contacts(faces, texels, _holds_b(mapped, faces, scene) if not (per_texel or light) else None, clusters,
                       1.0 / layouts.texel_density)
    lightmaps = {}
    for name, entry in texels.items():
        pulse()
        size, indices = layouts.sizes[name], objects[name]
        texel_values = entry.values
        material = scene.material_maps.get(name)
        if not light and material is not None:
            texel_values = combined_texels(texel_values, material, size, name)
        elif not light and per_texel:  # B = E + ρ H with each texel's patch values (a clustered face's own)
            texel_values = texel_values.copy()
            patch, face = entry.texel_patches(), entry.texel_faces()
            on_patch = patch >= 0
            emission = np.where(on_patch[:, None], patches.emission[np.maximum(patch, 0)], faces.emission[face])
            reflectance = np.where(on_patch[:, None], patches.reflectance[np.maximum(patch, 0)], faces.reflectance[face])
            texel_values[entry.covered] = emission + reflectance * texel_values[entry.covered]
        inside = entry.signed_ids > 0
        unit = np.maximum(entry.signed_ids, 1) - 1
        patch_index = np.where(inside, entry.unit_patch[unit], -1)
        if entry.nearest_patch is not None:
            patch_index = np.where(inside & (patch_index < 0), entry.nearest_patch, patch_index)
        levels, coverage = mip_levels(texel_values, entry.signed_ids != 0, settings.gutter)
        lightmaps[name] = Lightmap(object_name=name, levels=levels, coverage=coverage,
                                   patch_index=patch_index.astype(np.int32),
                                   surfaces=indices, surface_uv=surface_uv[indices],
                                   texel_density=math.sqrt(inside.sum() / scene.area[indices].sum()),
                                   content=settings.content,
                                   face_index=np.where(inside, entry.unit_face[unit], -1).astype(np.int32))
    return lightmaps


def _holds_b(mapped: np.ndarray, faces: Scene, scene: Scene):
    """Per patch and per face (clustered faces' texels): do its texels hold the interpolated B?"""
    mapped_faces = np.isin(np.asarray(faces.object_names)[faces.object_index], list(scene.material_maps))
    return ~mapped, ~mapped_faces


def covered_texels(texels: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[int]]:
    """The texels every lightmap of `texels` covers, in one list: their points (N, 3), faces (N,),
    patches (N,; -1 on clustered faces), and how many belong to each lightmap, in order."""
    entries = list(texels.values())
    points = np.concatenate([entry.positions[entry.covered] for entry in entries])
    faces = np.concatenate([entry.texel_faces() for entry in entries])
    patches = np.concatenate([entry.texel_patches() for entry in entries])
    return points, faces, patches, [int(entry.covered.sum()) for entry in entries]


def clear_contacts(faces: Scene, texels: dict, holds_b, clusters=None, texel: float = 0.0) -> None:
    """Texels under a face touching theirs (`contact`; texels `texel` wide) see nothing: their light
    H becomes 0, and B = E where a texel holds the interpolated B (`holds_b`: per patch and per
    face; None: nowhere)."""
    points, face, patch, counts = covered_texels(texels)
    distance = contact_distance(faces, texel)
    touched = in_contact(faces, points, face, None if clusters is None else touching_clusters(clusters, distance),
                         distance)
    cleared = np.zeros((len(face), 3))
    if holds_b is not None:
        by_patch, by_face = holds_b
        on_patch = patch >= 0
        holds = np.where(on_patch, by_patch[np.maximum(patch, 0)], by_face[face])
        cleared = np.where(holds[:, None], faces.emission[face], 0.0)
    start = 0
    for entry, count in zip(texels.values(), counts):
        mine = slice(start, start + count)
        start += count
        values = entry.values[entry.covered]
        values[touched[mine]] = cleared[mine][touched[mine]]
        entry.values[entry.covered] = values


def add_direct_light(gpu: GPU, solution: Solution, clusters, faces: Scene, texels: dict, settings: LightmapSettings,
                     reflected: np.ndarray | None = None, sky: bool = False, sun_maps: tuple = (None, 1)) -> None:
    """Add every lightmap's direct light texel by texel (one pass over all texels per shot), the
    mean over the texel's square where it is sharp (a second pass over those texels' points; each
    unit's world step per texel is its `axes`); the emitters send what they reflect of `reflected`
    (P, 3) too, when given; with `sky`, the sky's light at each texel's centre from the settings'
    `sky_directions` (it is soft); suns' maps are (pixels across, directions over a sun's disc)
    `sun_maps` (None pixels: the settings' `direct_map_resolution`)."""
    points, face, patch, counts = covered_texels(texels)
    patches = solution.patches
    on_patch = patch >= 0
    normals = np.where(on_patch[:, None], patches.normal[np.maximum(patch, 0)], faces.normal[face])
    # a texel is looked up as a point of its solved surface's front (its patch's plane, or its cluster's)
    planes = np.where(on_patch, patches.plane[np.maximum(patch, 0)], clusters.proxy_of_face[face])
    report = solution.report
    shoot = lambda at, normal, plane: direct_light(  # noqa: E731
        gpu, solution.scene, patches, at, normal, plane, report.settings.visibility, settings.direct_map_resolution,
        report.effects.occlusion, settings.direct_pieces, reflected, clusters, *sun_maps)[0]
    light = shoot(points, normals, planes)
    # where light may bend smoothly: a face the solve kept, or a cluster's faces together
    surface = clusters.proxy_of_face[face]
    images, face_images, start = [], [], 0
    for entry, count in zip(texels.values(), counts):
        image, face_image = np.zeros(entry.covered.shape), np.full(entry.covered.shape, -1, dtype=np.int64)
        image[entry.covered] = light[start:start + count].sum(axis=1)
        face_image[entry.covered] = surface[start:start + count]
        images.append(image)
        face_images.append(face_image)
        start += count
    sharp = np.flatnonzero(np.concatenate([flags[entry.covered] for flags, entry
                                           in zip(sharp_texels(images, face_images), texels.values())]))
    if len(sharp) and settings.direct_subsamples > 1:
        axes = np.concatenate([entry.axes[entry.unit_of_texel[entry.covered]] for entry in texels.values()])
        at, texel = footprint_points(faces.corners[face[sharp]], normals[sharp], points[sharp], axes[sharp],
                                     settings.direct_subsamples, clip=on_patch[sharp])
        spread = shoot(at, normals[sharp][texel], planes[sharp][texel])
        taken = np.bincount(texel, minlength=len(sharp))
        light[sharp] = np.stack([np.bincount(texel, weights=spread[:, c], minlength=len(sharp))
                                 for c in range(3)], axis=1) / taken[:, None]
    if sky:
        light += sky_light(gpu, solution.scene, patches, points, normals, planes, settings.sky_directions,
                           report.effects.occlusion, clusters)
    start = 0
    for entry, count in zip(texels.values(), counts):
        entry.values[entry.covered] = np.maximum(entry.values[entry.covered] + light[start:start + count], 0.0)
        start += count


def combined_texels(light: np.ndarray, material, size: tuple[int, int], name: str) -> np.ndarray:
    """B = E + ρ H texel by texel, from an object's material map (which has its lightmap's size)."""
    if material.albedo.shape[:2] != (size[1], size[0]):
        raise SolveError(f"object '{name}': its material map is {material.albedo.shape[1]}x{material.albedo.shape[0]}"
                         f" texels, its lightmap {size[0]}x{size[1]}")
    return material.emission + material.albedo * light

