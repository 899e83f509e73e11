"""Command line: `python -m radiosity_addon {solve,bake} ...` (docs/architecture.md, Interfaces).

Errors a user can cause end in one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import os
import json
import sys
import time
from pathlib import Path

from . import core
from .core import (CONTENTS, DEFAULT_QUALITY, KERNELS, MAX_LIGHTMAP_SIZE, METHODS, QUALITIES, SHOOTING_POINTS, SOLVERS, TEXEL_DENSITY,
                   VISIBILITY_VARIANTS)
from .core import LightmapSettings, SolveError, SolveSettings


def user_errors() -> tuple:
    """The core's USER_ERRORS plus the Blender side's BakeError once that side is loaded (it needs bpy)."""
    blender_errors = sys.modules.get(f"{__package__}.blender.errors")
    return core.USER_ERRORS + ((blender_errors.BakeError,) if blender_errors else ())


# (flags, SolveSettings field, argparse keywords, help); the defaults come from the --quality preset
SOLVER_OPTIONS = [
    ("--method", "method", {"choices": METHODS},
     "auto (the method the cost model predicts faster; the report says why), progressive refinement or the"
     " hemi-cube method"),
    ("--patch-size", "patch_size", {"type": float, "metavar": "S"},
     "split surfaces into patches about S scene units (metres) across, small ones staying whole"),
    ("--subdiv", "subdiv", {"type": int, "metavar": "N"},
     "split every surface N x N into patches instead, however big or small"),
    ("--elements", "elements", {"type": int, "metavar": "S"}, "S x S elements per patch, a power of two (progressive)"),
    ("--hemicube-res", "hemicube_res", {"type": int, "metavar": "R"}, "hemi-cube top-face resolution in pixels"),
    ("--solver", "solver", {"choices": SOLVERS}, "linear solver of the hemi-cube method"),
    ("--tolerance", "tolerance", {"type": float, "metavar": "T"},
     "hemicube: max change relative to max B; progressive: unshot power relative to emitted power"
     " (not given: the quality's, 1e-5 and 1e-2 for good)"),
    ("--max-iterations", "max_iterations", {"type": int}, "iteration cap of the linear solvers"),
    ("--max-shots", "max_shots", {"type": int}, "shot budget of the progressive method"),
    ("--visibility-res", "visibility_res", {"type": int, "metavar": "R"},
     "pixels across the progressive visibility map"),
    ("--shooter-clusters", "shooter_clusters", {"type": int, "metavar": "C"},
     "progressive: with more patches than C, weak light shoots from about C clusters of patches (0: never)"),
]


# the variants the benchmark compared and the presets do not use (docs/benchmarks.md): offered
# only with RADIOSITY_DEVELOPER=1 in the environment, never to users
RESEARCH_OPTIONS = [
    ("--visibility", "visibility", {"choices": VISIBILITY_VARIANTS},
     "progressive visibility variant: plain projection, tessellated, tessellated with neighbour search, or"
     " search guarded against peeking past occluders"),
    ("--shoot-from", "shoot_from", {"choices": SHOOTING_POINTS},
     "progressive: render each shooter's visibility map from the centroid of its unshot power or its centre"),
    ("--complete-remainder", "complete_remainder", {"action": argparse.BooleanOptionalAction},
     "progressive: add the light the power still unshot at the stop would deliver"),
    ("--kernel", "kernel", {"choices": KERNELS},
     "progressive form-factor kernel: exact point-to-polygon or the disk approximation"),
]
DEVELOPER_SWITCH = "RADIOSITY_DEVELOPER"


def solver_options() -> list:
    """The solver options offered: the research variants too where RADIOSITY_DEVELOPER asks."""
    developer = os.environ.get(DEVELOPER_SWITCH, "") not in ("", "0")
    return SOLVER_OPTIONS + (RESEARCH_OPTIONS if developer else [])


def add_solver_options(parser: argparse.ArgumentParser, defaults_from_file: bool = False) -> None:
    """The solver options. An option not given takes the --quality preset's value (`solve`), or
    (`bake`, with `defaults_from_file`) leaves the .blend's own setting in place: either way it is
    left out of the parsed arguments."""
    defaults = SolveSettings()
    group = parser.add_argument_group("solver")
    group.add_argument("--quality", choices=QUALITIES, default=argparse.SUPPRESS if defaults_from_file else DEFAULT_QUALITY,
                       help="what every knob below defaults to: draft (fast), good, final (the README's"
                            " 'What accuracy costs' gives each one's measured error and time)"
                            + (" (default: the file's setting)" if defaults_from_file else f" (default {DEFAULT_QUALITY})"))
    for flag, field, keywords, text in solver_options():
        default = getattr(defaults, field)
        keywords = {**keywords, "default": argparse.SUPPRESS}
        if defaults_from_file:
            text += " (default: the file's setting)"
        elif default is not None and field != "tolerance":
            shown = f"{default:g}" if isinstance(default, float) else f"{default}"
            text += f" (default: the quality's; {DEFAULT_QUALITY}: {shown})"
        group.add_argument(flag, dest=field, help=text, **keywords)
    group.add_argument("--no-skips", dest="skip_unneeded", action="store_false",
                       default=argparse.SUPPRESS if defaults_from_file else True,
                       help="simulate every effect even when the scene analysis shows it is absent")


def given_solver_options(args) -> dict:
    """SolveSettings fields given on the command line, and the quality."""
    fields = ["quality"] + [field for _, field, _, _ in solver_options()] + ["skip_unneeded"]
    given = {field: getattr(args, field) for field in fields if hasattr(args, field)}
    if given.get("subdiv") is None and "patch_size" in given:
        given["subdiv"] = None  # --patch-size chooses the size mode
    return given


def settings_from_args(args) -> SolveSettings:
    given = given_solver_options(args)
    return SolveSettings.preset(given.pop("quality", DEFAULT_QUALITY), **given)


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
    if args.texel_density is not None and not args.texel_density >= 0:
        raise SolveError(f"--texel-density must be positive (or 0: automatic), got {args.texel_density}")
    if args.preview and args.preview_size < 8:
        raise SolveError(f"--preview-size must be at least 8 pixels, got {args.preview_size}")
    if args.exposure is not None and not args.exposure > 0:
        raise SolveError(f"--exposure must be positive, got {args.exposure}")


def write_lightmaps_and_preview(args, scene, solution, gpu) -> None:
    """`solve --lightmaps DIR` / `--preview OUT.png`: bake the lightmaps, write them and the picture."""
    import numpy as np

    settings = LightmapSettings.preset(args.quality, texel_density=args.texel_density,
                                       max_size=args.max_lightmap_size, content=args.content)
    lightmaps = core.bake_lightmaps(scene, solution, settings, gpu=gpu)
    if args.lightmaps:
        directory = Path(args.lightmaps)
        directory.mkdir(parents=True, exist_ok=True)
        for name, lightmap in lightmaps.items():
            np.save(directory / f"{safe_file_name(name)}_lightmap.npy", lightmap.rgba)
        sizes = ", ".join(f"{name} {lm.size[0]}x{lm.size[1]}" for name, lm in lightmaps.items())
        density = core.chosen_texel_density(scene, settings)
        print(f"lightmaps ({density:.0f} texels/unit{' (automatic)' if settings.texel_density == 0 else ''}):"
              f" {sizes} -> {directory}/")
    if args.preview:
        preview = core.render_preview(scene, lightmaps, width=args.preview_size, height=args.preview_size, gpu=gpu)
        exposure = core.save_preview(args.preview, scene, preview, exposure=args.exposure)
        print(f"preview (exposure {exposure:.3g}) -> {args.preview}")


def safe_file_name(name: str) -> str:
    """An object name usable as a file name (path separators and the like become '_')."""
    return "".join(c if c.isalnum() or c in "-_. " else "_" for c in name).strip() or "object"


def command_solve(args) -> int:
    import numpy as np

    scene = core.load_scene(args.scene)
    settings = settings_from_args(args)
    wants_images = bool(args.lightmaps or args.preview)
    if wants_images:
        check_image_options(args)
    with core.open_gpu() as gpu:
        solution = core.solve(scene, settings, progress=print_progress(args.quiet), gpu=gpu)
        PROGRESS.end()
        if wants_images:
            write_lightmaps_and_preview(args, scene, solution, gpu)
    report = solution.report.to_dict()
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
    import importlib.util

    if importlib.util.find_spec("bpy") is None:  # the Blender module: only this command needs it
        raise SolveError("the bake command needs the Blender Python module: pip install bpy==5.0.1"
                         " (Python 3.11), or run it inside Blender (see the README)") from None
    from .blender.headless import HeadlessBake, bake_file
    from .blender.worker import keep_spare

    keep_spare(False)  # one bake, then the process ends: no solver process started ahead for a next
    progress = print_progress(args.quiet)
    lightmap_options = {field: getattr(args, field) for field in ("texel_density", "max_size", "content")
                        if getattr(args, field, None) is not None}
    request = HeadlessBake(file=args.file, solve_options=given_solver_options(args), lightmap_options=lightmap_options,
                           objects=args.objects, output_dir=args.output_dir, save_as=args.save_as,
                           preview=args.preview, preview_size=args.preview_size)
    summary, report = bake_file(request, progress=(lambda clock: progress(clock.fraction(), clock.stage, {}))
                                if progress else None)
    PROGRESS.end()
    write_report(report, args.report)
    print(summary)
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
    images.add_argument("--texel-density", type=float, default=None, metavar="D",
                        help="lightmap texels per scene unit (default 0: automatic, the quality preset's texel"
                             f" budget spread over the surfaces, at least {TEXEL_DENSITY:g})")
    images.add_argument("--max-lightmap-size", type=int, default=MAX_LIGHTMAP_SIZE, metavar="N",
                        help=f"cap on a lightmap's width and height (default {MAX_LIGHTMAP_SIZE})")
    images.add_argument("--content", choices=CONTENTS, default=LightmapSettings().content,
                        help="what the lightmaps hold: the light arriving (default; B = E + rho x light) or the"
                             " outgoing radiance B")
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
    bake_parser.add_argument("--preview-size", type=int, default=256, metavar="N",
                             help="longer side of the preview in pixels, at most the file's render size"
                                  " (default 256)")
    bake_parser.add_argument("--texel-density", type=float, metavar="D",
                             help="lightmap texels per metre (default: the file's setting; 0, a new file's:"
                                  f" automatic, the quality preset's texel budget over the baked area, at least"
                                  f" {TEXEL_DENSITY:g})")
    bake_parser.add_argument("--content", choices=CONTENTS,
                             help="what the lightmaps hold: the light arriving, shown as emission + Base Color x"
                                  " lightmap (the default of a new file), or combined: the outgoing radiance"
                                  " (default: the file's setting)")
    bake_parser.add_argument("--report", metavar="REPORT.json", help="write the solve's timings/effects report")
    bake_parser.add_argument("--max-lightmap-size", dest="max_size", type=int, metavar="PX",
                             help=f"largest lightmap side (default: the file's setting, {MAX_LIGHTMAP_SIZE} in a new file)")
    add_solver_options(bake_parser, defaults_from_file=True)
    bake_parser.add_argument("--quiet", action="store_true", help="no progress line")
    bake_parser.set_defaults(handler=command_bake)

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
