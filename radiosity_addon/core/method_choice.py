"""`--method auto`: the method predicted faster for these patches, from a cost model whose
constants `python -m bench.calibrate` measures (a faster GPU scales both methods'
costs alike to first order, so the choice holds).

Progressive refinement: shots ~ SHOTS_PER_PATCH(tolerance) x shooters, each drawing a hemi-cube
(pixels, and every triangle on each of 5 faces) and gathered by every element. The shooters are
the patches, or at most `shooter_clusters` when the patches are more (clusters shoot as one, and
as the unshot light weakens whole coarse clusters shoot: CLUSTERED_SHOTS of the shots per patch
each).
Hemi-cube method: a hemi-cube per receiving element (S_h^2 per patch) over the triangles its
atlas draws (a surface of many patches is drawn once and looked up: visibility/item_geometry.py;
each face draws only the clusters of them its frustum reaches: visibility/face_culling.py), then
Jacobi sweeps over the P x P matrix (~log(tolerance) / log(mean reflectance) sweeps); its
matrices must fit the memory limit, else it is not a choice at all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .hemicube.form_factors import matrix_bytes
from .scene import Patches
from .settings import SolveSettings
from .shooting.shots import hemicube_resolution
from .visibility.item_geometry import item_geometry

# python -m bench.calibrate's costs of a hemi-cube drawn, reduced and read back (per
# pixel, per drawn triangle and face). SHOT_SECONDS predate face culling, which a progressive shot's
# hemi-cube has too: progressive may be predicted slower than it is
HEMICUBE_SECONDS = {"pixel": 1.27e-07, "triangle": 4.6e-08}
SHOT_SECONDS = {"pixel": 5.18e-09, "triangle": 1.21e-07, "element": 3.4e-07}  # a progressive shot
SECONDS_PER_MATRIX_ENTRY_SWEEP = 3.93e-09
SHOTS_PER_PATCH = {0.01: 2.62, 0.003: 3.56, 0.001: 4.40}  # progressive, Cornell box, by tolerance
# clustered shots per shots_per_patch x shooter_clusters (progressive/clusters.py): about alike at
# every size of the bench's rooms
CLUSTERED_SHOTS = 0.5
ELEMENT_BYTES = 2 * 16 + 8  # light and residual texels (RGBA32F) and their share of the patch buffers


@dataclass
class Prediction:
    seconds: float
    bytes: int
    feasible: bool = True
    why_not: str = ""


@dataclass
class MethodChoice:
    method: str
    reason: str
    predicted: dict  # method -> {"seconds", "bytes", "feasible"}

    def as_dict(self) -> dict:
        return {"method": self.method, "reason": self.reason, "predicted": self.predicted}


def shots_per_patch(tolerance: float) -> float:
    """Interpolated in log(tolerance) through the measured points (extrapolated linearly)."""
    points = sorted(SHOTS_PER_PATCH.items())
    x = np.log([t for t, _ in points])
    y = np.array([s for _, s in points])
    slope = (y[-1] - y[0]) / (x[-1] - x[0])
    value = np.interp(math.log(tolerance), x, y, left=np.nan, right=np.nan)
    if np.isnan(value):
        value = y[0] + slope * (math.log(tolerance) - x[0])
    return float(max(value, 1.0))


def hemicube_seconds(costs: dict, resolution: int, triangles: int) -> float:
    """A hemi-cube of top face `resolution` over `triangles`: 3 R^2 pixels, every triangle on 5 faces."""
    return costs["pixel"] * 3 * resolution ** 2 + costs["triangle"] * 5 * triangles


def predict_progressive(patches: Patches, settings: SolveSettings, shooters: int | None = None) -> Prediction:
    count = len(patches)
    triangles = int(np.where(patches.is_triangle, 1, 2).sum())
    elements = count * settings.elements ** 2
    shots = shots_per_patch(settings.effective_tolerance if settings.method != "auto"
                            else replace(settings, method="progressive").effective_tolerance)
    if shooters is None:
        clustered = 0 < settings.shooter_clusters < count
        shooters = settings.shooter_clusters * CLUSTERED_SHOTS if clustered else count
    shots *= shooters
    seconds = shots * (hemicube_seconds(SHOT_SECONDS, hemicube_resolution(settings.visibility_res), triangles)
                       + SHOT_SECONDS["element"] * elements)
    return Prediction(seconds=seconds, bytes=elements * ELEMENT_BYTES)


def drawn_triangles(patches: Patches, resolution: int) -> int:
    """The triangles a hemi-cube atlas of top face `resolution` draws of these patches."""
    return len(item_geometry(patches, face_pixels=resolution * resolution * 3 // 5).indices) // 3


def predict_hemicube(patches: Patches, settings: SolveSettings, mean_reflectance: float) -> Prediction:
    count = len(patches)
    triangles = drawn_triangles(patches, settings.hemicube_res)
    need = matrix_bytes(count, settings.hemicube_elements)
    tolerance = replace(settings, method="hemicube").effective_tolerance
    sweeps = math.log(tolerance) / math.log(min(max(mean_reflectance, 0.05), 0.99))
    seconds = (count * settings.hemicube_elements ** 2 * hemicube_seconds(HEMICUBE_SECONDS, settings.hemicube_res,
                                                                          triangles)
               + SECONDS_PER_MATRIX_ENTRY_SWEEP * count ** 2 * sweeps)
    if need > settings.memory_limit_bytes:
        return Prediction(seconds=seconds, bytes=need, feasible=False,
                          why_not=f"its matrices need {need / 2**30:.1f} GiB (limit"
                                  f" {settings.memory_limit_bytes / 2**30:.1f} GiB)")
    return Prediction(seconds=seconds, bytes=need)


def choose_method(patches: Patches, settings: SolveSettings, shooters: int | None = None) -> MethodChoice:
    """The faster feasible method for these patches, and why."""
    area = patches.area
    mean_reflectance = float((area * patches.reflectance.mean(axis=1)).sum() / area.sum())
    predictions = {"progressive": predict_progressive(patches, settings, shooters),
                   "hemicube": predict_hemicube(patches, settings, mean_reflectance)}
    table = {name: {"seconds": round(p.seconds, 2), "bytes": int(p.bytes), "feasible": p.feasible}
             for name, p in predictions.items()}
    progressive, hemicube = predictions["progressive"], predictions["hemicube"]
    if not hemicube.feasible:
        return MethodChoice("progressive", f"hemi-cube method not possible: {hemicube.why_not}", table)
    chosen = "hemicube" if hemicube.seconds < progressive.seconds else "progressive"
    other = "progressive" if chosen == "hemicube" else "hemicube"
    reason = (f"{len(patches)} patches: predicted {predictions[chosen].seconds:.2g} s against"
              f" {predictions[other].seconds:.2g} s for the {other} method")
    return MethodChoice(chosen, reason, table)


# the solve's other stages, for the time-left estimate (timing.StagePlan), calibrated on the production
# terrace (bench/production.py): seconds per face for the faces' material means, clustering and the
# analysis; per patch probed and per surface in each of the sky's direction maps for a refinement
# round; per patch for a method before it is chosen
STAGE_SECONDS = {"materials": 1.5e-6, "cluster": 1.5e-5, "analyse": 6.5e-6, "refine_patch": 4e-4,
                 "sky_surface": 5e-7, "method_patch": 1.5e-3}
REFINED_SHARE = 0.3  # of the patches a refinement round after the first probes again (those it split)


def predicted_patches(scene, settings: SolveSettings) -> int:
    """The patches a solve will have, guessed before its faces are clustered: a patch per
    patch-sized piece of the surfaces, no more than faces (times four for the rounds' splits)."""
    if settings.subdiv is not None:
        return len(scene) * settings.subdiv ** 2
    return int(min(len(scene), 2 * float(scene.area.sum()) / settings.patch_size ** 2 + 16))


def stage_predictions(scene, settings: SolveSettings, patches: int, surfaces: int | None = None) -> dict:
    """Predicted seconds of a solve's stages for `scene` (its faces) and about `patches` patches on
    `surfaces` surfaces (default: as many as patches)."""
    faces = len(scene)
    surfaces = patches if surfaces is None else surfaces
    sky = STAGE_SECONDS["sky_surface"] * surfaces * 1024 if np.any(scene.world_color > 0) else 0.0
    rounds = settings.refinements
    refine = (STAGE_SECONDS["refine_patch"] * patches * (1 + REFINED_SHARE * max(rounds - 1, 0)) + rounds * sky
              if rounds else 0.0)
    predicted = {"cluster": STAGE_SECONDS["cluster"] * faces, "analyse": STAGE_SECONDS["analyse"] * faces,
                 "refine": refine, "method": STAGE_SECONDS["method_patch"] * patches + sky}
    if scene.material_maps:
        predicted["materials"] = STAGE_SECONDS["materials"] * faces
    return predicted
