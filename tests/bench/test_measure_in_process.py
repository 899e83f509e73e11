"""tools/measure_in_process.py: a run on a job folder is the solver process's solve and lightmaps
with the run's preset and overrides, at the sizes the reference is baked at."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import blender_support  # noqa: F401  (before the tool imports bpy: a temporary Blender user folder)

import numpy as np

from radiosity_addon import core
from radiosity_addon.core.settings import PATCHES_ACROSS_SCENE, QUALITY_PRESETS
from radiosity_addon.solver_process import child, protocol

TOOL = Path(__file__).resolve().parents[2] / "tools" / "measure_in_process.py"


def load_tool():
    spec = importlib.util.spec_from_file_location("measure_in_process", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_run_is_the_solver_process_bake_with_the_run_settings(tmp_path, gpu):
    tool = load_tool()
    scene = core.load_scene("cornell-box")
    lightmaps = core.LightmapSettings(texel_density=16.0, content="light")  # the job's; a run bakes combined
    protocol.write_job(tmp_path, scene, core.SolveSettings(quality="good"), lightmaps, scene.object_names, None)
    job = protocol.read_job(tmp_path)

    solution, images, solve_seconds, lightmap_seconds = tool.run_once(
        job, {"quality": "draft", "method": "hemicube", "refinements": 1, "lightmaps": {"direct_subsamples": 1}})

    assert solve_seconds > 0 and lightmap_seconds > 0
    assert solution.report.method == "hemicube" and solution.report.settings.refinements == 1
    assert solution.report.settings.patch_size == min(QUALITY_PRESETS["draft"]["solve"]["patch_size"],
                                                      scene.diameter / PATCHES_ACROSS_SCENE)
    settings = core.SolveSettings.preset("draft", method="hemicube", refinements=1)
    expected_lightmaps = core.LightmapSettings(quality="draft", texel_density=16.0, content="combined",
                                              direct_subsamples=1)
    expected = child.lightmap_images(scene, core.solve(scene, settings, gpu=gpu), scene.object_names,
                                     expected_lightmaps, gpu)
    sizes = tool.lightmap_sizes(job)
    assert sorted(images) == sorted(scene.object_names)
    for name, image in images.items():
        assert (image.shape[1], image.shape[0]) == tuple(sizes[name])
        np.testing.assert_allclose(image, expected[name], rtol=1e-5, atol=1e-7)
