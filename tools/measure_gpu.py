"""The presets' solves on another machine (a GPU), compared with the same solves here and with
Cycles' reference: what the README's "On a GPU" rows are measured with.

A machine lent for a few minutes has no Blender, so the work is cut where the add-on cuts it
already, at the solver process's job folder (export and write-back stay here):

    # here, with bpy: export one job folder per file and run (the bake's own export)
    .venv/bin/python tools/measure_gpu.py export FILE.blend --jobs DIR --uv-copy-dir PRESETS_DIR \\
        --reference 512 --runs '{"quality": "good"}' ...
    # anywhere with numpy + moderngl (no bpy): solve every job folder, as the solver process does,
    # `--repeat` times each (the first pays for compiling shaders); images and timings into OUT
    python tools/measure_gpu.py solve DIR --output OUT [--repeat 2]
    # here, with bpy: each OUT's images against Cycles' cached reference (tools/measure_presets.py's)
    .venv/bin/python tools/measure_gpu.py compare DIR OUT [OUT2 ...]

`export` bakes nothing: it runs the bake's `prepare` (UV maps, export, material probes) on the
file with 'Lightmap' UVs that measure_presets.py made in PRESETS_DIR (so the texels are those of
the reference cached in PRESETS_DIR/cache), writes the job folder and rolls back. `solve` times what the solver process does between reading its job
and writing its result: the solve and the lightmap stage, in one OpenGL context per job.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

META_FILE = "measure.json"  # beside the job's own files: which file and run it is


def export_job(path: Path, run: dict, directory: Path) -> None:
    """Write the job folder the add-on's bake of `path` (with `run`'s settings, content combined)
    would hand its solver process into `directory`: the bake's `prepare` (UV maps, export,
    material probes), then a rollback; nothing is baked."""
    import bpy

    from radiosity_addon.blender import bake
    from radiosity_addon.blender.headless import chosen_objects, ensure_registered
    from radiosity_addon.solver_process import protocol

    bpy.ops.wm.open_mainfile(filepath=str(path.resolve()), load_ui=False)
    ensure_registered()
    objects = chosen_objects(None)  # as a headless bake chooses
    solve = {key: value for key, value in run.items() if key != "lightmaps"}
    options = bpy.context.scene.radiosity.bake_options(objects).overridden(
        solve, {**run.get("lightmaps", {}), "content": "combined"})
    plan = bake.prepare(bpy.context, options, objects=objects, output_dir=directory.parent / "unused")
    try:
        directory.mkdir(parents=True, exist_ok=True)
        worker = plan.worker
        protocol.write_job(directory, worker.scene, worker.settings, worker.lightmaps, worker.objects, None)
    finally:
        bake.rollback(plan)


def export(args) -> int:
    from measure_presets import label_of, with_lightmap_uvs

    path, is_room = with_lightmap_uvs(args.file, args.uv_copy_dir / args.file.name)
    for k, text in enumerate(args.runs):
        run = json.loads(text)
        directory = args.jobs / f"{args.file.stem}-{k}"
        export_job(path, run, directory)
        (directory / META_FILE).write_text(json.dumps({
            "file": str(path), "label": label_of(run), "run": run, "room": is_room,
            "reference": args.reference, "cache": str(args.uv_copy_dir / "cache")}))
        print(f"{directory}: {label_of(run)}")
    return 0


def solve_job(scene, solve_settings, lightmap_settings, objects) -> dict:
    """What the solver process does with a job, in an OpenGL context of its own: {"solution",
    "images" (object: (H, W, 4)), "renderer", "solve" and "lightmaps" (seconds, context excluded)}."""
    from radiosity_addon import core
    from radiosity_addon.solver_process import child

    with core.open_gpu() as gpu:
        opened = time.perf_counter()
        solution = core.solve(scene, solve_settings, gpu=gpu)
        solved = time.perf_counter()
        images = child.lightmap_images(scene, solution, objects, lightmap_settings, gpu)
        ended = time.perf_counter()
        renderer = gpu.ctx.info["GL_RENDERER"]
    return {"solution": solution, "images": images, "renderer": renderer, "solve": solved - opened,
            "lightmaps": ended - solved}


def solve(args) -> int:
    from radiosity_addon.solver_process import protocol

    args.output.mkdir(parents=True, exist_ok=True)
    record = {"machine": {"node": platform.node(), "cpus": __import__("os").cpu_count(),
                          "python": platform.python_version(), "numpy": np.__version__}, "jobs": {}}
    for directory in sorted(path.parent for path in args.jobs.glob(f"*/{META_FILE}")):
        times = []
        for _ in range(args.repeat):
            started = time.perf_counter()
            scene, solve_settings, lightmap_settings, objects, _ = protocol.read_job(directory)
            solved = solve_job(scene, solve_settings, lightmap_settings, objects)
            ended = time.perf_counter()
            solution, images = solved["solution"], solved["images"]
            record["machine"]["renderer"] = solved["renderer"]
            times.append({"seconds": ended - started, "solve": solved["solve"], "lightmaps": solved["lightmaps"],
                          "stages": {key: float(value) for key, value in solution.report.timings.items()},
                          "method": solution.report.method, "patches": int(solution.report.counts.patches)})
            print(f"{directory.name}: {times[-1]['seconds']:.2f} s (solve {times[-1]['solve']:.2f} s,"
                  f" lightmaps {times[-1]['lightmaps']:.2f} s)", flush=True)
        # half floats, compressed: a room's lightmaps come back in a few MB
        np.savez_compressed(args.output / f"{directory.name}.npz", names=json.dumps(list(images)),
                            **{f"image_{i}": images[name].astype(np.float16) for i, name in enumerate(images)})
        record["jobs"][directory.name] = times
        # after every job: a run stopped at its time limit keeps what it measured
        (args.output / "timings.json").write_text(json.dumps(record, indent=1))
    return 0


def compare_results(args) -> int:
    import bpy

    from bench import blend_lightmaps, blend_reference, compare

    results = [(out, json.loads((out / "timings.json").read_text())) for out in args.outputs]
    print("| job | run | " + " | ".join(f"{record['machine']['renderer'][:40]}: s (solve + lightmaps) / texel RMS"
                                        for _, record in results) + " |")
    print("|---|---|" + "---:|" * len(results))
    for directory in sorted(path.parent for path in args.jobs.glob(f"*/{META_FILE}")):
        meta = json.loads((directory / META_FILE).read_text())
        cells = []
        for out, record in results:
            with np.load(out / f"{directory.name}.npz") as stored:
                names = json.loads(str(stored["names"]))
                images = {name: stored[f"image_{i}"].astype(np.float32) for i, name in enumerate(names)}
            sizes = blend_lightmaps.sizes_of(images)
            reference = blend_reference.reference_with_noise(meta["file"], sizes, "combined", meta["reference"],
                                                             cache_dir=meta["cache"])
            inside = None
            if meta["room"]:  # the texels' positions, from the file's meshes
                bpy.ops.wm.open_mainfile(filepath=meta["file"], load_ui=False)
                inside = blend_lightmaps.inside_room(blend_lightmaps.texel_geometry(sizes)[0])
            result = compare.compare(images, reference["images"], inside)
            seconds = min(run["seconds"] for run in record["jobs"][directory.name])
            cells.append(f"{seconds:.2f} s / {100 * result['texel_rms']:.1f} %"
                         + (f" ({100 * result['texel_rms_inside']:.1f} % inside)" if inside else ""))
        print(f"| {directory.name} | {meta['label']} | " + " | ".join(cells) + " |", flush=True)
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    exporting = commands.add_parser("export", help="job folders of FILE's runs (needs bpy)")
    exporting.add_argument("file", type=Path)
    exporting.add_argument("--jobs", type=Path, required=True)
    exporting.add_argument("--uv-copy-dir", type=Path, required=True,
                           help="measure_presets.py's --output-dir for FILE (its copy with Lightmap UVs)")
    exporting.add_argument("--runs", nargs="+", required=True, help="JSON objects as measure_presets.py's")
    exporting.add_argument("--reference", type=int, required=True,
                           help="Cycles samples per seed of the reference to compare with (measure_presets.py's)")
    solving = commands.add_parser("solve", help="solve every job folder under JOBS (numpy + moderngl only)")
    solving.add_argument("jobs", type=Path)
    solving.add_argument("--output", type=Path, required=True)
    solving.add_argument("--repeat", type=int, default=2)
    comparing = commands.add_parser("compare", help="each output's images against Cycles' reference (needs bpy)")
    comparing.add_argument("jobs", type=Path)
    comparing.add_argument("outputs", type=Path, nargs="+")
    args = parser.parse_args()
    return {"export": export, "solve": solve, "compare": compare_results}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
