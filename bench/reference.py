"""Reference answers on the common texel grid: a converged Cycles bake (cached on disk) or the exact one,
as reflected radiance B − E (see metrics.py).

The Cycles reference is the mean of two bakes with different seeds; half their RMS difference is the
reference's own noise, reported as the floor under which no error can be measured.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from radiosity_addon.core import Scene
from . import metrics, scenes


def cycles_bake(scene: Scene, resolution: int, samples: int, seed: int) -> dict:
    from .cycles import bake_scene  # bpy is imported only when Cycles runs

    return bake_scene(scene, resolution, samples, seed=seed)


def cache_key(scene: Scene, resolution: int, samples: int, seeds: tuple[int, ...]) -> str:
    content = json.dumps({"scene": scene.to_dict(), "resolution": resolution, "samples": samples,
                          "seeds": list(seeds)}, sort_keys=True)
    return hashlib.sha256(content.encode()).hexdigest()[:16]


def cycles_reference(scene: Scene, resolution: int, samples: int, cache_dir: Path, log=print) -> dict:
    """{"texels" (mean of two seeds), "half_difference" (their noise), "seconds", "samples"}, cached."""
    seeds = (101, 202)
    path = Path(cache_dir) / f"cycles_bake_{cache_key(scene, resolution, samples, seeds)}.npz"
    if path.exists():
        cached = np.load(path)
        return {key: cached[key] for key in cached.files}
    log(f"baking the Cycles reference ({resolution}² texels/surface, 2 x {samples} samples); cached in {path}")
    bakes = [cycles_bake(scene, resolution, samples, seed) for seed in seeds]
    first, second = (bake["texels"] for bake in bakes)
    mean = (first + second) / 2
    reference = {"texels": mean, "half_difference": (first - second) / 2,
                 "seconds": np.array(sum(b["seconds"] for b in bakes)), "samples": np.array(2 * samples)}
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **reference)
    return reference


def reference_for(scene_name: str, scene: Scene, resolution: int, samples: int, cache_dir: Path, log=print):
    """(texels, noise texels or None, description) of the scene's reference."""
    if scene_name in scenes.ANALYTIC_SCENES:
        exact = metrics.reflected(scene, scenes.exact_texels(scene_name, scene, resolution))
        return exact, None, "exact (float64, analytic)"
    reference = cycles_reference(scene, resolution, samples, cache_dir, log)
    return (metrics.reflected(scene, reference["texels"]), reference["half_difference"],
            f"Cycles, {int(reference['samples'])} samples per texel (two seeds averaged)")
