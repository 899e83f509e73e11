"""What a solve simulates: the `effects` entry of the report (DESIGN.md, Interfaces)."""

from __future__ import annotations

import numpy as np

from .patches import Patches
from .scene import Scene
from .solution import SolveSettings


def emitter_count(scene: Scene) -> int:
    return int(sum(bool(np.any(s.emission > 0)) for s in scene.surfaces))


def simulated(scene: Scene, patches: Patches, settings: SolveSettings) -> dict:
    """The effects this solve simulated (every solve currently runs the full simulation)."""
    return {
        "channels": 3,
        "occlusion": True,
        "interreflection": True,
        "emitters": emitter_count(scene),
        "reflective_surfaces": int(sum(bool(np.any(s.reflectance > 0)) for s in scene.surfaces)),
    }
