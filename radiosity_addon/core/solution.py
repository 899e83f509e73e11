"""A solve's result: the patches, their radiosity (and their elements'), and the report."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .report import Report
from .scene import Patches


@dataclass
class Solution:
    patches: Patches
    patch_radiosity: np.ndarray  # (P, 3) float64
    element_radiosity: np.ndarray | None  # (P, S, S, 3): [patch, t row, s column]; None for one value per patch
    report: Report | None = None  # None for preview snapshots and solutions made by hand (tests)
    patch_light: np.ndarray | None = None  # (P, 3) light H arriving, B = E + ρH
    element_light: np.ndarray | None = None  # (P, S, S, 3)
    patch_direct: np.ndarray | None = None  # (P, 3) the part of H straight from lamps and emitters
    element_direct: np.ndarray | None = None  # (P, S, S, 3)
    element_sky: np.ndarray | None = None  # (P, S, S, 3 or 1) the part of H straight from the sky
    scene: object = None  # the scene as solved (material maps applied, small faces clustered), for the lightmaps' direct light
    clusters: object = None  # FaceClusters: the given scene's faces and the surfaces solved (None: the same)

    def npz_arrays(self) -> dict:
        """The `solve --output OUT.npz` arrays (docs/architecture.md, Command line)."""
        arrays = {
            "patch_radiosity": self.patch_radiosity.astype(np.float32),
            "patch_area": self.patches.area.astype(np.float32),
            "patch_center": self.patches.center.astype(np.float32),
            "patch_normal": self.patches.normal.astype(np.float32),
            "patch_surface": self.patches.surface.astype(np.int32),
            "patch_corners": self.patches.corners.astype(np.float32),
        }
        if self.element_radiosity is not None:
            arrays["element_radiosity"] = self.element_radiosity.astype(np.float32)
        return arrays
