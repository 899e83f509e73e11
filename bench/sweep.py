"""The sweep: for each scene, solve with each setting (and bake with Cycles at several sample
counts) and measure wall time per stage and the error on the common texel grid."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from radiosity_addon.core import Scene, SolveError, SolveSettings, solve
from . import metrics, reference
from .scenes import ANALYTIC_SCENES
from .texels import solution_texels, texel_patches, texel_weights


@dataclass(frozen=True)
class SweepPlan:
    """What one bench run covers; `quick` keeps it to a few minutes on 2 cores."""
    texel_resolution: int  # texels per surface side on the common grid
    reference_samples: int  # Cycles samples per texel of each of the two reference bakes
    cycles_samples: tuple[int, ...]
    hemicube: tuple[SolveSettings, ...]
    progressive: tuple[SolveSettings, ...]
    analytic_subdivisions: dict  # method -> subdivisions swept on the analytic scenes


def one_at_a_time(base: SolveSettings, **axes) -> tuple[SolveSettings, ...]:
    """The base setting and, per axis, the base with that one knob varied (duplicates dropped)."""
    settings = [base] + [replace(base, **{axis: value}) for axis, values in axes.items() for value in values]
    unique = {}
    for s in settings:
        unique.setdefault(tuple(sorted(s.as_dict().items())), s)
    return tuple(unique.values())


def make_plan(quick: bool) -> SweepPlan:
    # final's preset with the finer hemi-cubes the sweep was first measured with, and no refinement:
    # the sweep maps each patch to its grid cell (texels.py), which a refined patch's children share
    hemicube = SolveSettings(method="hemicube", quality="final", subdiv=6, hemicube_res=64, hemicube_elements=2,
                             refinements=0, solver="jacobi-gpu", tolerance=1e-5)
    progressive = SolveSettings(method="progressive", quality="final", subdiv=4, elements=4, refinements=0,
                                tolerance=1e-3)
    if quick:
        return SweepPlan(
            texel_resolution=32, reference_samples=1024, cycles_samples=(4, 16, 64),
            hemicube=one_at_a_time(hemicube, subdiv=(2, 4, 8), hemicube_res=(32, 128), tolerance=(1e-2,),
                                   solver=("gauss-seidel",)),
            # progressive costs ~14 s at subdiv 4 on llvmpipe (visibility maps and shots are fragment work)
            progressive=one_at_a_time(progressive, subdiv=(2,), elements=(8,), tolerance=(1e-2,)),
            analytic_subdivisions={"hemicube": (2, 4, 8), "progressive": (1, 2)},
        )
    return SweepPlan(
        texel_resolution=32, reference_samples=4096, cycles_samples=(4, 16, 64, 256, 1024),
        hemicube=one_at_a_time(hemicube, subdiv=(2, 3, 4, 8, 10, 12), hemicube_res=(16, 32, 128, 256),
                               tolerance=(1e-2, 1e-3, 1e-4), solver=("jacobi-cpu", "gauss-seidel"))
        + one_at_a_time(replace(hemicube, subdiv=12, hemicube_res=256), tolerance=(1e-3,)),
        progressive=one_at_a_time(progressive, subdiv=(2, 3, 6, 8), elements=(1, 2, 8, 16),
                                  tolerance=(1e-2, 1e-4), visibility=("plain", "tessellated"), kernel=("disk",)),
        analytic_subdivisions={"hemicube": (1, 2, 4, 8, 12), "progressive": (1, 2, 4)},
    )


class Evaluation:
    """A scene's texel weights and reference, and the error of any answer on that grid."""

    def __init__(self, name: str, scene: Scene, plan: SweepPlan, cache_dir, log):
        self.name, self.scene, self.resolution = name, scene, plan.texel_resolution
        self.weights = metrics.compared_surfaces(scene, texel_weights(scene, self.resolution))
        self.reference, noise, self.reference_description = reference.reference_for(
            name, scene, self.resolution, plan.reference_samples, cache_dir, log)
        # the reference's own noise: (a − b)/2 of two seeds has the spread of their mean (a + b)/2
        self.noise_floor = None if noise is None else metrics.relative_rms(
            self.reference + noise, self.reference, self.weights)

    def errors(self, texels: np.ndarray) -> dict:
        """Errors of reflected-radiance texels (B − E) against the reference."""
        worst, worst_error = metrics.worst_object_error(self.scene, texels, self.reference, self.weights)
        return {"error": metrics.relative_rms(texels, self.reference, self.weights),
                "worst_object": worst, "worst_object_error": worst_error}


