"""The pipeline: scene -> patches -> solve -> Solution with its report.

Both methods enter here, so callers (CLI, Blender operator, tests, benchmark)
get the same settings checks, emitter check, timings and report.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from . import gl
from .effects import effects_for
from .patches import subdivide
from .scene import Scene, check_has_emitter
from .solution import Solution, SolveSettings, StageTimer


def solve(scene: Scene, settings: SolveSettings | None = None, progress=None, should_cancel=None,
          ctx=None) -> Solution:
    """Solve radiosity for `scene`. `progress(fraction, message, details)` is called as it goes;
    `should_cancel()` returning True stops it with SolveCancelled. Without `ctx`, a standalone
    OpenGL context is made for this solve and released after it."""
    settings = settings or SolveSettings()
    settings.validate()
    check_has_emitter(scene)
    started = time.perf_counter()
    timer = StageTimer()
    with timer.stage("analyse"):
        effects = effects_for(scene, settings.skip_unneeded)
    with timer.stage("subdivide"):
        patches = subdivide(scene, settings.subdiv)
    with gl.gl_context(ctx) as gl_ctx:
        if settings.method == "hemicube":
            from .original import solve_original

            radiosity, details, _ = solve_original(gl_ctx, patches, scene.diameter, settings, effects,
                                                   timer, progress, should_cancel)
            elements = None
        else:
            from .progressive import solve_progressive

            radiosity, elements, details = solve_progressive(gl_ctx, scene, patches, settings, timer,
                                                             progress, should_cancel)
    timer.timings["total"] = time.perf_counter() - started

    work = details.pop("work", {})
    element_count = len(patches) * (settings.elements ** 2 if elements is not None else 1)
    report = {
        "method": settings.method,
        "settings": settings.as_dict(),
        "counts": {"surfaces": len(scene.surfaces), "objects": len(scene.objects),
                   "patches": len(patches), "elements": element_count},
        "timings": timer.timings,
        **details,
        "effects": {**dataclasses.asdict(effects), **work},
        "radiosity_max": float(np.max(radiosity)),
    }
    return Solution(patches=patches, patch_radiosity=np.asarray(radiosity, dtype=np.float64),
                    element_radiosity=elements, report=report)
