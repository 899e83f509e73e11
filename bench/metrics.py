"""Error metrics (docs/architecture.md, Oracles): area-weighted relative RMS, and the worst object's mean.

They are taken on the reflected radiance B − E over the surfaces that do not emit (there
B − E = B): an emitter's own emission is reproduced exactly by every method and would swamp
the error of the light the scene reflects (the Cornell box's lamp is 17 against ~0.1 on the
walls), and Cycles' baked emission wobbles near edges. A scene where every surface emits (the
furnace) is compared on all of them, on B − E.
"""

from __future__ import annotations

import numpy as np

from radiosity_addon.core import Scene


def compared_surfaces(scene: Scene, weights: np.ndarray) -> np.ndarray:
    """`weights` (surfaces, ...) with emitting surfaces zeroed, unless every surface emits."""
    emits = np.any(scene.emission > 0, axis=1)
    if emits.all():
        return weights
    return np.where(emits.reshape((-1,) + (1,) * (weights.ndim - 1)), 0.0, weights)


def reflected(scene: Scene, texels: np.ndarray) -> np.ndarray:
    """Texels (surfaces, R, R, 3) less each surface's own emission."""
    return texels - scene.emission[:, None, None, :]


def relative_rms(values: np.ndarray, reference: np.ndarray, weights: np.ndarray) -> float:
    """sqrt(Σ w |B − B_ref|² / Σ w |B_ref|²) over texels (RGB summed); weights broadcast over RGB."""
    w = weights[..., None]
    return float(np.sqrt((w * (values - reference) ** 2).sum() / (w * reference**2).sum()))


def footprint_rms(values: np.ndarray, reference: np.ndarray, weights: np.ndarray, owners: np.ndarray) -> float:
    """Relative RMS of footprint means: both answers averaged over the covered texels of each
    patch (`owners`: patch index per texel). Leaves out the piecewise-constant display error, so
    it measures the solve (form factors, solver, visibility) alone."""
    covered = weights > 0
    flat_owners, flat_weights = owners[covered], weights[covered]
    count = flat_owners.max() + 1
    area = np.bincount(flat_owners, flat_weights, minlength=count)
    used = area > 0
    means = [np.stack([np.bincount(flat_owners, flat_weights * texels[covered][:, c], minlength=count)[used]
                       / area[used] for c in range(3)], axis=1) for texels in (values, reference)]
    return relative_rms(means[0], means[1], area[used])


def object_means(scene: Scene, values: np.ndarray, weights: np.ndarray) -> dict[str, np.ndarray]:
    """Area-weighted mean RGB per object over the weighted texels (objects with any weight)."""
    means = {}
    for name, members in scene.object_surfaces.items():
        w = weights[members][..., None]
        if w.sum() > 0:
            means[name] = (w * values[members]).sum(axis=tuple(range(w.ndim - 1))) / w.sum()
    return means


def worst_object_error(scene: Scene, values: np.ndarray, reference: np.ndarray, weights: np.ndarray):
    """(object, relative error) of the object whose mean radiance (RGB summed) is off the most."""
    ours = object_means(scene, values, weights)
    theirs = object_means(scene, reference, weights)
    errors = {name: abs(ours[name].sum() - theirs[name].sum()) / theirs[name].sum()
              for name in theirs if theirs[name].sum() > 0}
    worst = max(errors, key=errors.get)
    return worst, float(errors[worst])


def pareto_front(rows: list[dict]) -> list[dict]:
    """Rows no other row beats on both time and error, fastest first."""
    front, best_error = [], np.inf
    for row in sorted(rows, key=lambda r: (r["seconds"], r["error"])):
        if row["error"] < best_error:
            front.append(row)
            best_error = row["error"]
    return front
