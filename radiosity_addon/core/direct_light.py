"""Light from lamps and the world, shot once into element textures.

Progressive refinement does this before its first patch shot (what receivers reflect of
it becomes unshot radiosity); the original method does it into one-element patches and
adds the result to its emission term, B = E + ρ·H_lamps + ρ F B.
"""

from __future__ import annotations

import numpy as np

from .element_textures import element_centers
from .hemicube import frames, sky_fractions
from .lights import lamp_shooters, scene_lamps, world_color
from .patches import Patches
from .scene import Scene

SKY_HEMICUBE_RESOLUTION = 64


def has_direct_light(scene: Scene) -> bool:
    return bool(scene_lamps(scene)) or bool(np.any(world_color(scene) > 0))


def element_frames(patches: Patches, elements: int):
    """Hemi-cube frames at every element centre, flattened in element order [p, j, i]."""
    per_patch = elements * elements
    centres = element_centers(patches, elements).reshape(-1, 3)
    normals = np.repeat(patches.normal, per_patch, axis=0)
    edges = np.repeat(patches.corners[:, 1] - patches.corners[:, 0], per_patch, axis=0)
    return frames(centres, normals, edges)


def shoot_direct_light(ctx, scene: Scene, patches: Patches, elements: int, gatherer, visibility_map,
                       occlusion: bool) -> dict:
    """Shoot every lamp (and the sky) once; returns the work done for the report."""
    low, high = scene.bounds
    centre, diameter = (low + high) / 2, scene.diameter
    lamps = scene_lamps(scene)
    maps = 0
    for lamp in lamps:
        for shooter in lamp_shooters(lamp, centre, diameter):
            if occlusion:
                visibility_map.render(shooter.position, shooter.axes, -1, shooter.ortho_extent)
                maps += 1
            gatherer.shoot(shooter, visibility_map)
    sky = world_color(scene)
    sky_hemicubes = 0
    if np.any(sky > 0):
        fractions = sky_fractions(ctx, patches, element_frames(patches, elements), SKY_HEMICUBE_RESOLUTION,
                                  diameter)
        sky_hemicubes = len(fractions)
        gatherer.shoot_sky(sky, fractions, visibility_map)
    return {"lamps": len(lamps), "lamp_visibility_maps": maps, "sky_hemicubes": sky_hemicubes}


def direct_light_on_patches(ctx, scene: Scene, patches: Patches, visibility: str, visibility_res: int,
                            occlusion: bool) -> tuple[np.ndarray, dict]:
    """(P, 3) radiance each patch reflects of the lamps and the sky at its centre (ρ · H), for the
    original method's emission term; the progressive machinery with one element per patch."""
    from .element_textures import ElementTextures
    from .shooting import Gatherer, PatchBuffers
    from .visibility import VARIANTS, VisibilityMap

    textures = ElementTextures(ctx, patches, 1)
    buffers = PatchBuffers(ctx, patches, textures)
    visibility_map = VisibilityMap(ctx, patches, visibility_res, visibility, scene.diameter)
    gatherer = Gatherer(ctx, textures, buffers, "exact", VARIANTS[visibility].search_radius,
                        occluder_margin=VARIANTS[visibility].occluder_margin, occlusion=occlusion)
    try:
        work = shoot_direct_light(ctx, scene, patches, 1, gatherer, visibility_map, occlusion)
        reflected = textures.read_radiosity()[:, 0, 0] - patches.emission
    finally:
        for obj in (gatherer, visibility_map, buffers, textures):
            obj.release()
    return np.maximum(reflected, 0.0), work
