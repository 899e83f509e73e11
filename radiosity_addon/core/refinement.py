"""Adaptive substructuring (Cohen et al. 1986): where the light changes fast across a patch — a
shadow edge, a contact, an emitter a few millimetres from a ceiling — the patch is a poor shooter
(it sends its mean radiosity from everywhere on it) and a poor receiver, so it is split 2 x 2;
smooth regions stay coarse.

The estimate is measured, not guessed: the direct light (lamps and emitters, the few shots that
light a scene first) is shot into S x S elements per patch, and a patch whose elements' light
spreads more than `refine_threshold` of its mean (plus a floor of REFINE_FLOOR of the scene's
mean, so dim corners are not split for noise) is split; that is repeated `refinements` times,
then the method solves once on the refined patches. Steep direct light is where the indirect
light is steep too (the cavity between an emitter and a ceiling, contact shadows), and the
direct shots cost little next to the solve.
"""

from __future__ import annotations

import numpy as np

from .progressive import solve_progressive
from .scene import Patches, split_patches
from .timing import StageTimer
from .uvspace import patch_material_values

REFINE_FLOOR = 0.05
PROBE_ELEMENTS = 4  # elements per patch side the direct light is measured on


def patches_to_refine(patches: Patches, element_light: np.ndarray, threshold: float, min_size: float) -> np.ndarray:
    """(P,) bool: patches whose elements' light spreads more than `threshold` of their mean (plus
    the floor) and that are still larger than `min_size` across."""
    light = np.asarray(element_light, dtype=np.float64).sum(axis=-1)  # (P, S, S)
    mean = light.mean(axis=(1, 2))
    area = patches.area
    floor = REFINE_FLOOR * float((area * mean).sum() / area.sum())
    spread = light.max(axis=(1, 2)) - light.min(axis=(1, 2))
    return (spread > threshold * (mean + floor)) & (np.sqrt(area) > min_size)


def refine(gpu, scene, patches: Patches, backs, settings, effects, timer) -> tuple[Patches, list[int]]:
    """`patches` split where the direct light changes fast, and how many were split per round."""
    from dataclasses import replace

    probe = replace(settings, elements=max(settings.elements, PROBE_ELEMENTS))
    refined = []
    for level in range(settings.refinements):
        with timer.stage("refine"):
            _, _, light, _, _ = solve_progressive(gpu, scene, patches, probe, effects, StageTimer(), direct_only=True)
            min_size = (settings.patch_size if settings.subdiv is None else scene.diameter / 16) / 2 ** (level + 3)
            split = patches_to_refine(patches, light, settings.refine_threshold, min_size)
            if not split.any():
                break
            refined.append(int(split.sum()))
            patches = split_patches(patches, split, backs)
            if scene.material_maps:
                patches.reflectance, patches.emission = patch_material_values(gpu, scene, patches)
    return patches, refined
