"""Shooters (patches, lamps, the sun, the sky), the receiving element textures, the pass that adds
a shot's light to them, and the same pass over lightmap texels for the direct light: shared by
both methods and the lightmaps."""

from .direct import (SOLVE_EMITTER_PIECES, DirectLightWork, MeasuredDirectLight, direct_light_at_elements,
                     direct_shooters, emitter_pieces, emitter_shooters, lamps_as_shooters, light_at_points, light_at_receivers,
                     patch_scale_shots, same_shots, shoot_lamps, shoot_sky)
from .elements import ElementLayout, ElementTextures, element_areas, element_centers, element_parameters, patch_means
from .lamps import lamp_shooters
from .shooters import PatchShooters, Shooter
from .shooting_pass import PatchBuffers, ShootingPass
from .shots import MAX_SHOTS, ShotVisibility, shot_records, surface_visibility
from .texel_pass import TexelReceivers

__all__ = ["MAX_SHOTS", "SOLVE_EMITTER_PIECES", "ShotVisibility", "shot_records", "surface_visibility", "DirectLightWork", "MeasuredDirectLight", "ElementLayout", "ElementTextures", "PatchBuffers", "PatchShooters", "Shooter",
           "ShootingPass", "TexelReceivers", "direct_light_at_elements", "direct_shooters", "emitter_pieces", "emitter_shooters", "element_areas",
           "element_centers", "element_parameters", "lamp_shooters", "lamps_as_shooters", "light_at_points", "light_at_receivers", "patch_means", "patch_scale_shots", "same_shots", "shoot_lamps",
           "shoot_sky"]