def solve_row(evaluation: Evaluation, settings: SolveSettings, gpu) -> dict:
    solution = solve(evaluation.scene, settings, gpu=gpu)
    constant, interpolated = (metrics.reflected(evaluation.scene, solution_texels(
        evaluation.scene, solution.patches, solution.patch_radiosity, solution.element_radiosity,
        evaluation.resolution, interpolate)) for interpolate in (False, True))
    report = solution.report.to_dict()
    owners = texel_patches(evaluation.scene, solution.patches, evaluation.resolution)
    footprint = metrics.footprint_rms(constant, evaluation.reference, evaluation.weights, owners)
    return {"scene": evaluation.name, "method": settings.method, "settings": compact_settings(settings),
            "seconds": report["timings"]["total"], **evaluation.errors(interpolated),
            "constant_error": metrics.relative_rms(constant, evaluation.reference, evaluation.weights),
            "patch_error": footprint,
            "timings": report["timings"], "counts": report["counts"],
            "iterations": report.get("iterations", report.get("shots"))}


def cycles_row(evaluation: Evaluation, samples: int) -> dict:
    bake = reference.cycles_bake(evaluation.scene, evaluation.resolution, samples, seed=7)
    return {"scene": evaluation.name, "method": "cycles", "settings": {"samples": samples},
            "seconds": bake["seconds"], **evaluation.errors(metrics.reflected(evaluation.scene, bake["texels"])),
            "timings": {"bake": bake["seconds"], "total": bake["seconds"]},
            "counts": {"texels": int((evaluation.weights > 0).sum())}}


KNOBS = {"hemicube": ("subdiv", "hemicube_res", "solver", "tolerance", "skip_unneeded"),
         "progressive": ("subdiv", "elements", "tolerance", "visibility", "kernel")}


def compact_settings(settings: SolveSettings) -> dict:
    """The knobs that matter to the method (SolveSettings carries both methods' knobs)."""
    full = settings.as_dict()
    return {key: full[key] for key in KNOBS[settings.method]} | {"tolerance": settings.effective_tolerance}


def sweep_scene(name: str, scene: Scene, plan: SweepPlan, gpu, cache_dir, log=print) -> tuple[list[dict], dict]:
    """Rows of one scene, and notes on its reference and on skipped families."""
    evaluation = Evaluation(name, scene, plan, cache_dir, log)
    notes = {"reference": evaluation.reference_description, "noise_floor": evaluation.noise_floor,
             "texels_per_surface_side": plan.texel_resolution, "skipped": []}
    families = [("hemicube", plan.hemicube), ("progressive", plan.progressive)]
    if name in ANALYTIC_SCENES:  # subdivision only; the hemi-cube also without the analytic shortcuts
        families = [(method, tuple(replace(settings[0], subdiv=n, skip_unneeded=skip)
                                   for skip in ((True, False) if method == "hemicube" else (True,))
                                   for n in plan.analytic_subdivisions[method]))
                    for method, settings in families]
    rows = []
    for method, settings_list in families:
        for settings in settings_list:
            try:
                row = solve_row(evaluation, settings, gpu)
            except SolveError as error:
                log(f"  {name} {method} {compact_settings(settings)}: {error}")
                notes["skipped"].append(f"{method} {compact_settings(settings)}: {error}")
                continue
            log(f"  {name} {method} {row['settings']}: {row['seconds']:.2f} s, error {row['error']:.4f}")
            rows.append(row)
    for samples in plan.cycles_samples:
        row = cycles_row(evaluation, samples)
        log(f"  {name} cycles {samples} samples: {row['seconds']:.2f} s, error {row['error']:.4f}")
        rows.append(row)
    return rows, notes

