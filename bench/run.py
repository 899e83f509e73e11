"""`python -m bench`: the accuracy-vs-time sweep and the dissertation's Table 5.1."""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

from radiosity_addon.core import load_scene, open_gpu
from . import report, sweep, table51
from .scenes import ANALYTIC_SCENES


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run_bench(output_dir: Path, quick: bool, cache_dir: Path | None = None, table51_samples: int | None = None,
              scenes: tuple[str, ...] = ("cornell-box", "furnace", "plates")) -> dict:
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    cache_dir = Path(cache_dir) if cache_dir else output_dir / "cache"
    plan = sweep.make_plan(quick)
    started = time.perf_counter()
    machine = {"cpus": os.cpu_count(), "platform": platform.platform(), "load_average_at_start": os.getloadavg()}
    rows, notes = [], {}
    with open_gpu() as gpu:
        for name in scenes:
            scene = ANALYTIC_SCENES[name]() if name in ANALYTIC_SCENES else load_scene(name)
            log(f"{name}:")
            scene_rows, notes[name] = sweep.sweep_scene(name, scene, plan, gpu, cache_dir, log)
            rows += scene_rows
        report.mark_pareto(rows)
        machine["load_average_after_sweep"] = os.getloadavg()  # the timings are only as quiet as the machine
        machine["gl_renderer"] = gpu.ctx.info.get("GL_RENDERER")
        report.write_json(output_dir / "accuracy_vs_time.json", rows, notes, machine)
        (output_dir / "accuracy_vs_time.md").write_text(report.markdown(rows, notes, machine))
        report.plot(output_dir / "accuracy_vs_time.png", rows, notes)
        samples = table51_samples if table51_samples is not None else (5 if quick else table51.SAMPLES)
        if samples > 0:
            log("Table 5.1:")
            measured = table51.measure(gpu, samples, log=log)
            machine["load_average_after_table_5_1"] = os.getloadavg()
            table51.write(output_dir, measured, report.machine_line(
                machine | {"load_average_after_sweep": machine["load_average_after_table_5_1"]}))
    seconds = time.perf_counter() - started
    log(f"bench done in {seconds:.0f} s; outputs in {output_dir}")
    return {"rows": rows, "scenes": notes, "seconds": seconds}
