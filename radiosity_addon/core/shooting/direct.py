"""Light from lamps and the world, shot once into element textures: the piece both methods share.

Progressive refinement does this before its first patch shot (what receivers reflect of it
becomes unshot radiosity); the hemi-cube method does it into one-element patches and adds the
result to its emission term, B = E + ρ·H_lamps + ρ F B.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpu import Resources
from ..scene import Patches, Scene
from ..visibility import VARIANTS, VisibilityMap
from .elements import ElementTextures
from .lamps import lamp_shooters
from .shooting_pass import PatchBuffers, ShootingPass
from .sky import SKY_HEMICUBE_RESOLUTION, element_frames, sky_fractions


@dataclass
class DirectLightWork:
    """What shooting the lamps and the sky cost (the report's effects)."""
    lamps: int = 0
    lamp_visibility_maps: int = 0
    sky_hemicubes: int = 0


def has_direct_light(scene: Scene) -> bool:
    return bool(scene.lamps) or bool(np.any(scene.world_color > 0))


def shoot_direct_light(res: Resources, scene: Scene, patches: Patches, elements: int, shooting: ShootingPass,
                       visibility_map: VisibilityMap, occlusion: bool) -> DirectLightWork:
    """Shoot every lamp (and the sky) once."""
    low, high = scene.bounds
    centre, diameter = (low + high) / 2, scene.diameter
    work = DirectLightWork(lamps=len(scene.lamps))
    for lamp in scene.lamps:
        for shooter in lamp_shooters(lamp, centre, diameter):
            if occlusion:
                visibility_map.render(shooter.position, shooter.axes, -1, shooter.ortho_extent)
                work.lamp_visibility_maps += 1
            shooting.shoot(shooter, visibility_map)
    sky = scene.world_color
    if np.any(sky > 0):
        fractions = sky_fractions(res, patches, element_frames(patches, elements), SKY_HEMICUBE_RESOLUTION, diameter)
        work.sky_hemicubes = len(fractions)
        shooting.shoot_sky(sky, fractions, visibility_map)
    return work


def direct_light_on_patches(res: Resources, scene: Scene, patches: Patches, visibility: str, visibility_res: int,
                            occlusion: bool) -> tuple[np.ndarray, DirectLightWork]:
    """(P, 3) light H each patch gets from the lamps and the sky at its centre (it reflects ρ · H),
    for the hemi-cube method's emission term: the shooting pass with one element per patch."""
    with res.gpu.resources() as scoped:
        textures = ElementTextures(scoped, patches, 1)
        buffers = PatchBuffers(scoped, patches, textures)
        visibility_map = VisibilityMap(scoped, patches, visibility_res, visibility, scene.diameter)
        shooting = ShootingPass(scoped, textures, buffers, "exact", VARIANTS[visibility].search_radius,
                                occluder_margin=VARIANTS[visibility].occluder_margin, occlusion=occlusion)
        work = shoot_direct_light(scoped, scene, patches, 1, shooting, visibility_map, occlusion)
        light = textures.read_light()[:, 0, 0]
    return light, work
