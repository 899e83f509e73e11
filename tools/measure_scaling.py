"""How each stage of a bake grows with the scene: seconds and peak memory per stage on the
benchmark's furnished rooms (bench/rooms.py) from ~1k to ~100k triangles, or on its
production terrace (bench/production.py: dense meshes, 20 materials in one object, a triangle
soup, alpha-cut leaves, sun and sky) from ~50k to ~500k.

    .venv/bin/python tools/measure_scaling.py --output-dir out/scaling \\
        [--triangles 1000 4000 16000 64000 100000] [--methods auto] [--quality draft] [--timeout 1800] \\
        [--cycles 64] [--family production --objects 10]

Every (room, method) runs in a process of its own, which builds the room and bakes it stage by
stage as the add-on does (bench/scaling.py: export, material maps, the core
solve's stages, lightmaps, write-back), each stage's seconds and peak resident memory recorded.
After each room's first bake, Cycles bakes the same room (built again, saved in DIR) into
lightmaps of the same sizes at `--cycles` samples per texel, in a process of its own (0: not).
Writes DIR/scaling.json, DIR/scaling.png (seconds and peak memory per stage against
triangles, log-log, with Cycles' whole bake) and DIR/scaling.md (the same as a table: what
docs/bench/ shows; `--replot` redraws both from the json).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def plot(path: Path, runs: list[dict]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
    ours = [run for run in runs if not run["method_asked"].startswith("cycles") and "stage_seconds" in run]
    names = list(dict.fromkeys(name for run in ours for name in run["stage_seconds"]))  # one colour per stage
    colours = plt.get_cmap("tab20")
    labelled = set()
    for m, method in enumerate(dict.fromkeys(run["method_asked"] for run in ours)):
        done = sorted((run for run in ours if run["method_asked"] == method), key=lambda run: run["triangles"])
        for name in dict.fromkeys(name for run in done for name in run["stage_seconds"]):
            k = names.index(name)
            points = [(run["triangles"], run["stage_seconds"].get(name), run["stage_peak_mb"].get(name)) for run in done
                      if name in run["stage_seconds"]]
            x = [p[0] for p in points]
            style = {"marker": "os^"[m % 3], "color": colours(k % 20), "linestyle": ("-", "--", ":")[k // 7 % 3],
                     "label": None if name in labelled else name}
            labelled.add(name)
            left.plot(x, [max(p[1], 1e-3) for p in points], **style)
            right.plot(x, [p[2] for p in points], **style)
        left.plot([run["triangles"] for run in done], [run["seconds"] for run in done], "k--", marker="s",
                  label=f"whole bake ({method})")
    for method in dict.fromkeys(run["method_asked"] for run in runs if run["method_asked"].startswith("cycles")):
        done = sorted((run for run in runs if run["method_asked"] == method and "seconds" in run),
                      key=lambda run: run["triangles"])
        x = [run["triangles"] for run in done]
        style = {"color": "grey", "linestyle": "-.", "marker": "D", "linewidth": 2}
        left.plot(x, [run["seconds"] for run in done], label=f"whole bake ({method})", **style)
        right.plot(x, [run["peak_mb"] for run in done], label=f"whole bake ({method})", **style)
    for axis, label in ((left, "seconds"), (right, "peak resident memory, MiB")):
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel("triangles")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=7, ncol=2)
    left.set_title("time per stage")
    right.set_title("peak memory per stage")
    figure.tight_layout()
    figure.savefig(path, dpi=110)


def table(runs: list[dict]) -> str:
    """A markdown table of `runs`: per scene the size of its solve, our bake's seconds and peak
    memory, its slowest stages, and Cycles' bake of the same lightmaps."""
    cycles = {run["triangles_target"]: run for run in runs if run["method_asked"].startswith("cycles")}
    lines = ["| triangles | objects | patches | texels | seconds | peak MiB | slowest stages (s) | job MB | Cycles |",
             "|---:|---:|---:|---:|---:|---:|---|---:|---|"]
    for run in runs:
        if run["method_asked"].startswith("cycles"):
            continue
        if "stage_seconds" not in run:
            lines.append(f"| {run['triangles_target']} | | | | failed: {run.get('failed')} | | | | |")
            continue
        stages = sorted(run["stage_seconds"].items(), key=lambda item: -item[1])[:3]
        other = cycles.get(run["triangles_target"], {})
        versus = (f"{other['seconds']:.1f} s, {other['peak_mb']:.0f} MiB ({other['method_asked']})"
                  if "seconds" in other else "")
        lines.append(f"| {run['triangles']} | {run.get('objects', '')} | {run['patches']} | {run['texels']} | "
                     f"{run['seconds']:.1f} | {max(run['stage_peak_mb'].values()):.0f} | "
                     + ", ".join(f"{name} {seconds:.1f}" for name, seconds in stages)
                     + f" | {run.get('job_mb', 0):.0f} | {versus} |")
    return "\n".join(lines) + "\n"


