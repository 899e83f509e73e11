"""The quality presets (or any settings) against Cycles on a .blend, texel by texel: what the
README's "Quality presets" tables are measured with.

    .venv/bin/python tools/measure_presets.py FILE.blend --output-dir out/presets \\
        --runs '{"quality": "draft"}' '{"quality": "good", "method": "hemicube"}' \\
        [--reference 256] [--cycles 16 64] [--rounds 5]

FILE is baked as its author made it. Meshes without a 'Lightmap' UV map get one first, made by
the add-on's own Lightmap Pack, saved as DIR/<name>.blend: every bake and Cycles' reference use
that copy, so both fill the same texels. Each run is the add-on's headless bake with the file's
settings and the run's replaced (content: combined, B), at the texel density the first run's bake
chose (a file's automatic density differs by preset: one reference compares them all), timed as a whole; the reference is Cycles'
Combined bake at `--reference` samples per seed, two seeds (bench/blend_reference.py, cached in
DIR/cache); `--cycles` adds Cycles' own rows at fewer samples, baked and timed in this run, with a seed
of their own (`blend_reference.ROW_SEED`: not correlated with the reference). With `--rounds N`
every run and every row is baked N times, in turn (ours, then Cycles', N times over), and each
one's median time is reported: this machine's speed drifts by tens of per cent within minutes.
Every bake, ours and Cycles', starts once the solver process our last bake started ahead is
ready (blender/worker.py's spare), as a user's next bake finds it; the session's first bake,
which starts its own, is in the json as "first_bake". The comparison
(bench/compare.py) gives the texel RMS over all texels and over those inside the room (a room of
bench/rooms.py; elsewhere the same), the object-balanced RMS (each object's error relative to its
own brightness, counted by its texels) and that with the reference's noise taken out, and the
worst object's mean. Then, from Cycles' rows of the run (`compare.cycles_to_reach`: samples
interpolated as a power law between the two rows that bracket an error, seconds linear in the
samples), the samples and seconds Cycles needs for each run's texel RMS and for `--target-error`
(5 %), and each run's seconds against half the latter — the Cornell box's target, "the bar" — first
against the reference as it is, then against a converged one (every texel RMS with the reference's
noise taken out); `--reprint` prints them again from DIR/presets.json.
`--pictures` writes each run's lightmaps beside the reference's (bench/pictures.py). `--densities` then times the
first run and Cycles at the first `--cycles` samples at other texel densities. Writes
DIR/presets.json, DIR/presets.md (the table docs/bench/ shows) and DIR/presets.png (error against
time); `--replot` redraws both from the json.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

from bench import blend_lightmaps, blend_reference, compare, foliage, pictures  # noqa: E402
from bench.production import PRODUCTION_PROPERTY  # noqa: E402
from bench.rooms import ROOM_PROPERTY  # noqa: E402
from radiosity_addon.blender import worker  # noqa: E402
from radiosity_addon.blender.headless import HeadlessBake, bake_file, ensure_registered  # noqa: E402
from radiosity_addon.blender.lightmap_uv import add_lightmap_uvs  # noqa: E402


def log(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def canopy_shadow(positions: dict):
    """The floor's texels under the canopy as the sun sees them (bench/foliage.py), where the open
    file is a production terrace with a sun; else None."""
    suns = [obj for obj in bpy.context.scene.objects if obj.type == "LIGHT" and obj.data.type == "SUN"]
    if PRODUCTION_PROPERTY not in bpy.context.scene or not suns or foliage.FLOOR not in positions:
        return None
    towards_sun = np.array(suns[0].matrix_world.to_3x3() @ Vector((0.0, 0.0, 1.0)))
    return foliage.canopy_shadow(positions[foliage.FLOOR], towards_sun / np.linalg.norm(towards_sun))


def with_lightmap_uvs(source: Path, target: Path) -> tuple[Path, bool]:
    """The file with a 'Lightmap' UV map on every mesh (a copy when some lacked one); is it a room?"""
    bpy.ops.wm.open_mainfile(filepath=str(source.resolve()), load_ui=False)
    ensure_registered()
    meshes = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    is_room = ROOM_PROPERTY in bpy.context.scene
    if not add_lightmap_uvs(bpy.context, meshes, bpy.context.scene.radiosity.uv_margin):
        return source, is_room
    target.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(target.resolve()))
    return target, is_room


def label_of(run: dict) -> str:
    return " ".join(f"{key}={value}" for key, value in run.items()) or "file's settings"


def density_sweep(path: Path, run: dict, samples: int, densities: list[float], out: Path) -> list[dict]:
    """Seconds of our bake (`run`) and of Cycles at `samples` per texel density: our texels come
    from the solve's patches (their cost is the lightmap stage's), Cycles' each cost samples."""
    rows = []
    print(f"| texels per unit | texels | {label_of(run)} | Cycles {samples} samples |")
    print("|---:|---:|---:|---:|")
    for density in densities:
        started = time.perf_counter()
        directory = out / f"density{density:g}"
        bake_file(HeadlessBake(str(path), solve_options=run, output_dir=str(directory),
                               lightmap_options={"content": "combined", "texel_density": density}))
        ours = time.perf_counter() - started
        names = [obj.name for obj in bpy.context.scene.objects if obj.type == "MESH"]
        sizes = blend_lightmaps.sizes_of(blend_lightmaps.read_lightmaps(directory, names))
        cycles = blend_reference.cycles_lightmaps(path, sizes, "combined", samples, blend_reference.ROW_SEED,
                                                   out / "cache")["seconds"]
        texels = sum(w * h for w, h in sizes.values())
        rows.append({"texel_density": density, "texels": texels, "ours_seconds": ours, "cycles_seconds": cycles})
        print(f"| {density:g} | {texels} | {ours:.1f} s | {cycles:.1f} s |", flush=True)
    return rows


