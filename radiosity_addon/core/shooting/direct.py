"""Light from lamps and the world, shot once into element textures: the piece both methods share.

Progressive refinement does this before its first patch shot (what receivers reflect of it
becomes unshot radiosity); the hemi-cube method does it into one-element patches and adds the
result to its emission term, B = E + ρ·H_lamps + ρ F B.

The direct light — lamps, the sun and the emissive patches, not the sky — is also what the
lightmaps recompute texel by texel (`direct_shooters`, `texel_pass`): the solve records how much
of its element light it is, so only the smooth rest is interpolated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpu import Resources
from ..scene import Patches, Scene
from .elements import ElementTextures
from .lamps import lamp_shooters, polygon_shooters
from .shooters import Shooter
from .shooting_pass import PatchBuffers, ShootingPass
from .shots import ShotVisibility
from .sky import SKY_HEMICUBE_RESOLUTION, element_frames, sky_fractions


@dataclass
class DirectLightWork:
    """What shooting the lamps and the sky cost (the report's effects)."""
    lamps: int = 0
    lamp_visibility_maps: int = 0
    sky_hemicubes: int = 0


MAX_SPLIT_EMITTERS = 64  # emissive patches split into pieces for the texel pass; beyond, one shot each


def has_direct_light(scene: Scene) -> bool:
    return bool(scene.lamps) or bool(np.any(scene.world_color > 0))


def lamps_as_shooters(scene: Scene) -> list[Shooter]:
    low, high = scene.bounds
    return [shooter for lamp in scene.lamps for shooter in lamp_shooters(lamp, (low + high) / 2, scene.diameter)]


def direct_shooters(scene: Scene, patches: Patches) -> list[Shooter]:
    """Every shot of the direct light: the lamps', and the emissive patches' in pieces (one each
    when there are more than MAX_SPLIT_EMITTERS of them)."""
    emitting = np.flatnonzero(np.any(patches.emission > 0, axis=1))
    size = scene.diameter if len(emitting) <= MAX_SPLIT_EMITTERS else np.inf
    pieces = [shooter for p in emitting
              for shooter in polygon_shooters(patches.corners[p], patches.emission[p], size, patch=int(p))]
    return lamps_as_shooters(scene) + pieces


def shoot_lamps(scene: Scene, shooting: ShootingPass) -> DirectLightWork:
    """Shoot every lamp once."""
    before = shooting.visibility_source.maps_rendered
    shooting.shoot_all(lamps_as_shooters(scene))
    return DirectLightWork(lamps=len(scene.lamps), lamp_visibility_maps=shooting.visibility_source.maps_rendered - before)


def shoot_sky(res: Resources, scene: Scene, patches: Patches, elements: int, shooting: ShootingPass,
              work: DirectLightWork) -> None:
    """Every element gathers the world colour times its sky fraction."""
    sky = scene.world_color
    if np.any(sky > 0):
        fractions = sky_fractions(res, patches, element_frames(patches, elements), SKY_HEMICUBE_RESOLUTION,
                                  scene.diameter)
        work.sky_hemicubes = len(fractions)
        shooting.shoot_sky(sky, fractions)


def direct_light_on_patches(res: Resources, scene: Scene, patches: Patches, visibility: str, visibility_res: int,
                            occlusion: bool, elements: int = 1) -> tuple[np.ndarray, np.ndarray, DirectLightWork]:
    """(P, S, S, 3) light H each element gets from the lamps, and (P, S, S, 3) from the sky (it
    reflects ρ · H), for the hemi-cube method's emission term: the shooting pass on S x S elements."""
    with res.gpu.resources() as scoped:
        textures = ElementTextures(scoped, patches, elements)
        buffers = PatchBuffers(scoped, patches, textures)
        shots = ShotVisibility(scoped, patches, visibility_res, visibility, scene.diameter, occlusion)
        shooting = ShootingPass(scoped, textures, buffers, "exact", shots)
        work = shoot_lamps(scene, shooting)
        lamps = textures.read_light()
        shoot_sky(scoped, scene, patches, elements, shooting, work)
        sky = textures.read_light() - lamps
    return lamps, sky, work
