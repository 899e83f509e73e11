"""Faces an item buffer draws in place of patches: a cluster's own faces for the rectangle the
solve took them as (`scene.face_clusters`), so what a texel's light sees has the faces' shape."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene import OpacityMaps


@dataclass
class DrawnFaces:
    """Polygons an item buffer draws for some front patches instead of their own quads: the faces a
    cluster's rectangle stands for (`scene.face_clusters`), so what is seen has the faces' own shape
    and the rectangle's id."""
    corners: np.ndarray  # (n, 4, 3) counter-clockwise from the front, triangles repeating their last corner
    patch: np.ndarray  # (n,) the front patch each is drawn for
    opacity: OpacityMaps | None = None  # their opacity textures (None: all opaque)

    @property
    def is_triangle(self) -> np.ndarray:
        return np.all(self.corners[:, 3] == self.corners[:, 2], axis=1)
