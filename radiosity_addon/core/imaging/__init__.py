"""Image operations shared by element tiles and lightmaps (numpy, whole images at once)."""

from .padding import dilate, downsample_weighted, pad_tiles

__all__ = ["dilate", "downsample_weighted", "pad_tiles"]
