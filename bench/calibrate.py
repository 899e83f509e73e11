"""`python -m bench.calibrate`: measure the constants of the auto method's cost
model (core/method_choice.py) on this machine, on the Cornell box subdivided more and more:

- a hemi-cube of the hemi-cube method (drawn, reduced, read back): seconds per pixel and per
  triangle (R and P varied, least squares on the form-factor stage's time);
- a progressive shot: seconds per pixel, per triangle and per element (visibility and shooting
  stages, batches as the solve makes them);
- the linear solve: seconds per matrix entry and sweep (Jacobi on the GPU);
- progressive refinement: shots per patch to a tolerance.

It prints the constants as Python to paste into method_choice.py, with the load average (the
numbers are only as quiet as the machine)."""

from __future__ import annotations

import argparse
import os
import numpy as np

from radiosity_addon.core import SolveSettings, load_scene, solve


def fit(rows: list, seconds: list) -> np.ndarray:
    """Non-negative least squares by clipping (the columns are costs: none can be negative)."""
    coefficients, *_ = np.linalg.lstsq(np.array(rows, float), np.array(seconds, float), rcond=None)
    return np.maximum(coefficients, 0.0)


def triangles(patches) -> int:
    return int(np.where(patches.is_triangle, 1, 2).sum())


def hemicube_costs(scene, subdivisions=(3, 8), resolutions=(32, 128)) -> tuple[float, float]:
    """(seconds per pixel, per triangle and face) of a hemi-cube of the hemi-cube method (drawn,
    reduced into a row, read back), from its form-factor stage."""
    rows, seconds = [], []
    for subdiv in subdivisions:
        for resolution in resolutions:
            solution = solve(scene, SolveSettings(method="hemicube", subdiv=subdiv, refinements=0,
                                                  hemicube_elements=1, hemicube_res=resolution))
            hemicubes = solution.report.work.hemicubes
            rows.append([3 * resolution ** 2, 5 * triangles(solution.patches)])
            seconds.append(solution.report.timings["form_factors"] / hemicubes)
    per_pixel, per_triangle = fit(rows, seconds)
    return float(per_pixel), float(per_triangle)


def shot_costs(scene, settings=((3, 1, 256), (8, 1, 256), (8, 4, 256), (3, 4, 1024)), shots: int = 256):
    """(seconds per pixel, per triangle and face, per element) of a progressive shot (its hemi-cube
    drawn in a batch, every element gathering it), from the visibility and shooting stages."""
    rows, seconds = [], []
    for subdiv, elements, resolution in settings:
        solution = solve(scene, SolveSettings(method="progressive", subdiv=subdiv, elements=elements, refinements=0,
                                              visibility_res=resolution, max_shots=shots, tolerance=1e-9))
        timings, count = solution.report.timings, solution.report.details.shots
        hemicube = resolution // 2
        rows.append([3 * hemicube ** 2, 5 * triangles(solution.patches), len(solution.patches) * elements ** 2])
        seconds.append((timings["visibility"] + timings["shoot"]) / count)
    return tuple(float(c) for c in fit(rows, seconds))


def sweep_cost(scene, subdiv: int = 12) -> float:
    """Seconds per matrix entry and Jacobi sweep (GPU), from a hemi-cube solve's linear stage."""
    solution = solve(scene, SolveSettings(method="hemicube", subdiv=subdiv, refinements=0, hemicube_elements=1,
                                          hemicube_res=32, tolerance=1e-6))
    report = solution.report
    patches = len(solution.patches)
    return report.timings["linear_solve"] / (patches ** 2 * max(report.details.iterations, 1))


def shots_per_patch(scene, tolerances=(1e-2, 3e-3, 1e-3)) -> dict:
    """Progressive shots per patch to each tolerance."""
    result = {}
    for tolerance in tolerances:
        solution = solve(scene, SolveSettings(method="progressive", subdiv=6, refinements=0, elements=1,
                                              tolerance=tolerance, visibility_res=128))
        result[tolerance] = solution.report.details.shots / len(solution.patches)
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.parse_args(argv)
    scene = load_scene("cornell-box")
    started_load = os.getloadavg()[0]
    per_pixel, per_triangle = hemicube_costs(scene)
    shot_pixel, shot_triangle, per_element_shot = shot_costs(scene)
    per_entry_sweep = sweep_cost(scene)
    shots = shots_per_patch(scene)
    print(f"# measured by python -m bench.calibrate (load average {started_load:.1f}"
          f" -> {os.getloadavg()[0]:.1f})")
    print(f"HEMICUBE_SECONDS = {{'pixel': {per_pixel:.3g}, 'triangle': {per_triangle:.3g}}}")
    print(f"SHOT_SECONDS = {{'pixel': {shot_pixel:.3g}, 'triangle': {shot_triangle:.3g},"
          f" 'element': {per_element_shot:.3g}}}")
    print(f"SECONDS_PER_MATRIX_ENTRY_SWEEP = {per_entry_sweep:.3g}")
    print(f"SHOTS_PER_PATCH = {{{', '.join(f'{t:g}: {s:.2f}' for t, s in shots.items())}}}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
