"""Direct light texel by texel: every texel of every lightmap gathers the lamps', the sun's and the
emitters' light with its own visibility (`shooting.TexelReceivers`), so shadows and penumbrae are
as sharp as the lightmap can show; the smooth rest of the light comes from the solve's elements.

A texel's point is the world point its centre shows on the patch whose UV footprint holds it (a
texel a footprint only grazes: the footprint's nearest point), so every sample lies on a
surface and takes that surface's plane for the visibility lookup.
"""

from __future__ import annotations

import numpy as np

from ..gpu import GPU
from ..scene import Patches, Scene
from ..scene.geometry import bilinear
from ..settings import VISIBILITY_VARIANTS
from ..shooting import direct_shooters, light_at_points
from ..uvspace import rasterize


def texel_points(gpu: GPU, patches: Patches, rows: np.ndarray, corners_texels: np.ndarray, size) -> tuple:
    """(positions (H, W, 3), owner patch (H, W), covered (H, W)) of one lightmap whose patches are
    `rows` with UV corners in texels `corners_texels`."""
    params = np.array([0.0, 0.5, 1.0])
    s, t = np.meshgrid(params, params)
    lattice = bilinear(patches.corners[rows], s, t)  # (n, 3, 3, 3): the bilinear map is exact on it
    positions, signed_ids = rasterize(gpu, corners_texels, lattice, size)
    covered = signed_ids != 0
    owner = np.where(covered, rows[np.abs(signed_ids) - 1], -1)
    return positions.astype(np.float64), owner, covered


def direct_light(gpu: GPU, scene: Scene, patches: Patches, points: np.ndarray, owners: np.ndarray,
                 visibility: str, resolution: int, occlusion: bool, pieces: int) -> tuple[np.ndarray, int]:
    """(N, 3) direct light H at `points` (N, 3) lying on the patches `owners` (N,), and the
    number of shots (emitters and area lamps in up to `pieces` x `pieces` each)."""
    shooters = direct_shooters(scene, patches, pieces)
    variant = visibility if visibility in VISIBILITY_VARIANTS else "hemicube"
    with gpu.resources() as res:
        light = light_at_points(res, scene, patches, points, owners, shooters, variant, resolution, occlusion)
    return light, len(shooters)
