"""What a point sees, on the GPU: hemispherical visibility maps and hemi-cube item buffers."""

from .hemicube import HemicubeAtlas, HemicubeRenderer, delta_form_factors, fixed_point_weights, patch_frames
from .hemisphere import VARIANTS, Variant, VisibilityMap

__all__ = ["HemicubeAtlas", "HemicubeRenderer", "VARIANTS", "Variant", "VisibilityMap", "delta_form_factors",
           "fixed_point_weights", "patch_frames"]