def write_results(out: Path, runs: list[dict]) -> None:
    plot(out / "scaling.png", runs)
    (out / "scaling.md").write_text(table(runs))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output-dir", type=Path, required=True)
    parser.add_argument("--triangles", type=int, nargs="+", default=[1000, 4000, 16000, 64000, 100000])
    parser.add_argument("--methods", nargs="+", default=["auto"])
    parser.add_argument("--quality", default="draft")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per bake before it is stopped")
    parser.add_argument("--cycles", type=int, default=64, metavar="SAMPLES",
                        help="Cycles' samples per texel on the same rooms (0: no Cycles bakes)")
    parser.add_argument("--family", choices=("rooms", "production"), default="rooms")
    parser.add_argument("--objects", type=int, default=10, help="production: about how many objects (1: one)")
    parser.add_argument("--one", nargs=2, metavar=("TRIANGLES", "METHOD"), help=argparse.SUPPRESS)
    parser.add_argument("--one-cycles", nargs=2, metavar=("TRIANGLES", "SIZES"), help=argparse.SUPPRESS)
    parser.add_argument("--replot", action="store_true", help="only redraw DIR/scaling.png and .md from DIR/scaling.json")
    args = parser.parse_args()
    if args.replot:
        write_results(args.output_dir, json.loads((args.output_dir / "scaling.json").read_text()))
        return 0
    if args.one:
        from bench.scaling import bake_production_in_stages, bake_room_in_stages
        solve = {"quality": args.quality, "method": args.one[1]}
        run = (bake_production_in_stages(int(args.one[0]), solve, args.objects) if args.family == "production"
               else bake_room_in_stages(int(args.one[0]), solve))
        print(json.dumps(run, default=float))
        return 0
    if args.one_cycles:
        from bench.scaling import bake_room_with_cycles
        sizes = json.loads(Path(args.one_cycles[1]).read_text())
        print(json.dumps(bake_room_with_cycles(int(args.one_cycles[0]), sizes, args.cycles, args.output_dir,
                                               args.family, args.objects), default=float))
        return 0
    out = args.output_dir
    out.mkdir(parents=True, exist_ok=True)
    runs = []

    def run_one(triangles: int, method_asked: str, command: list) -> dict:
        started = time.perf_counter()
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=args.timeout)
            lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
            run = json.loads(lines[-1]) if done.returncode == 0 and lines else \
                {"triangles_target": triangles, "failed": done.stderr.strip().splitlines()[-3:]}
        except subprocess.TimeoutExpired:
            run = {"triangles_target": triangles, "failed": f"stopped after {args.timeout:.0f} s"}
        run.update(method_asked=method_asked, wall_seconds=time.perf_counter() - started, load_average=os.getloadavg())
        runs.append(run)
        print(json.dumps({k: v for k, v in run.items() if k != "sizes"}, default=float), flush=True)
        (out / "scaling.json").write_text(json.dumps(runs, indent=1, default=float))
        return run

    base = [sys.executable, __file__, "--output-dir", str(out), "--quality", args.quality, "--cycles", str(args.cycles),
            "--family", args.family, "--objects", str(args.objects)]
    for k, method in enumerate(args.methods):
        for triangles in args.triangles:
            run = run_one(triangles, method, base + ["--one", str(triangles), method])
            if k == 0 and args.cycles > 0 and "sizes" in run:  # Cycles into the first method's lightmap sizes
                sizes = out / f"sizes_{triangles}.json"
                sizes.write_text(json.dumps(run["sizes"]))
                run_one(triangles, f"cycles {args.cycles} spp", base + ["--one-cycles", str(triangles), str(sizes)])
    write_results(out, runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
