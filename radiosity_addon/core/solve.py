"""The pipeline: scene -> analysis -> patches -> a method's solve -> Solution with its report.

Both methods enter here, so every caller (command line, Blender, tests, benchmark) gets the
same settings checks, emitter check, timings and report.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from .gpu import GPU, open_gpu
from .hemicube import solve_hemicube
from .hemicube.form_factors import check_memory, patch_budget
from .method_choice import choose_method, predicted_patches, stage_predictions
from .progressive import solve_progressive
from .report import Counts, Report
from .scene import Scene, check_has_emitter, effects_for, subdivide
from .scene.analysis import simulated_backs
from .scene.face_clusters import cluster_faces
from .settings import PATCHES_ACROSS_SCENE, SolveSettings
from .shooting import element_areas, patch_means
from .solution import Solution
from .refinement import refine
from .timing import ProgressCallback, StagePlan, StageTimer
from .uvspace import patch_material_values, surfaces_with_material_maps


def solve(scene: Scene, settings: SolveSettings | None = None, progress: ProgressCallback | None = None,
          should_cancel=None, gpu: GPU | None = None, preview=None, preview_interval: float = 2.0,
          timer: StageTimer | None = None) -> Solution:
    """Solve radiosity for `scene` (see core/__init__.py for the parameters)."""
    settings = settings or SolveSettings()
    settings.validate()
    if settings.subdiv is None and settings.patch_size > scene.diameter / PATCHES_ACROSS_SCENE:
        # a 1 m patch in a 55 cm box would leave each wall one sample of its light
        settings = replace(settings, patch_size=scene.diameter / PATCHES_ACROSS_SCENE)
    if not scene.material_maps:  # refuse before any GPU work (with maps, once they are read)
        check_has_emitter(scene)
    started = time.perf_counter()
    timer = timer if timer is not None else StageTimer()
    plan = StagePlan(progress, stage_predictions(scene, settings, predicted_patches(scene, settings)))
    with open_gpu(gpu) as solve_gpu:
        if scene.material_maps:  # textured materials: surfaces and patches take their texels' means
            with plan.stage("materials", "reading the material maps"), timer.stage("materials"):
                scene = surfaces_with_material_maps(solve_gpu, scene, scene.material_maps)
            check_has_emitter(scene)
        faces = scene
        with plan.stage("cluster", f"clustering {len(faces)} faces"), timer.stage("cluster"):
            clusters = cluster_faces(faces, settings.patch_size, settings.subdiv)  # the solve's surfaces
        scene = clusters.proxies
        with plan.stage("analyse", "analysing the scene"), timer.stage("analyse"):
            backs = clusters.proxy_backs(simulated_backs(faces, settings.skip_unneeded))
            effects, backs = effects_for(scene, settings.skip_unneeded, backs)
        with timer.stage("subdivide"):
            patches = subdivide(scene, settings.subdiv, settings.patch_size, backs)
        for name, seconds in stage_predictions(faces, settings, len(patches), len(scene)).items():
            if name in ("refine", "method"):
                plan.predict(name, seconds)
        if scene.material_maps:
            with timer.stage("materials"):
                patches.reflectance, patches.emission = patch_material_values(solve_gpu, scene, patches)
        budget = None
        if settings.method == "hemicube":  # refuse before any GPU work; refinement stays within the matrices' memory
            check_memory(len(patches), settings.memory_limit_bytes, settings.hemicube_elements)
            budget = patch_budget(settings.memory_limit_bytes, settings.hemicube_elements)
        with plan.stage("refine", f"refining {len(patches)} patches"):
            patches, refined, measured = refine(solve_gpu, scene, patches, backs, settings, effects, timer, budget,
                                                plan.within())
        choice = choose_method(patches, settings)  # each method's predicted time: the estimate's, and auto's choice
        asked_auto = settings.method == "auto"
        if asked_auto:
            settings = replace(settings, method=choice.method)
        plan.predict("method", choice.predicted[settings.method]["seconds"])
        choice = choice if asked_auto else None
        with plan.stage("method", f"solving {len(patches)} patches ({settings.method})",
                        estimates_itself=settings.method == "progressive"):
            result = _solve_patches(solve_gpu, scene, patches, settings, effects, timer, plan.within(),
                                    should_cancel, preview, preview_interval, measured, clusters)
    radiosity, elements, light, element_light, direct, element_direct, element_sky, details = result
    timer.timings["total"] = time.perf_counter() - started
    element_count = len(patches) * elements.shape[1] ** 2
    report = Report(method=settings.method, settings=settings,
                    counts=Counts(surfaces=len(faces), objects=len(scene.object_names), patches=len(patches),
                                  elements=element_count, clusters=int(clusters.merged.sum())),
                    timings=timer.timings, effects=effects, details=details,
                    radiosity_max=float(np.max(radiosity)), refined=refined,
                    method_choice=choice.as_dict() if choice is not None else None)
    return Solution(patches=patches, patch_radiosity=np.asarray(radiosity, dtype=np.float64),
                    element_radiosity=elements, report=report, patch_light=np.asarray(light, dtype=np.float64),
                    element_light=element_light, patch_direct=np.asarray(direct, dtype=np.float64),
                    element_direct=element_direct, element_sky=element_sky, scene=scene, clusters=clusters)


def _solve_patches(gpu: GPU, scene: Scene, patches, settings: SolveSettings, effects, timer: StageTimer, progress,
                   should_cancel, preview, preview_interval, measured=None, clusters=None):
    """One method's solve on these patches: (B, element B, H, element H, direct H, element direct H,
    element sky H, details); element arrays (P, S, S, 3), or for the hemi-cube method's one value
    per patch the patch arrays as 1 x 1 elements. `measured`: refinement's probe of the direct light; `clusters`:
    the faces the patches' surfaces stand for (previews are laid out on them)."""
    if settings.method == "hemicube":
        radiosity, elements, element_light, element_direct, element_sky, details, _ = solve_hemicube(
            gpu, scene, patches, settings, effects, timer, progress, should_cancel, measured)
        areas = element_areas(patches, settings.hemicube_elements)
        return (radiosity, elements, patch_means(areas, element_light), element_light,
                patch_means(areas, element_direct), element_direct, element_sky, details)
    areas = element_areas(patches, settings.elements)
    shown = None if preview is None else (
        lambda radiosity, light: preview(Solution(patches, patch_means(areas, radiosity), radiosity,
                                                  patch_light=patch_means(areas, light), element_light=light,
                                                  scene=scene, clusters=clusters)))
    radiosity, elements, element_light, element_direct, element_sky, details = solve_progressive(
        gpu, scene, patches, settings, effects, timer, progress, should_cancel, shown, preview_interval)
    return (radiosity, elements, patch_means(areas, element_light), element_light,
            patch_means(areas, element_direct), element_direct, element_sky, details)
