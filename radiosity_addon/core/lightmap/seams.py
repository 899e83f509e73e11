"""Where the interpolated light must not be joined across patches: the footprint of an emitter hung
close in front of a surface (a ceiling panel 1 mm under the ceiling). Under it the surface sees
the emitter's back and little else; beside it, the room. The light changes at the emitter's
outline as sharply as the texels can show, so the lattice keeps the footprint's patches apart
from their neighbours (`continuous_lattice`'s groups): joined, the footprint's values leaked into
the larger patches around it, a dark (or bright) ring about twice the emitter's size.
"""

from __future__ import annotations

import numpy as np

from ..scene import Patches, Scene
from ..scene.neighbours import near_pairs
from .contact import inside_polygons

NEAR_EMITTER_GAP = 0.1  # of an emitter's size: a surface nearer than this in front of it is under it


def under_near_emitters(scene: Scene, patches: Patches) -> np.ndarray:
    """(P,) bool: patches (of `scene`'s surfaces) whose centre lies in front of an emitting patch
    (its emitting side: a two-sided emitter's back is a patch of its own), facing it, nearer than
    NEAR_EMITTER_GAP of its surface's size (refinement splits an emitter finely), and inside it."""
    under = np.zeros(len(patches), dtype=bool)
    emits = np.any(patches.emission > 0, axis=1)
    emitters = np.flatnonzero(emits)
    if len(emitters) == 0:
        return under
    corners = patches.corners
    centre = corners.mean(axis=1)
    radius = np.linalg.norm(corners - centre[:, None], axis=2).max(axis=1)
    gap = np.zeros(len(patches))
    surface_corners = scene.corners[patches.surface[emitters]]
    gap[emitters] = NEAR_EMITTER_GAP * np.linalg.norm(surface_corners - surface_corners.mean(axis=1)[:, None],
                                                      axis=2).max(axis=1) * 2
    receivers = np.flatnonzero(~emits)
    for query, emitter in near_pairs(centre, radius + gap, receivers, radius[receivers], others=emitters):
        receiver = receivers[query]
        normal = patches.normal[emitter]
        height = np.einsum("nd,nd->n", centre[receiver] - corners[emitter, 0], normal)
        facing = np.einsum("nd,nd->n", patches.normal[receiver], normal) < 0
        near = facing & (height > 0) & (height < gap[emitter]) & (patches.surface[receiver] != patches.surface[emitter])
        inside = inside_polygons(centre[receiver[near]], corners[emitter[near]], normal[near], 0.0)
        under[receiver[near][inside]] = True
    return under
