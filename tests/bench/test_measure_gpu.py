"""tools/measure_gpu.py's `solve` (the part that runs on a machine without Blender): it solves a job
folder as the solver process does and brings back the same lightmaps and its timings."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from radiosity_addon import core
from radiosity_addon.solver_process import child, protocol

TOOL = Path(__file__).resolve().parents[2] / "tools" / "measure_gpu.py"


def test_solve_writes_the_solver_process_lightmaps_and_timings(tmp_path, gpu):
    scene = core.load_scene("cornell-box")
    settings = core.SolveSettings(quality="draft", method="hemicube")
    lightmaps = core.LightmapSettings(texel_density=16.0, content="combined")
    job = tmp_path / "jobs" / "cornell-0"
    job.mkdir(parents=True)
    protocol.write_job(job, scene, settings, lightmaps, scene.object_names, None)
    (job / "measure.json").write_text(json.dumps({"label": "draft"}))
    out = tmp_path / "out"
    subprocess.run([sys.executable, str(TOOL), "solve", str(tmp_path / "jobs"), "--output", str(out), "--repeat", "1"],
                   check=True, capture_output=True, timeout=300)

    record = json.loads((out / "timings.json").read_text())
    (run,) = record["jobs"]["cornell-0"]
    assert run["method"] == "hemicube" and run["patches"] > 0
    assert 0 < run["solve"] + run["lightmaps"] <= run["seconds"]
    with np.load(out / "cornell-0.npz") as stored:
        names = json.loads(str(stored["names"]))
        images = {name: stored[f"image_{k}"] for k, name in enumerate(names)}
    expected = child.lightmap_images(scene, core.solve(scene, settings, gpu=gpu), scene.object_names, lightmaps, gpu)
    assert names == scene.object_names
    for name in names:  # half floats: 2^-11 relative
        np.testing.assert_allclose(images[name], expected[name], rtol=1e-3, atol=1e-6)
