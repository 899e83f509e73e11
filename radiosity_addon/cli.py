"""Command line: `python -m radiosity_addon {solve,bake,bench} ...` (DESIGN.md, Interfaces).

Errors a user can cause end in one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from pathlib import Path

from .core.gl import GLUnavailable, gl_context
from .core.lightmap import MAX_SIZE, TEXEL_DENSITY
from .core.scene import SceneError
from .core.solution import METHODS, SOLVERS, VISIBILITY_VARIANTS, SolveCancelled, SolveError, SolveSettings

USER_ERRORS = (SceneError, SolveError, GLUnavailable, SolveCancelled, FileNotFoundError)


def user_errors() -> tuple:
    """USER_ERRORS plus the Blender side's BakeError once that side is loaded (it needs bpy)."""
    blender_errors = sys.modules.get(f"{__package__}.blender.errors")
    return USER_ERRORS + ((blender_errors.BakeError,) if blender_errors else ())


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
    group.add_argument("--visibility", choices=VISIBILITY_VARIANTS, default=defaults.visibility,
                       help="progressive visibility variant: plain projection, tessellated, tessellated with"
                            " neighbour search (default), or search guarded against peeking past occluders")
    group.add_argument("--visibility-res", type=int, default=defaults.visibility_res, metavar="R",
                       help=f"pixels across the progressive visibility map (default {defaults.visibility_res})")
    group.add_argument("--shoot-from", choices=("centroid", "centre"), default=defaults.shoot_from,
                       help="progressive: render each shooter's visibility map from the centroid of its unshot"
                            " power (default) or from its centre")
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
        visibility_res=args.visibility_res, shoot_from=args.shoot_from, skip_unneeded=args.skip_unneeded,
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


def check_image_options(args) -> None:
    """Refuse bad lightmap/preview options before the solve, not after it."""
    if not args.texel_density > 0:
        raise SolveError(f"--texel-density must be positive, got {args.texel_density}")
    if args.preview and args.preview_size < 8:
        raise SolveError(f"--preview-size must be at least 8 pixels, got {args.preview_size}")
    if args.exposure is not None and not args.exposure > 0:
        raise SolveError(f"--exposure must be positive, got {args.exposure}")


def write_lightmaps_and_preview(args, scene, solution, ctx) -> None:
    """`solve --lightmaps DIR` / `--preview OUT.png`: bake the lightmaps, write them and the picture."""
    import numpy as np

    from .core.lightmap import bake_lightmaps
    from .core.preview import render_preview, save_preview

    lightmaps = bake_lightmaps(scene, solution, texel_density=args.texel_density,
                               max_size=args.max_lightmap_size, ctx=ctx)
    if args.lightmaps:
        directory = Path(args.lightmaps)
        directory.mkdir(parents=True, exist_ok=True)
        for name, lightmap in lightmaps.items():
            np.save(directory / f"{safe_file_name(name)}_lightmap.npy", lightmap.rgba)
        sizes = ", ".join(f"{name} {lm.size[0]}x{lm.size[1]}" for name, lm in lightmaps.items())
        print(f"lightmaps ({args.texel_density:g} texels/unit): {sizes} -> {directory}/")
    if args.preview:
        preview = render_preview(scene, lightmaps, width=args.preview_size, height=args.preview_size, ctx=ctx)
        exposure = save_preview(args.preview, scene, preview, exposure=args.exposure)
        print(f"preview (exposure {exposure:.3g}) -> {args.preview}")


def safe_file_name(name: str) -> str:
    """An object name usable as a file name (path separators and the like become '_')."""
    return "".join(c if c.isalnum() or c in "-_. " else "_" for c in name).strip() or "object"


def command_solve(args) -> int:
    import numpy as np

    from .core.scene import load_scene
    from .core.solve import solve

    scene = load_scene(args.scene)
    settings = settings_from_args(args)
    wants_images = bool(args.lightmaps or args.preview)
    if wants_images:
        check_image_options(args)
    with gl_context() if wants_images else contextlib.nullcontext() as ctx:
        solution = solve(scene, settings, progress=print_progress(args.quiet), ctx=ctx)
        PROGRESS.end()
        if wants_images:
            write_lightmaps_and_preview(args, scene, solution, ctx)
    report = solution.report
    if args.output:
        Path(args.output).parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(args.output, **solution.npz_arrays())
    write_report(report, args.report)
    counts, timings = report["counts"], report["timings"]
    print(f"{report['method']}: {counts['patches']} patches, {counts['elements']} elements,"
          f" {timings['total']:.2f} s ({', '.join(f'{k} {v:.2f}' for k, v in timings.items() if k != 'total')})")
    return 0


