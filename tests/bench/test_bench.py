"""The benchmark's own arithmetic: texel grid, exact answers, metrics, Pareto front, and (with bpy)
that the Cycles bake lands on the same grid and in the same units."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from bench import metrics, scenes, sweep, texels
from radiosity_addon.cli import build_parser
from radiosity_addon.core import subdivide
from radiosity_addon.core import load_scene, scene_from_dict


def test_exact_plates_answer_matches_the_opposed_squares_oracle():
    scene = scenes.plates_scene()
    exact = scenes.exact_texels("plates", scene, 32)
    # the texel average over the whole receiver is ρ E times the area-to-area factor 0.199825
    assert exact[0, ..., 0].mean() == pytest.approx(scenes.PLATES_REFLECTANCE * 0.199825, rel=1e-4)


def test_texels_find_their_patches_on_quads_and_triangles():
    """Each covered texel shows the value of the patch holding it (piecewise constant), including
    the inverted sub-triangles of the Cornell box's triangular left wall."""
    scene = load_scene("cornell-box")
    patches = subdivide(scene, 3)
    radiosity = np.repeat(np.arange(len(patches), dtype=float)[:, None], 3, axis=1)
    shown = texels.solution_texels(scene, patches, radiosity, None, 24)
    owners = texels.texel_patches(scene, patches, 24)
    weights = texels.texel_weights(scene, 24)
    covered = weights > 0
    # texels straddling a patch border average two patches; the others show their owner exactly
    exact = np.isclose(shown[..., 0], owners)
    assert exact[covered].mean() > 0.6
    assert np.all(patches.surface[owners[covered]] == np.nonzero(covered)[0])


def test_bilinear_display_reproduces_linear_light():
    m = 8
    centres = (np.arange(m) + 0.5) / m
    grid = np.stack([np.add.outer(2 * centres, 3 * centres)] * 3, axis=-1)  # value = 3 s + 2 t
    s, t = np.meshgrid(np.linspace(0.1, 0.9, 5), np.linspace(0.1, 0.9, 5))
    np.testing.assert_allclose(texels.bilinear_on_grid(grid, s, t)[..., 0], 3 * s + 2 * t, atol=1e-12)


def test_metrics_and_pareto_front():
    reference = np.ones((2, 4, 4, 3))
    weights = np.ones((2, 4, 4))
    assert metrics.relative_rms(reference * 1.1, reference, weights) == pytest.approx(0.1)
    rows = [{"seconds": 1, "error": 0.5}, {"seconds": 2, "error": 0.6}, {"seconds": 3, "error": 0.1}]
    assert metrics.pareto_front(rows) == [rows[0], rows[2]]


def test_bench_command_is_wired(monkeypatch):
    """`python -m bench` runs the sweep; the shipped command line has no bench (the zip has none)."""
    import bench.__main__ as bench_main

    calls = []
    monkeypatch.setattr(bench_main, "run_bench", lambda *args: calls.append(args))
    assert bench_main.main(["--quick", "--output-dir", "out", "--scenes", "furnace"]) == 0
    assert calls == [(Path("out"), True, None, None, ("furnace",))]
    with pytest.raises(SystemExit):
        build_parser().parse_args(["bench", "--quick", "--output-dir", "out"])


@pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason="needs the bpy module")
def test_cycles_bake_lands_on_the_grid_in_radiosity_units():
    from bench.cycles import bake_scene

    # a small emitter over one corner of the receiver: light that a flipped or transposed grid
    # would move elsewhere
    emitter = [[0, 0, 0.5], [0, 0.4, 0.5], [0.6, 0.4, 0.5], [0.6, 0, 0.5]]
    scene = scene_from_dict({"surfaces": [
        {"name": "receiver", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
         "reflectance": [0.8] * 3, "emission": [0] * 3},
        {"name": "emitter", "vertices": emitter, "reflectance": [0] * 3, "emission": [1] * 3}]})
    baked = bake_scene(scene, 16, 64, seed=1)["texels"]
    receiver = scene.surfaces[0]
    s, t = texels.sample_parameters(16)
    factor = scenes.point_to_polygon_form_factor(texels.surface_points(receiver, s, t), receiver.normal,
                                                 np.asarray(emitter, dtype=float))
    exact = 0.8 * factor.mean(axis=2)
    inside = texels.covered_mask(False, 16)
    ratio = baked[0][inside][:, 0] / exact[inside]
    assert np.abs(ratio.mean() - 1) < 0.02  # same units, no clamping or bounce cut
    assert np.abs(ratio - 1).max() < 0.15  # same orientation of the grid (no flip or transpose)


def test_the_sweep_maps_unrefined_solves_and_refuses_refined_ones():
    """texels.py finds a texel's patch by its grid cell, which the 2 x 2 children of a refined patch
    share: the sweep solves without refinement, and a refined solve is refused rather than shown as
    one child stretched over its parent (what rated every progressive run ~25 % off)."""
    from radiosity_addon.core.scene import split_patches

    plan = sweep.make_plan(quick=True)
    assert all(settings.refinements == 0 for settings in (*plan.hemicube, *plan.progressive))
    scene = load_scene("cornell-box")
    backs = np.zeros(len(scene), dtype=bool)
    patches = subdivide(scene, 2, 0.5, backs)
    assert texels.texel_patches(scene, patches, 8).max() == len(patches) - 1  # every patch shows
    refined = split_patches(patches, np.arange(len(patches)) == 0, backs)
    with pytest.raises(ValueError, match="share a grid cell"):
        texels.texel_patches(scene, refined, 8)
