"""Rewrite the README's (and docs/benchmarks.md's) measured figures from the JSON the benchmarks write.

    .venv/bin/python tools/readme_figures.py           # rewrite the blocks in both documents
    .venv/bin/python tools/readme_figures.py --check   # exit 1 if either is out of date
    make readme-figures

Every table of current numbers in README.md and docs/benchmarks.md sits between two markers,

    <!-- figures:NAME -->
    ...generated, do not edit by hand...
    <!-- /figures:NAME -->

and this tool replaces what is between them with what BLOCKS[NAME] makes of the JSON in
docs/bench/ (standard library only: no bpy, no numpy). Running it twice changes nothing. The JSON
comes from the benchmark tools (the README names the command next to each table):

    docs/bench/presets_cornell.json  tools/measure_presets.py on sample_blends/cornell_box.blend
                                     (DIR/presets.json copied here)
    docs/bench/presets_room.json     tools/measure_presets.py on the 4k furnished room (the same)
    docs/bench/scaling.json          tools/measure_scaling.py on the furnished rooms (DIR/scaling.json)

Blocks: presets (one row per quality preset, both scenes), results-cornell and results-room (ours
and Cycles' rows of one run), room-objects (the room's objects that `good` leaves more than 10 %
off Cycles' mean), scaling (each room's bake and Cycles'; the README does not show it today). A
block reads only its own JSON, and only the blocks the README holds are made. There is no
production block: make bench-production writes markdown, not JSON (docs/bench/production/).
Exit status: 0 done (or, with --check, up to date); 1 out of date (--check); 2 a marker or a
JSON file is missing or malformed.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from generated_blocks import BlocksError, update

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("draft", "good", "final")


# -- formatting ---------------------------------------------------------------------------------

def seconds(value: float) -> str:
    return f"{value:.2f} s" if value < 10 else f"{value:.1f} s" if value < 1000 else f"{value:.0f} s"


def percent(value: float) -> str:
    return f"{100 * value:.1f} %"


def signed_percent(value: float) -> str:
    return f"{100 * value:+.0f} %".replace("-", "−")


def count(value: int) -> str:
    return f"{value:,}".replace(",", " ")


def gigabytes(megabytes: float) -> str:
    return f"{megabytes / 1024:.2f} GB"


def times(ratio: float) -> str:
    return f"{ratio:.0f} ×" if ratio >= 10 else f"{ratio:.1f} ×"


def speed_up(ours_seconds: float, cycles_seconds: float) -> str:
    """Which bake is faster to the same error, and by how much."""
    if cycles_seconds >= ours_seconds:
        return f"ours {times(cycles_seconds / ours_seconds)} faster"
    return f"Cycles {times(ours_seconds / cycles_seconds)} faster"


def object_name(name: str) -> str:
    return name.replace("_", " ")


def table(header: list[str], align: str, rows: list[list[str]]) -> list[str]:
    """A markdown table; `align` has one character per column, l or r."""
    return (["| " + " | ".join(header) + " |",
             "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"]
            + ["| " + " | ".join(row) + " |" for row in rows])


# -- the JSON ------------------------------------------------------------------------------------

def load(bench: Path, name: str):
    path = bench / name
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise BlocksError(f"{path} is missing; run the benchmark the README names next to the table") from None
    except json.JSONDecodeError as error:
        raise BlocksError(f"{path} is not JSON: {error}") from None


def preset_run(record: dict, quality: str) -> dict | None:
    """The run of `record` that is the preset `quality` as it is (no other setting)."""
    for run in record["runs"]:
        if run.get("settings") == {"quality": quality}:
            return run
    return None


def ours(record: dict) -> list[dict]:
    return [run for run in record["runs"] if run.get("method") != "cycles"]


def cycles(record: dict) -> list[dict]:
    return sorted((run for run in record["runs"] if run.get("method") == "cycles"), key=lambda run: run["samples"])


def some_cycles(record: dict) -> list[dict]:
    """Cycles' rows at 16 × 4^k samples (16, 64, 256, 1 024, ...) where the run has more than four
    rows, so that a summary stays short; all of them otherwise."""
    rows = cycles(record)
    if len(rows) <= 4:
        return rows
    powers = {16 * 4 ** k for k in range(8)}
    return [run for run in rows if run["samples"] in powers] or rows


def run_label(run: dict) -> str:
    settings = run.get("settings") or {}
    quality = settings.get("quality", "custom")
    label = f"**{quality}** (default)" if quality == "good" and len(settings) == 1 else quality
    others = [f"`--{key} {value}`" for key, value in settings.items() if key != "quality"]
    return " ".join([label] + others)


def method_name(method: str) -> str:
    return {"hemicube": "hemi-cube", "progressive": "progressive"}.get(method, method)


def bake_time(run: dict) -> str:
    return seconds(run["seconds"])


def reference_line(record: dict, scene: str) -> str:
    reference = record["reference"]
    rounds = max(len(run.get("rounds") or [1]) for run in record["runs"])
    cpus = (record.get("machine") or {}).get("cpus")
    where = f" on {cpus} CPU cores (Mesa llvmpipe, no GPU)" if cpus else ""
    density = record.get("texel_density")
    texels = f" at {density:.0f} texels per metre (what the first run chose)" if density else ""
    return (f"{scene}: every row baked {rounds} × in turn{where}{texels}, the median time given; errors against"
            f" Cycles'"
            f" Combined bake at {count(reference['samples_per_seed'])} samples × 2 seeds (its own noise"
            f" {percent(reference['noise'])} texel RMS).")


# -- the blocks ----------------------------------------------------------------------------------

def block_presets(bench: Path) -> list[str]:
    cornell, room = load(bench, "presets_cornell.json"), load(bench, "presets_room.json")
    rows = []
    for quality in PRESETS:
        box, rooms = preset_run(cornell, quality), preset_run(room, quality)
        if box is None and rooms is None:
            continue
        cells = [f"**{quality}** (default)" if quality == "good" else quality]
        for run in (box, rooms):
            cells += (["", ""] if run is None else
                      [f"{seconds(run['seconds'])}, {method_name(run['method'])}", percent(run["texel_rms"])])
        rows.append(cells)
    return table(["preset", "Cornell box: bake, method `auto` picked", "texel RMS",
                  "4k-triangle room: bake, method", "texel RMS"], "lrrrr", rows)


def block_results_cornell(bench: Path) -> list[str]:
    record = load(bench, "presets_cornell.json")
    rows = []
    for run in ours(record):
        same = run.get("cycles_to_same_error")
        rows.append([run_label(run), method_name(run["method"]), count(run["patches"]), bake_time(run),
                     percent(run["texel_rms"]), f"{percent(run['balanced_bias'])}",
                     f"{object_name(run['worst_object'])} {signed_percent(run['worst_object_error'])}",
                     "" if same is None else f"≈ {same['samples']:.0f} samples, {seconds(same['seconds'])}:"
                                             f" {speed_up(run['seconds'], same['seconds'])}"])
    for run in some_cycles(record):
        rows.append([f"Cycles, {count(run['samples'])} samples", "", "", bake_time(run), percent(run["texel_rms"]),
                     percent(run["balanced_bias"]),
                     f"{object_name(run['worst_object'])} {signed_percent(run['worst_object_error'])}", ""])
    lines = [reference_line(record, "Cornell sample (`sample_blends/cornell_box.blend`)"), ""]
    lines += table(["run", "method", "patches", "bake", "texel RMS", "object-balanced RMS (noise out)",
                    "worst object mean", "Cycles to the same texel RMS"], "llrrrrlr", rows)
    bar, final = record.get("bar"), preset_run(record, "final")
    if bar:
        lines += ["", f"Cycles reaches {percent(bar['target_error'])} texel RMS at about {bar['samples']:.0f}"
                      f" samples, in {seconds(bar['seconds'])}"
                  + ("." if final is None else f"; `final` bakes in {seconds(final['seconds'])},"
                     f" {final['seconds'] / bar['seconds']:.2f} × that time, to {percent(final['texel_rms'])}.")]
    return lines


def block_results_room(bench: Path) -> list[str]:
    record = load(bench, "presets_room.json")
    rows = []
    for run in ours(record) + some_cycles(record):
        label = run_label(run) if run.get("method") != "cycles" else f"Cycles, {count(run['samples'])} samples"
        rows.append([label, method_name(run["method"]) if run.get("method") != "cycles" else "",
                     count(run["patches"]) if run.get("patches") else "", bake_time(run),
                     f"{percent(run['texel_rms'])} / {percent(run['texel_rms_inside'])}", percent(run["balanced_bias"]),
                     f"{object_name(run['worst_object'])} {signed_percent(run['worst_object_error'])}"])
    lines = [reference_line(record, "Furnished room, 3 932 triangles, 23 objects"), ""]
    return lines + table(["run", "method", "patches", "bake", "texel RMS: all / inside the room",
                          "object-balanced RMS (noise out)", "worst object mean"], "llrrrrl", rows)


def block_room_objects(bench: Path) -> list[str]:
    record = load(bench, "presets_room.json")
    run = preset_run(record, "good")
    if run is None or not run.get("objects"):
        raise BlocksError("docs/bench/presets_room.json has no `good` run with per-object errors")
    off = sorted(((name, error) for name, error in run["objects"].items() if abs(error) > 0.10),
                 key=lambda item: -abs(item[1]))
    listed = ", ".join(f"{name} {signed_percent(error)}" for name, error in off) or "none"
    return [f"At `good`, {len(off)} of the room's {len(run['objects'])} objects are more than 10 % off Cycles'"
            f" mean: {listed}."]


def block_scaling(bench: Path) -> list[str]:
    runs = load(bench, "scaling.json")
    auto = sorted((run for run in runs if run.get("method_asked") == "auto" and "stage_seconds" in run),
                  key=lambda run: run["triangles"])
    other = {run["triangles_target"]: run for run in runs
             if str(run.get("method_asked", "")).startswith("cycles") and "seconds" in run}
    if not auto:
        raise BlocksError("docs/bench/scaling.json has no `auto` run")
    rows = []
    for run in auto:
        versus = other.get(run["triangles_target"])
        slowest = sorted(run["stage_seconds"].items(), key=lambda item: -item[1])[:2]
        rows.append([count(run["triangles"]), count(run["patches"]), method_name(run["method"]),
                     seconds(run["seconds"]),
                     ", ".join(f"{name} {value:.1f} s" for name, value in slowest),
                     gigabytes(max(run["stage_peak_mb"].values())),
                     "" if versus is None else seconds(versus["seconds"])])
    samples = {run["method_asked"].split()[1] for run in other.values()}
    cycles_header = f"Cycles, {samples.pop()} samples" if len(samples) == 1 else "Cycles"
    quality = "draft"  # measure_scaling.py's default, which the README's command keeps
    return [f"Furnished rooms at `--quality {quality}`, method `auto`, the whole bake; Cycles into lightmaps of the"
            " same sizes.", ""] + table(
        ["triangles", "patches", "method", "bake", "slowest stages", "peak memory", cycles_header],
        "rrlrlrr", rows)


BLOCKS = {
    "presets": block_presets,
    "results-cornell": block_results_cornell,
    "results-room": block_results_room,
    "room-objects": block_room_objects,
    "scaling": block_scaling,
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if the README is out of date")
    parser.add_argument("--document", type=Path, action="append",
                        help="a document to rewrite (default: README.md and docs/benchmarks.md)")
    parser.add_argument("--bench-dir", type=Path, default=ROOT / "docs" / "bench",
                        help="where the benchmark JSON is (default docs/bench)")
    args = parser.parse_args(argv)
    render = {name: (lambda block=block: block(args.bench_dir)) for name, block in BLOCKS.items()}
    documents = args.document or [ROOT / "README.md", ROOT / "docs" / "benchmarks.md"]
    try:
        return max(update("readme_figures", document, "figures", render, args.check, "readme-figures")
                   for document in documents)
    except (KeyError, TypeError, ValueError, IndexError) as error:  # a JSON of another shape
        print(f"readme_figures: docs/bench JSON not as the benchmark tools write it: {error!r}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
