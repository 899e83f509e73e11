"""Measurements of the progressive method for the issue's closing note.

- furnace: closed unit cube, ρ = 0.9, E = 1 (exact answer B = 10), per kernel and subdivision;
- speed: shots per second on the Cornell box at several element counts (fixed shot budget).

    .venv/bin/python tools/measure_progressive.py furnace [--subdiv 1 2 4] [--elements 2]
    .venv/bin/python tools/measure_progressive.py speed [--subdiv 4] [--elements 2 8] [--shots 300]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.scenes import CUBE_FACES  # noqa: E402
from radiosity_addon.core import GPU, SolveSettings, load_scene, scene_from_dict, solve  # noqa: E402


def furnace(gpu, args):
    scene = scene_from_dict({"surfaces": [
        {"name": n, "vertices": v, "reflectance": [0.9] * 3, "emission": [1.0] * 3} for n, v in CUBE_FACES.items()
    ]})
    for kernel in ("exact", "disk"):
        for subdiv in args.subdiv:
            started = time.perf_counter()
            solution = solve(scene, SolveSettings(method="progressive", quality="final", subdiv=subdiv,
                                                  elements=args.elements, tolerance=args.tolerance, kernel=kernel), gpu=gpu)
            b = solution.element_radiosity[..., 0]
            area = solution.patches.area
            mean = float((area * solution.patch_radiosity[:, 0]).sum() / area.sum())
            energy = solution.report.details.energy
            print(f"furnace kernel {kernel:5s} subdiv {subdiv} elements {args.elements} tol {args.tolerance:g}:"
                  f" mean B {mean:.4f} (error {mean / 10 - 1:+.2%}), elements {b.min():.3f}..{b.max():.3f},"
                  f" row-sum shortfall {energy['escaped'] / energy['emitted']:.2%} and surplus"
                  f" {energy['surplus'] / energy['emitted']:.2%} of emitted,"
                  f" {solution.report.shots} shots, {time.perf_counter() - started:.1f} s")


def speed(gpu, args):
    scene = load_scene(args.scene)
    for elements in args.elements:
        for subdiv in args.subdiv:
            solution = solve(scene, SolveSettings(method="progressive", quality="final", subdiv=subdiv,
                                                  elements=elements, max_shots=args.shots, tolerance=1e-9), gpu=gpu)
            r = solution.report.to_dict()
            t = r["timings"]
            loop = sum(t.get(k, 0.0) for k in ("select", "visibility", "shoot", "mipmap"))
            print(f"speed {args.scene} subdiv {subdiv} ({r['counts']['patches']} patches) elements {elements}x{elements}"
                  f" ({r['counts']['elements']} elements): {r['shots']} shots in {loop:.2f} s ="
                  f" {r['shots'] / loop:.1f} shots/s  (select {t['select']:.2f}, visibility {t['visibility']:.2f},"
                  f" shoot {t['shoot']:.2f}, mipmap {t['mipmap']:.2f} s; GL is asynchronous, so stage times"
                  f" shift work between them)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    f = sub.add_parser("furnace")
    f.add_argument("--subdiv", type=int, nargs="+", default=[1, 2, 4])
    f.add_argument("--elements", type=int, default=2)
    f.add_argument("--tolerance", type=float, default=2e-3)
    s = sub.add_parser("speed")
    s.add_argument("--scene", default="cornell-box")
    s.add_argument("--subdiv", type=int, nargs="+", default=[4])
    s.add_argument("--elements", type=int, nargs="+", default=[2, 8])
    s.add_argument("--shots", type=int, default=300)
    args = parser.parse_args()
    with GPU() as gpu:
        {"furnace": furnace, "speed": speed}[args.what](gpu, args)


if __name__ == "__main__":
    main()
