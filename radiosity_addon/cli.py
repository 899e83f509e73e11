"""Command line: `python -m radiosity_addon {solve,bake,bench} ...` (DESIGN.md, Interfaces).

Errors a user can cause end in one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from .core.gl import GLUnavailable
from .core.scene import SceneError
from .core.solution import METHODS, SOLVERS, SolveCancelled, SolveError, SolveSettings

USER_ERRORS = (SceneError, SolveError, GLUnavailable, SolveCancelled, FileNotFoundError)


def add_solver_options(parser: argparse.ArgumentParser) -> None:
    defaults = SolveSettings()
    group = parser.add_argument_group("solver")
    group.add_argument("--method", choices=METHODS, default=defaults.method,
                       help="progressive refinement (default) or the original hemi-cube method")
    group.add_argument("--subdiv", type=int, default=defaults.subdiv, metavar="N",
                       help=f"split each surface N x N into patches (default {defaults.subdiv})")
    group.add_argument("--elements", type=int, default=defaults.elements, metavar="S",
                       help=f"S x S elements per patch, a power of two (progressive; default {defaults.elements})")
    group.add_argument("--hemicube-res", type=int, default=defaults.hemicube_res, metavar="R",
                       help=f"hemi-cube top-face resolution in pixels (default {defaults.hemicube_res})")
    group.add_argument("--solver", choices=SOLVERS, default=defaults.solver,
                       help="linear solver of the hemi-cube method (default jacobi-gpu)")
    group.add_argument("--tolerance", type=float, default=None, metavar="T",
                       help="hemicube: max change relative to max B (default 1e-5); progressive: unshot"
                            " power relative to emitted power (default 1e-3)")
    group.add_argument("--max-iterations", type=int, default=defaults.max_iterations,
                       help="iteration cap of the linear solvers")
    group.add_argument("--max-shots", type=int, default=None, help="shot budget of the progressive method")
    group.add_argument("--visibility", choices=("plain", "tessellated", "search"), default=defaults.visibility,
                       help="progressive visibility variant (default search)")
    group.add_argument("--kernel", choices=("exact", "disk"), default=defaults.kernel,
                       help="progressive form-factor kernel: exact point-to-polygon (default) or the disk"
                            " approximation")
    group.add_argument("--no-skips", dest="skip_unneeded", action="store_false",
                       help="simulate every effect even when the scene analysis shows it is absent")


def settings_from_args(args) -> SolveSettings:
    return SolveSettings(
        method=args.method, subdiv=args.subdiv, elements=args.elements, hemicube_res=args.hemicube_res,
        solver=args.solver, tolerance=args.tolerance, max_iterations=args.max_iterations,
        max_shots=args.max_shots, visibility=args.visibility, kernel=args.kernel,
        skip_unneeded=args.skip_unneeded,
    )


class ProgressLine:
    """A progress callback that rewrites one stderr line at most ~5 times a second."""

    def __init__(self):
        self.last = 0.0
        self.shown = False

    def __call__(self, fraction, message, details):
        now = time.monotonic()
        if now - self.last >= 0.2 or fraction >= 1:
            self.last, self.shown = now, True
            print(f"\r{100 * fraction:5.1f}%  {message:<60}", end="", file=sys.stderr, flush=True)

    def end(self):
        if self.shown:
            print(file=sys.stderr)
            self.shown = False


PROGRESS = ProgressLine()


def print_progress(quiet: bool):
    return None if quiet else PROGRESS


def command_solve(args) -> int:
    import numpy as np

    from .core.scene import load_scene
    from .core.solve import solve

    scene = load_scene(args.scene)
    settings = settings_from_args(args)
    solution = solve(scene, settings, progress=print_progress(args.quiet))
    PROGRESS.end()
    report = solution.report
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(args.output, **solution.npz_arrays())
    if args.report:
        Path(args.report).parent.mkdir(parents=True, exist_ok=True)
        Path(args.report).write_text(json.dumps(report, indent=2))
    counts, timings = report["counts"], report["timings"]
    print(f"{report['method']}: {counts['patches']} patches, {counts['elements']} elements,"
          f" {timings['total']:.2f} s ({', '.join(f'{k} {v:.2f}' for k, v in timings.items() if k != 'total')})")
    return 0


def command_bench(args) -> int:
    from .bench.run import run_bench

    run_bench(Path(args.output_dir), args.quick, args.cache_dir, args.table51_samples,
              tuple(name for name in args.scenes.split(",") if name))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m radiosity_addon",
                                     description="Radiosity Baker: diffuse GI by radiosity on the GPU.")
    commands = parser.add_subparsers(dest="command", required=True)

    solve_parser = commands.add_parser("solve", help="solve a scene file or a bundled scene (cornell-box)")
    solve_parser.add_argument("scene", help="scene JSON path or bundled scene name (cornell-box)")
    add_solver_options(solve_parser)
    solve_parser.add_argument("--output", metavar="OUT.npz", help="write patch (and element) radiosity")
    solve_parser.add_argument("--report", metavar="REPORT.json", help="write the timings/accuracy/effects report")
    solve_parser.add_argument("--quiet", action="store_true", help="no progress line")
    solve_parser.set_defaults(handler=command_solve)

    bench_parser = commands.add_parser(
        "bench", help="accuracy vs time against Cycles and exact answers, and the dissertation's Table 5.1")
    bench_parser.add_argument("--quick", action="store_true", help="a smaller sweep: a few minutes on 2 cores")
    bench_parser.add_argument("--output-dir", required=True, metavar="DIR",
                              help="writes accuracy_vs_time.{json,md,png} and table_5_1.{json,md}")
    bench_parser.add_argument("--cache-dir", metavar="DIR", help="Cycles reference cache (default DIR/cache)")
    bench_parser.add_argument("--table51-samples", type=int, default=None, metavar="N",
                              help="timed solves per solver and size for Table 5.1 (default 30, quick 5; 0 skips)")
    bench_parser.add_argument("--scenes", default="cornell-box,furnace,plates",
                              help="comma-separated: cornell-box (Cycles reference), furnace, plates (exact)")
    bench_parser.set_defaults(handler=command_bench)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except USER_ERRORS as error:
        PROGRESS.end()
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        PROGRESS.end()
        print("error: interrupted", file=sys.stderr)
        return 130
