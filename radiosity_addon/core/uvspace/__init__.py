"""UV space on the GPU: which patch's footprint covers each texel, with interpolated values."""

from .materials import patch_material_values, surfaces_with_material_maps
from .rasterize import footprint_means, rasterize

__all__ = ["footprint_means", "patch_material_values", "rasterize", "surfaces_with_material_maps"]
