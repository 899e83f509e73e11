"""Measurements of the benchmark's furnished rooms (bench/rooms.py) for a report:
the room family (triangle target -> real triangles, build time), the add-on's bake of one room by
both methods at the file's (default) settings, and Cycles' reference of it at two sample counts,
compared on the same texels (bench/compare.py).

    .venv/bin/python tools/measure_rooms.py --output-dir out/rooms [--triangles 4000] [--samples 64 1024]

Writes DIR/rooms.json; Cycles bakes are cached in DIR/cache, so a rerun only bakes what is new.
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

from bench import blend_lightmaps, blend_reference, compare, rooms  # noqa: E402
from radiosity_addon.blender.headless import HeadlessBake, bake_file  # noqa: E402

FAMILY = (1000, 2000, 4000, 8000, 16000, 32000, 64000, 100000)


def log(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def summary_of(result: dict) -> dict:
    worst, error = result["worst_object"]
    return {"texel_rms": result["texel_rms"], "texel_rms_inside": result["texel_rms_inside"],
            "worst_object": worst, "worst_object_error": error,
            "objects": {name: {"mean_error": e["relative_rgb"], "rms": e["rms"]} for name, e in result["objects"].items()}}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output-dir", type=Path, required=True)
    parser.add_argument("--triangles", type=int, default=4000, help="the room baked and compared")
    parser.add_argument("--samples", type=int, nargs="+", default=[64, 1024], help="Cycles samples; the last is the reference")
    parser.add_argument("--methods", nargs="+", default=["hemicube", "progressive"])
    args = parser.parse_args()
    out = args.output_dir
    record: dict = {"machine": {"cpus": os.cpu_count(), "load_average_at_start": os.getloadavg()}, "family": []}
    for target in FAMILY:
        built = rooms.build_room(target)
        record["family"].append({key: built[key] for key in ("triangles_target", "triangles", "objects", "seconds")})
        log(f"room {target}: {built['triangles']} triangles in {built['seconds']:.2f} s")
    path = out / f"room_{args.triangles}.blend"
    rooms.save_room(path, args.triangles)

    lightmaps, bakes = {}, {}
    for method in args.methods:
        started = time.perf_counter()
        _, report = bake_file(HeadlessBake(str(path), solve_options={"method": method},
                                           output_dir=str(out / f"lightmaps_{method}")))
        bakes[method] = {"seconds": time.perf_counter() - started, "solve_seconds": report["timings"]["total"],
                         "patches": report["counts"]["patches"], "elements": report["counts"]["elements"],
                         "shots": report.get("shots"), "load_average": os.getloadavg()}
        log(f"{method}: {bakes[method]}")
        names = [obj.name for obj in bpy.context.scene.objects if obj.type == "MESH"]
        lightmaps[method] = blend_lightmaps.read_lightmaps(out / f"lightmaps_{method}", names)
    record["bakes"] = bakes
    sizes = blend_lightmaps.sizes_of(lightmaps[args.methods[0]])
    record["texels"] = sum(w * h for w, h in sizes.values())

    cycles = {}
    for samples in args.samples:
        # the reference's samples in its two seeds, the rows' in the seed they are compared in
        for seed in blend_reference.REFERENCE_SEEDS if samples == args.samples[-1] else (blend_reference.ROW_SEED,):
            bake = blend_reference.cycles_lightmaps(path, sizes, "combined", samples, seed, out / "cache")
            cycles[f"{samples} seed {seed}"] = {"seconds": bake["seconds"], "cached": bake["cached"],
                                                "load_average": os.getloadavg()}
            log(f"Cycles {samples} samples, seed {seed}: {bake['seconds']:.1f} s (cached: {bake['cached']})")
    light = blend_reference.cycles_lightmaps(path, sizes, "light", args.samples[0], 1, out / "cache")
    cycles[f"light {args.samples[0]} seed 1"] = {"seconds": light["seconds"], "cached": light["cached"]}
    record["cycles"] = cycles

    reference = blend_reference.reference_with_noise(path, sizes, "combined", args.samples[-1], cache_dir=out / "cache")
    positions, areas = blend_lightmaps.texel_geometry(sizes)
    inside = blend_lightmaps.inside_room(positions)
    texels = compare.common_texels(reference["images"], reference["images"])
    within = compare.common_texels(reference["images"], reference["images"], inside)
    record["reference"] = {"samples_per_seed": args.samples[-1],
                           "noise": compare.relative_noise(reference["noise"], reference["images"], texels),
                           "noise_inside": compare.relative_noise(reference["noise"], reference["images"], within)}
    compared = {method: lightmaps[method] for method in args.methods}
    for samples in args.samples[:-1]:
        compared[f"Cycles {samples}"] = blend_reference.cycles_lightmaps(path, sizes, "combined", samples,
                                                                         blend_reference.ROW_SEED, out / "cache")["images"]
    record["comparisons"] = {}
    for name, images in compared.items():
        record["comparisons"][name] = {
            "by texel count": summary_of(compare.compare(images, reference["images"], inside)),
            "by area": summary_of(compare.compare(images, reference["images"], inside, areas))}
        log(f"{name} against the reference: {record['comparisons'][name]['by texel count']['texel_rms']:.3f}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "rooms.json").write_text(json.dumps(record, indent=1, default=float))
    log(f"wrote {out / 'rooms.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
