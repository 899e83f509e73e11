"""Shooters (patches, lamps, the sun, the sky), the receiving element textures and the pass
that adds a shot's light to them: shared by both methods."""

from .direct import DirectLightWork, direct_light_on_patches, has_direct_light, shoot_direct_light
from .elements import ElementLayout, ElementTextures, element_areas, element_centers, element_parameters
from .lamps import lamp_shooters
from .shooters import PatchShooters, Shooter
from .shooting_pass import PatchBuffers, ShootingPass

__all__ = ["DirectLightWork", "ElementLayout", "ElementTextures", "PatchBuffers", "PatchShooters", "Shooter",
           "ShootingPass", "direct_light_on_patches", "element_areas", "element_centers", "element_parameters",
           "has_direct_light", "lamp_shooters", "shoot_direct_light"]
