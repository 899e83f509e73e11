"""The dissertation's Table 5.1 reproduced: linear-solve time vs patch count on the Cornell box.

Their setup: the form-factor matrix of the hemi-cube method for 69 ... 2449 patches, 30 timed
solves per solver, stopping when the largest change falls under two decimal places. Their box
had one more surface (a 2 x 2 triangle pair for the left wall gives us 17 surfaces), so our
counts are 17 n²: 68, 153, ..., 2448. With the light at about 1 (8-bit colours), "under two
decimal places" is a change of 0.01 relative to max B: our tolerance 1e-2. Our default (1e-5)
is measured too. Each timed solve is one whole `solve_linear` call (GPU: buffer upload, shader
build, sweeps, readbacks) on a form-factor matrix computed once per size.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from radiosity_addon.core import Convergence, form_factor_matrix, load_scene, solve_linear, subdivide

SAMPLES = 30
SUBDIVISIONS = tuple(range(2, 13))  # 17 n² patches: 68 ... 2448
HEMICUBE_RESOLUTION = 128
TOLERANCES = {"dissertation rule (1e-2)": 1e-2, "our default (1e-5)": 1e-5}
SOLVERS = {"Seidel": "gauss-seidel", "JacCPU": "jacobi-cpu", "JacGPU": "jacobi-gpu"}

# Tabela 5.1 (ms): patches -> (Seidel mean, std, JacCPU mean, std, JacGPU mean, std)
DISSERTATION = {
    69: (0.72, 0.06, 0.86, 0.33, 15.09, 4.25),
    154: (2.19, 0.21, 3.35, 0.69, 15.01, 3.62),
    273: (11.79, 1.05, 10.1, 0.67, 14.81, 4.09),
    426: (37.73, 0.78, 26.82, 2.36, 14.35, 2.53),
    613: (79, 1.8, 69.52, 2.09, 20.15, 2.26),
    834: (164.22, 2.63, 163.33, 2.8, 41.41, 3.66),
    1089: (278.34, 3.64, 279.46, 3.32, 54.65, 4.33),
    1378: (466.73, 8.86, 455.07, 3.78, 71.65, 4.48),
    1701: (682.77, 6.14, 713.92, 4.92, 109.99, 6.62),
    2058: (992.7, 5.64, 1213.14, 6.39, 173.87, 5.69),
    2449: (1403.55, 7.32, 1558.16, 8.31, 217.12, 7.16),
}


def timed_solves(gpu, solver: str, form_factors, patches, tolerance: float, samples: int):
    """Milliseconds of `samples` solves (after one untimed warm-up) and the iterations of the last."""
    times = []
    for sample in range(samples + 1):
        monitor = Convergence(solver, tolerance, 100_000)
        started = time.perf_counter()
        solve_linear(gpu, solver, form_factors, patches.reflectance, patches.emission, monitor)
        if sample:
            times.append(1e3 * (time.perf_counter() - started))
    return np.array(times), monitor.iterations


def measure(gpu, samples: int = SAMPLES, subdivisions=SUBDIVISIONS, log=print) -> list[dict]:
    scene = load_scene("cornell-box")
    rows = []
    for n in subdivisions:
        patches = subdivide(scene, n)
        form_factors = form_factor_matrix(gpu, patches, HEMICUBE_RESOLUTION, scene.diameter)
        for label, tolerance in TOLERANCES.items():
            row = {"patches": len(patches), "dissertation_patches": len(patches) + 1, "tolerance": tolerance,
                   "rule": label, "solvers": {}}
            for column, solver in SOLVERS.items():
                times, iterations = timed_solves(gpu, solver, form_factors, patches, tolerance, samples)
                row["solvers"][column] = {"mean_ms": float(times.mean()), "std_ms": float(times.std(ddof=1)),
                                          "iterations": iterations, "samples": samples}
            log(f"  {len(patches)} patches, tol {tolerance:g}: " + ", ".join(
                f"{c} {v['mean_ms']:.1f}±{v['std_ms']:.1f} ms ({v['iterations']} it)"
                for c, v in row["solvers"].items()))
            rows.append(row)
    return rows


def winner(solvers: dict) -> str:
    return min(solvers, key=lambda column: solvers[column]["mean_ms"])


def markdown(rows: list[dict], machine_line: str = "") -> str:
    lines = ["# Table 5.1 reproduced: linear-solve time (ms) vs patch count", "",
             "Mean ± standard deviation of timed solves of the Cornell box's form-factor system."
             " Dissertation: its Tabela 5.1 (2011 hardware, a real GPU). Ours: this machine"
             " (\"GPU\" = Mesa llvmpipe, i.e. the CPU cores running the compute shader).", "", machine_line, ""]
    for label in TOLERANCES:
        lines += [f"## Stopping rule: {label}", "",
                  "| patches (theirs / ours) | Seidel theirs | Seidel ours | JacCPU theirs | JacCPU ours"
                  " | JacGPU theirs | JacGPU ours | fastest here (theirs) |",
                  "|---|---:|---:|---:|---:|---:|---:|---|"]
        for row in (r for r in rows if r["rule"] == label):
            theirs = DISSERTATION.get(row["dissertation_patches"])
            cells = []
            for k, column in enumerate(SOLVERS):
                ours = row["solvers"][column]
                cells.append(f"{theirs[2 * k]:.2f} ± {theirs[2 * k + 1]:.2f}" if theirs else "—")
                cells.append(f"{ours['mean_ms']:.2f} ± {ours['std_ms']:.2f} ({ours['iterations']} it)")
            their_winner = min(SOLVERS, key=lambda c: theirs[2 * list(SOLVERS).index(c)]) if theirs else "—"
            lines.append(f"| {row['dissertation_patches']} / {row['patches']} | " + " | ".join(cells)
                         + f" | {winner(row['solvers'])} ({their_winner}) |")
        lines.append("")
    return "\n".join(lines)


def write(output_dir: Path, rows: list[dict], machine_line: str = "") -> None:
    Path(output_dir, "table_5_1.json").write_text(json.dumps({"rows": rows, "dissertation_ms": DISSERTATION},
                                                              indent=1))
    Path(output_dir, "table_5_1.md").write_text(markdown(rows, machine_line))