def write_report(report: dict, path: str | None) -> None:
    if path:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(json.dumps(report, indent=2))


def command_bake(args) -> int:
    try:
        import bpy  # noqa: F401  (the Blender module; only this command needs it)
    except ImportError:
        raise SolveError("the bake command needs the Blender Python module: pip install bpy==5.0.1"
                         " (Python 3.11), or run it inside Blender (see the README)") from None
    from .blender.headless import bake_file

    progress = print_progress(args.quiet)
    summary, report = bake_file(args.file, settings_from_args(args), objects=args.objects, output_dir=args.output_dir,
                        save_as=args.save_as, preview=args.preview, texel_density=args.texel_density,
                        max_resolution=args.max_lightmap_size, preview_size=args.preview_size,
                        patch_size=args.patch_size,
                        progress=(lambda p: progress(p.fraction, p.message, {})) if progress else None)
    PROGRESS.end()
    write_report(report, args.report)
    print(summary)
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
    images = solve_parser.add_argument_group("lightmaps and preview")
    images.add_argument("--lightmaps", metavar="DIR",
                        help="write each object's lightmap as DIR/<object>_lightmap.npy: float32 (H, W, 4)"
                             " linear radiance, alpha = coverage, row 0 at v = 0")
    images.add_argument("--texel-density", type=float, default=TEXEL_DENSITY, metavar="D",
                        help=f"lightmap texels per scene unit (default {TEXEL_DENSITY:g})")
    images.add_argument("--max-lightmap-size", type=int, default=MAX_SIZE, metavar="N",
                        help=f"cap on a lightmap's width and height (default {MAX_SIZE})")
    images.add_argument("--preview", metavar="OUT.png",
                        help="render the scene with its lightmaps from its camera into a PNG")
    images.add_argument("--preview-size", type=int, default=512, metavar="N",
                        help="preview width and height in pixels (default 512)")
    images.add_argument("--exposure", type=float, default=None,
                        help="preview exposure (default: lit surfaces just reach white, emitters clip)")
    solve_parser.set_defaults(handler=command_solve)

    bake_parser = commands.add_parser("bake", help="bake the mesh objects of a .blend file (needs the bpy module)")
    bake_parser.add_argument("file", metavar="FILE.blend")
    bake_parser.add_argument("--objects", metavar="A,B", help="objects to bake (default: every visible mesh)")
    bake_parser.add_argument("--output-dir", metavar="DIR", help="write DIR/<object>_lightmap.exr")
    bake_parser.add_argument("--save-as", metavar="OUT.blend",
                             help="save the file with the lightmaps applied (packed unless --output-dir)")
    bake_parser.add_argument("--preview", metavar="OUT.png",
                             help="render the baked file from its camera (Cycles, CPU, a few samples)")
    bake_parser.add_argument("--patch-size", type=float, metavar="S",
                             help="split faces into patches about S metres across, small faces staying whole"
                                  " (instead of --subdiv's N x N for every face)")
    bake_parser.add_argument("--preview-size", type=int, default=256, metavar="N",
                             help="longer side of the preview in pixels, at most the file's render size"
                                  " (default 256)")
    bake_parser.add_argument("--texel-density", type=float, metavar="D",
                             help="lightmap texels per metre (default: the file's setting, 64)")
    bake_parser.add_argument("--report", metavar="REPORT.json", help="write the solve's timings/effects report")
    bake_parser.add_argument("--max-lightmap-size", type=int, metavar="PX", help="largest lightmap side")
    add_solver_options(bake_parser)
    bake_parser.add_argument("--quiet", action="store_true", help="no progress line")
    bake_parser.set_defaults(handler=command_bake)

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
    except Exception as error:
        if not isinstance(error, user_errors()):
            raise
        PROGRESS.end()
        print(f"error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        PROGRESS.end()
        print("error: interrupted", file=sys.stderr)
        return 130
