"""Material maps into surface and patch values: the mean albedo and emission of the texels each
footprint covers (an object's map has its lightmap's size and UVs). Patches are small, so their
means carry a texture's light transport; the texels keep its detail for the lightmap."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..gpu import GPU
from ..scene import MAX_REFLECTANCE, Patches, Scene
from ..scene.opacity import coverage
from .rasterize import footprint_means

MIN_COVER = 0.05  # an alpha-cut footprint clearer than this keeps its albedo as baked (nearly nothing of it reflects)


def _means(gpu: GPU, scene: Scene, owners: np.ndarray, corners_uv: np.ndarray, fallback: tuple, cover=None):
    """(reflectance, emission) per footprint: map means where a map covers it, else `fallback`. A
    map's albedo on an alpha-cut surface is alpha times its colour (as Cycles bakes it): divided by
    the footprint's opaque share `cover` (per footprint; None: all opaque), it is the albedo where the
    surface is, which its patches reflect with (shooting and visibility let the clear share through)."""
    reflectance, emission = (np.array(values, dtype=np.float64) for values in fallback)
    for name, material in scene.material_maps.items():
        surfaces = scene.object_surfaces.get(name)
        if surfaces is None:
            continue
        mine = np.flatnonzero(np.isin(owners, surfaces))
        image = np.concatenate([material.albedo, material.emission], axis=2)
        means, texels = footprint_means(gpu, corners_uv[mine], image)
        covered = texels > 0
        albedo = means[covered, :3]
        if cover is not None:
            albedo = albedo / np.maximum(cover[mine[covered]], MIN_COVER)[:, None]
        reflectance[mine[covered]] = np.clip(albedo, 0.0, MAX_REFLECTANCE)
        emission[mine[covered]] = np.maximum(means[covered, 3:], 0.0)
    return reflectance, emission


def surfaces_with_material_maps(gpu: GPU, scene: Scene, maps: dict) -> Scene:
    """`scene` with `maps` (object -> MaterialMap) attached and each mapped surface's reflectance
    and emission replaced by its footprint's means (a surface smaller than a texel keeps its own)."""
    mapped = dataclasses.replace(scene, material_maps=dict(maps))
    cover = None if scene.opacity is None else coverage(scene.opacity)
    reflectance, emission = _means(gpu, mapped, np.arange(len(scene)), scene.uv,
                                   (scene.reflectance, scene.emission), cover)
    return dataclasses.replace(mapped, reflectance=reflectance, emission=emission)


def patch_material_values(gpu: GPU, scene: Scene, patches: Patches) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) reflectance and emission of every patch from the scene's material maps (a back patch
    takes its front's); patches a map does not cover keep their surface's values."""
    fronts = patches.front_count
    reflectance, emission = _means(gpu, scene, patches.surface[:fronts], patches.uv[:fronts],
                                   (patches.reflectance[:fronts], patches.emission[:fronts]), patches.coverage[:fronts])
    drawn = patches.drawn  # fronts come first; each back copies its front
    return reflectance[drawn], emission[drawn]
