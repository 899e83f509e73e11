"""Lightmaps: per-object images in UV space from a solution — charts, lattices, rasterizing,
gutters and mips."""

from .bake import Lightmap, bake_lightmaps, lightmap_sizes
from .bake import predicted_seconds as lightmap_seconds
from .mips import filled_image, gl_mip_count, mip_levels
from .size import chosen_texel_density

__all__ = ["Lightmap", "bake_lightmaps", "chosen_texel_density", "lightmap_seconds", "lightmap_sizes", "filled_image",
           "gl_mip_count", "mip_levels"]