METRICS = (("texel_rms", "texel relative RMS against Cycles' reference, %"),
           ("balanced_bias", "object-balanced RMS, its noise out, %"))


def plot(path: Path, record: dict) -> None:
    """Error against the bake's seconds, one panel per metric (compare.py: the texel RMS, which a
    scene's brightest texels decide, and the object-balanced RMS without the reference's noise):
    our runs as points, Cycles' as a line through its sample counts (its error falls as
    1/sqrt(samples), its time grows with them)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    metrics = [(key, label) for key, label in METRICS if all(key in run for run in record["runs"])]
    figure, axes = plt.subplots(1, len(metrics), figsize=(6.0 * len(metrics), 4.4), squeeze=False)
    cycles = sorted((run for run in record["runs"] if run["method"] == "cycles"), key=lambda run: run["seconds"])
    for axis, (key, label) in zip(axes[0], metrics):
        if cycles:
            axis.plot([run["seconds"] for run in cycles], [100 * run[key] for run in cycles], "-.D", color="grey",
                      label="Cycles")
            for run in cycles:
                axis.annotate(run["label"].replace("Cycles ", ""), (run["seconds"], 100 * run[key]), fontsize=7,
                              xytext=(4, 4), textcoords="offset points")
        for run in (run for run in record["runs"] if run["method"] != "cycles"):
            axis.plot(run["seconds"], 100 * run[key], "o", label=f"{run['label']} ({run['method']})")
        axis.set_xscale("log")
        axis.set_yscale("log")
        for ticks in (axis.xaxis, axis.yaxis):  # plain numbers, not powers of ten
            ticks.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda value, _: f"{value:g}"))
            ticks.set_minor_formatter(matplotlib.ticker.FuncFormatter(
                lambda value, _: f"{value:g}" if f"{value:e}"[0] in "235" else ""))
        axis.set_xlabel("seconds, whole bake (2 cores, llvmpipe)")
        axis.set_ylabel(label)
        axis.set_title(Path(record["file"]).name)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def table(record: dict) -> str:
    """DIR/presets.md: one row per run and Cycles row of `record`, what docs/bench/ shows."""
    lines = [f"{Path(record['file']).name}, against Cycles at {record['reference']['samples_per_seed']} samples"
             f" x 2 seeds (its noise {100 * record['reference']['noise']:.1f} %)", "",
             "| run | method | patches | seconds | texel RMS | object-balanced (noise out) | worst object mean"
             " | canopy shadow mean / texel RMS | Cycles to the same error |",
             "|---|---|---:|---:|---:|---:|---|---:|---|"]
    for entry in record["runs"]:
        leaves, same = entry.get("foliage"), entry.get("cycles_to_same_error")
        shadow = "" if leaves is None else \
            f"{100 * (leaves['shadow_mean_ratio'] - 1):+.1f} % / {100 * leaves['pattern_rms']:.1f} %"
        cycles = "" if same is None else f"{same['samples']:.0f} samples, {same['seconds']:.1f} s"
        lines.append(
            f"| {entry['label']} | {entry['method']} | {entry.get('patches') or ''} | {entry['seconds']:.1f} "
            f"| {100 * entry['texel_rms']:.1f} % | {100 * entry['balanced_rms']:.1f} % ({100 * entry['balanced_bias']:.1f} %) "
            f"| {entry['worst_object']} {100 * entry['worst_object_error']:+.0f} % | {shadow} | {cycles} |")
    named = [entry for entry in record["runs"] if "object_rms" in entry]
    if named:  # each object's own texel RMS (and with the reference's noise out), run by run
        objects = sorted({name for entry in named for name in entry["object_rms"]})
        lines += ["", "Each object's texel RMS (with the reference's own noise taken out):", "",
                  "| object | " + " | ".join(entry["label"] for entry in named) + " |", "|---|" + "---:|" * len(named)]
        cell = lambda entry, name: (f"{100 * entry['object_rms'][name]:.1f} %"  # noqa: E731
                                    f" ({100 * entry.get('object_rms_noise_out', {}).get(name, float('nan')):.1f} %)")
        lines += [f"| {name} | " + " | ".join(cell(entry, name) if name in entry["object_rms"] else ""
                                              for entry in named) + " |" for name in objects]
    return "\n".join(lines) + "\n"


def write_results(out: Path, record: dict) -> None:
    (out / "presets.json").write_text(json.dumps(record, indent=1, default=float))
    (out / "presets.md").write_text(table(record))
    plot(out / "presets.png", record)


def print_cycles_equivalents(record: dict, target_error: float) -> None:
    """What Cycles needs to reach each run's texel RMS and `target_error` (`compare.cycles_to_reach`,
    between its rows of this run), and each run's seconds against half the latter: the bar. Then
    the same against a converged reference (the target's words), every texel RMS with the
    reference's noise taken out (`compare.without_reference_noise`)."""
    noise = record["reference"]["noise"]
    cycles = [entry for entry in record["runs"] if entry["method"] == "cycles"]
    ours = [entry for entry in record["runs"] if entry["method"] != "cycles"]
    for suffix, error_of, against in (("", lambda e: e, "its reference"),
                                      ("_noise_out", lambda e: compare.without_reference_noise(e, noise),
                                       f"a converged reference (its noise, {100 * noise:.1f} %, taken out)")):
        rows = [(entry.get("samples") or int(entry["label"].split()[1]), entry["seconds"],
                 error_of(entry["texel_rms"])) for entry in cycles]
        bar = compare.cycles_to_reach(target_error, rows)
        record["bar" + suffix] = None if bar is None else {"target_error": target_error, **bar,
                                                           "half": bar["seconds"] / 2}
        print(f"Against {against}:")
        if bar is not None:
            print(f"  Cycles reaches {100 * target_error:g} % texel RMS at about {bar['samples']:.0f} samples,"
                  f" {bar['seconds']:.2f} s (between its {bar['between'][0]} and {bar['between'][1]} sample"
                  f" rows); half of that, the bar: {bar['seconds'] / 2:.2f} s")
        for entry in ours:
            error = error_of(entry["texel_rms"])
            same = compare.cycles_to_reach(error, rows)
            entry["cycles_to_same_error" + suffix] = same
            to_same = ("outside Cycles' rows" if same is None else
                       f"Cycles needs about {same['samples']:.0f} samples, {same['seconds']:.2f} s:"
                       f" {same['seconds'] / entry['seconds']:.1f} x the time")
            against_bar = "" if bar is None else f"; {entry['seconds'] / (bar['seconds'] / 2):.2f} x the bar"
            print(f"  {entry['label']}: {entry['seconds']:.2f} s for {100 * error:.1f} %; {to_same}{against_bar}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file", type=Path)
    parser.add_argument("--output-dir", type=Path, required=True)
    parser.add_argument("--runs", nargs="+", default=['{"quality": "draft"}', '{"quality": "good"}', '{"quality": "final"}'],
                        help="JSON objects of SolveSettings fields (a 'quality' first sets its preset)")
    parser.add_argument("--reference", type=int, default=256, help="Cycles samples per seed of the reference (two seeds)")
    parser.add_argument("--cycles", type=int, nargs="*", default=[16, 64], help="Cycles' own rows, at these samples")
    parser.add_argument("--rounds", type=int, default=1,
                        help="bake every run and every Cycles row this many times, in turn; report the median")
    parser.add_argument("--densities", type=float, nargs="*", default=[],
                        help="then time the first run and Cycles at the first --cycles samples at these texel"
                             " densities (texels per unit): how each one's cost grows with the lightmaps' texels")
    parser.add_argument("--target-error", type=float, default=0.05,
                        help="texel RMS for the bar: the seconds Cycles needs to reach it, interpolated between its"
                             " rows, and each run's seconds against half of them (the Cornell box's target)")
    parser.add_argument("--pictures", type=Path, metavar="PICTURES_DIR",
                        help="write each run's lightmaps beside the reference's and their difference there"
                             " (bench/pictures.py: PICTURES_DIR/<run>_<object>.png)")
    parser.add_argument("--replot", action="store_true", help="only redraw DIR/presets.png and .md from DIR/presets.json")
    parser.add_argument("--reprint", action="store_true",
                        help="only print the bar and what Cycles needs for each run from DIR/presets.json")
    args = parser.parse_args()
    out = args.output_dir
    if args.replot:
        write_results(out, json.loads((out / "presets.json").read_text()))
        return 0
    if args.reprint:
        print_cycles_equivalents(json.loads((out / "presets.json").read_text()), args.target_error)
        return 0
    out.mkdir(parents=True, exist_ok=True)
    path, is_room = with_lightmap_uvs(args.file, out / args.file.name)
    record: dict = {"file": str(args.file), "baked": str(path), "machine": {"cpus": os.cpu_count()}, "runs": []}

    # every round bakes each run, then each Cycles row: a slower or faster minute of the machine
    # falls on both alike, and the median of the rounds is the time reported (each round's in the json)
    lightmaps, cycles_images, times = {}, {}, {}
    pinned: dict = {}  # the texel density the first run chose (the file's may be automatic, per preset)
    for round_number in range(args.rounds):
        for k, text in enumerate(args.runs):
            run = json.loads(text)
            solve = {key: value for key, value in run.items() if key != "lightmaps"}
            load = os.getloadavg()[0]
            spare = worker.wait_for_spare(60)  # as a user's next bake finds it (worker.py)
            started = time.perf_counter()
            lightmap_options = {**pinned, **run.get("lightmaps", {}), "content": "combined"}
            _, report = bake_file(HeadlessBake(str(path), solve_options=solve, lightmap_options=lightmap_options,
                                               output_dir=str(out / f"run{k}")))
            times.setdefault(("run", k), []).append(time.perf_counter() - started)
            if not pinned:  # every run's texels those of the first: one reference compares them all
                pinned = {"texel_density": report["texel_density"]}
                record["texel_density"] = report["texel_density"]
            if not spare:  # the session's first bake: its solver process started with it
                record["first_bake"] = {"label": label_of(run), "seconds": times[("run", k)][-1]}
            if round_number == 0:
                names = [obj.name for obj in bpy.context.scene.objects if obj.type == "MESH"]
                lightmaps[k] = blend_lightmaps.read_lightmaps(out / f"run{k}", names)
                record["runs"].append({"label": label_of(run), "settings": run, "load_average": load,
                                       "method": report["method"], "patches": report["counts"]["patches"],
                                       "solve_seconds": report["timings"]["total"], "shots": report.get("shots")})
            log(f"{label_of(run)}: {report['method']}, {report['counts']['patches']} patches, "
                f"{times[('run', k)][-1]:.1f} s")
        if round_number == 0:
            sizes = blend_lightmaps.sizes_of(lightmaps[0])
        for samples in args.cycles:
            # never from the cache: a row's seconds must be measured in this run, beside ours;
            # not while our spare still starts (it would take CPU from Cycles)
            worker.wait_for_spare(60)
            bake = blend_reference.cycles_lightmaps(path, sizes, "combined", samples, blend_reference.ROW_SEED)
            times.setdefault(("cycles", samples), []).append(bake["seconds"])
            cycles_images.setdefault(samples, bake["images"])
            log(f"Cycles {samples} samples: {bake['seconds']:.1f} s")
    for k, entry in enumerate(record["runs"]):
        entry.update(seconds=float(np.median(times[("run", k)])), rounds=times[("run", k)])

    reference = blend_reference.reference_with_noise(path, sizes, "combined", args.reference, cache_dir=out / "cache")
    positions, _ = blend_lightmaps.texel_geometry(sizes)
    inside = blend_lightmaps.inside_room(positions) if is_room else None
    texels = compare.common_texels(reference["images"], reference["images"], inside)
    record["reference"] = {"samples_per_seed": args.reference,
                           "noise": compare.relative_noise(reference["noise"], reference["images"], texels),
                           "balanced_noise": compare.object_balanced_rms(  # of the noise itself: ours = ref + noise
                               {k: v + reference["noise"][k] for k, v in reference["images"].items()},
                               reference["images"], compare.common_texels(reference["images"], reference["images"]))}
    rows = [(entry, lightmaps[k]) for k, entry in enumerate(record["runs"])]
    object_noise = {name: compare.relative_noise(reference["noise"], reference["images"], {name: mask}) for name, mask
                    in compare.common_texels(reference["images"], reference["images"]).items() if mask.any()}
    for samples in args.cycles:
        seconds = times[("cycles", samples)]
        entry = {"label": f"Cycles {samples} samples", "seconds": float(np.median(seconds)), "rounds": seconds,
                 "method": "cycles", "samples": samples}
        record["runs"].append(entry)
        rows.append((entry, cycles_images[samples]))
    print(f"reference: Cycles {args.reference} samples x 2 seeds, noise {100 * record['reference']['noise']:.1f} %"
          f" (object-balanced {100 * record['reference']['balanced_noise']:.1f} %)")
    if "first_bake" in record:
        print(f"the session's first bake ({record['first_bake']['label']}, its solver process started with it):"
              f" {record['first_bake']['seconds']:.2f} s")
    print("| run | method | patches | seconds | texel RMS all / inside | object-balanced (noise out) | worst object mean |")
    print("|---|---|---:|---:|---:|---:|---|")
    for entry, images in rows:
        result = compare.compare(images, reference["images"], inside, noise=reference["noise"])
        worst, error = result["worst_object"]
        entry.update(texel_rms=result["texel_rms"], texel_rms_inside=result.get("texel_rms_inside", result["texel_rms"]),
                     balanced_rms=result["balanced_rms"], balanced_bias=result["balanced_bias"],
                     worst_object=worst, worst_object_error=error,
                     objects={name: e["relative_rgb"] for name, e in result["objects"].items()},
                     object_rms={name: e["rms"] for name, e in result["objects"].items()},
                     object_rms_noise_out={name: compare.without_reference_noise(e["rms"], object_noise.get(name, 0.0))
                                           for name, e in result["objects"].items()})
        print(f"| {entry['label']} | {entry['method']} | {entry.get('patches', '')} | {entry['seconds']:.1f} "
              f"| {100 * entry['texel_rms']:.1f} % / {100 * entry['texel_rms_inside']:.1f} % "
              f"| {100 * entry['balanced_rms']:.1f} % ({100 * entry['balanced_bias']:.1f} %) | {worst} {100 * error:+.0f} % |", flush=True)
    if args.pictures is not None:
        for entry, images in rows:
            if entry["method"] != "cycles":
                prefix = "".join(c if c.isalnum() else "-" for c in entry["label"].split("=")[-1]) + "_"
                pictures.write_pictures(args.pictures, prefix, images, reference["images"])
    shadow = canopy_shadow(positions)
    if shadow is not None:  # the production terrace: the dappled floor under the canopy
        for entry, images in rows:
            entry["foliage"] = foliage.foliage_numbers(images[foliage.FLOOR], reference["images"][foliage.FLOOR], shadow)
            print(f"foliage, {entry['label']}: the canopy's shadow on the floor ({entry['foliage']['texels']} texels)"
                  f" {100 * (entry['foliage']['shadow_mean_ratio'] - 1):+.1f} % in its mean,"
                  f" {100 * entry['foliage']['pattern_rms']:.1f} % texel RMS")
    print_cycles_equivalents(record, args.target_error)
    if args.densities:
        record["densities"] = density_sweep(path, json.loads(args.runs[0]), args.cycles[0], args.densities, out)
    write_results(out, record)
    log(f"wrote {out / 'presets.json'}, presets.md and presets.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
