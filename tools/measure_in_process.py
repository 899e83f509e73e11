"""Settings against Cycles on a .blend in a second or two a run: the solve and the lightmaps run in
this process on the job the add-on's bake hands its solver, so a sweep of knobs costs no Blender
round trip, no solver process start and no image writing per run. For finding where the error
and the time go; the README's tables are measured whole, with tools/measure_presets.py.

    .venv/bin/python tools/measure_in_process.py FILE.blend --output-dir out/in-process \\
        --runs '{"quality": "draft"}' '{"quality": "draft", "hemicube_res": 32, "refinements": 3}' \\
        [--reference 512] [--repeat 2]

The file gets a 'Lightmap' UV map where it lacks one (as in measure_presets.py; the copy in
DIR). Its job (scene, material maps, lightmap settings: the solver process's input,
solver_process/protocol.py) is written once as the add-on's bake would (tools/measure_gpu.py's
`export_job`, into DIR/job); each run then is `core.solve` +
the lightmap images with the run's preset and overrides ("lightmaps": {...} for the lightmap
settings), compared texel by texel with Cycles' reference (bench/blend_reference.py, cached in
DIR/cache: the same cache measure_presets.py fills for the same DIR). Each line gives the solve's
and the lightmaps' seconds (the best of `--repeat`), the solve's stage timings, the texel RMS and
every object's mean error and texel RMS. Shader compilation is cached by the driver after the first run.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import bpy  # noqa: E402,F401  (the reference bakes with Cycles)

from radiosity_addon import core  # noqa: E402
from bench import blend_lightmaps, blend_reference, compare, pictures  # noqa: E402
from radiosity_addon.core.settings import QUALITY_PRESETS  # noqa: E402
from radiosity_addon.solver_process import protocol  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measure_gpu import export_job, solve_job  # noqa: E402
from measure_presets import label_of, log, with_lightmap_uvs  # noqa: E402


def lightmap_sizes(job) -> dict:
    """{object: (width, height)} of the job's lightmaps: the texels the reference is baked at."""
    scene, _, lightmap_settings, objects, _ = job
    return core.lightmap_sizes(scene, lightmap_settings, objects)


def run_once(job, run: dict):
    """(solution, {object: image}, solve seconds, lightmap seconds) of one run on the job."""
    scene, _, lightmap_settings, objects, _ = job
    overrides = {key: value for key, value in run.items() if key != "lightmaps"}
    quality = overrides.pop("quality", "good")
    settings = core.SolveSettings.preset(quality, **overrides)
    # the preset's lightmap knobs, but the job's texel density (resolved: an automatic one follows
    # the preset's budget): the texels the reference is baked at
    knobs = {key: value for key, value in QUALITY_PRESETS[quality]["lightmaps"].items() if key != "texel_density"}
    density = core.chosen_texel_density(scene, lightmap_settings, objects)
    lightmaps = dataclasses.replace(lightmap_settings, content="combined", quality=quality, texel_density=density,
                                    **(knobs | run.get("lightmaps", {})))
    solved = solve_job(scene, settings, lightmaps, objects)
    return solved["solution"], solved["images"], solved["solve"], solved["lightmaps"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file", type=Path)
    parser.add_argument("--output-dir", type=Path, required=True)
    parser.add_argument("--runs", nargs="+", default=['{"quality": "draft"}', '{"quality": "good"}', '{"quality": "final"}'])
    parser.add_argument("--reference", type=int, default=512, help="Cycles samples per seed of the reference (two seeds)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each setting; the fastest is reported")
    parser.add_argument("--pictures", action="store_true",
                        help="write each run's lightmaps beside the reference's into DIR/pictures (bench/pictures.py)")
    args = parser.parse_args()
    out = args.output_dir
    out.mkdir(parents=True, exist_ok=True)
    path, is_room = with_lightmap_uvs(args.file, out / args.file.name)
    export_job(path, {}, out / "job")
    job = protocol.read_job(out / "job")
    sizes = lightmap_sizes(job)
    reference = blend_reference.reference_with_noise(path, sizes, "combined", args.reference, cache_dir=out / "cache")
    inside = None
    if is_room:
        positions, _ = blend_lightmaps.texel_geometry(sizes)
        inside = blend_lightmaps.inside_room(positions)
    log(f"job written; reference Cycles {args.reference} samples x 2 seeds")
    for text in args.runs:
        run = json.loads(text)
        results = [run_once(job, run) for _ in range(max(1, args.repeat))]
        solution, images, _, _ = results[-1]
        solve_seconds = min(r[2] for r in results)
        lightmap_seconds = min(r[3] for r in results)
        result = compare.compare(images, reference["images"], inside, noise=reference["noise"])
        if args.pictures:
            prefix = label_of(run).replace("=", "-").replace(" ", "_") + "_"
            pictures.write_pictures(out / "pictures", prefix, images, reference["images"])
        objects = " ".join(f"{name} {100 * entry['relative_rgb']:+.1f}/{100 * entry['rms']:.1f}"
                           for name, entry in result["objects"].items())
        stages = " ".join(f"{name} {seconds:.2f}" for name, seconds in solution.report.timings.items() if seconds >= 0.005)
        print(f"{label_of(run)}: {solution.report.method}, {len(solution.patches)} patches; solve {solve_seconds:.2f} s"
              f" + lightmaps {lightmap_seconds:.2f} s; texel RMS {100 * result['texel_rms']:.2f} %; object-balanced"
              f" {100 * result['balanced_rms']:.2f} %, its noise out {100 * result['balanced_bias']:.2f} %"
              f"\n    objects (mean/RMS, %): {objects}\n    stages (s, last run): {stages}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
