"""Scene analysis: each skip gives the full simulation's result with measurably less work."""

import numpy as np
import pytest
from scenes import area_weighted_mean, closed_cube, opposed_squares, solve_settings, surface

from radiosity_addon.core.scene import analyse
from radiosity_addon.core import SceneError, load_scene, scene_from_dict
from radiosity_addon.core import solve


def solve_both(gpu, scene, **settings):
    """(analysed, full) solutions of one scene, on the same patches (no refinement)."""
    return tuple(solve(scene, solve_settings(method="hemicube", skip_unneeded=skip, refinements=0, **settings), gpu=gpu)
                 for skip in (True, False))


def grey_room_with_occluder():
    """A closed grey cube with a small grey panel floating inside: grey but occluded."""
    data = closed_cube(reflectance=0.6, emitting={"ceiling"})
    data["surfaces"].append(surface("panel", [[0.3, 0.3, 0.5], [0.7, 0.3, 0.5], [0.7, 0.7, 0.5],
                                              [0.3, 0.7, 0.5]], 0.6, 0.0))
    return scene_from_dict(data)


def test_grey_convex_room_one_channel_no_occlusion(gpu):
    scene = scene_from_dict(closed_cube(reflectance=0.7, emission=0.5))
    effects = analyse(scene)
    assert (effects.channels, effects.occlusion, effects.interreflection, effects.emitters) == (1, False, True, 6)
    solution = solve(scene, solve_settings(method="hemicube", subdiv=2, tolerance=1e-7), gpu=gpu)
    report = solution.report
    assert report.effects.channels == 1 and report.effects.occlusion is False and report.work.hemicubes == 0
    np.testing.assert_allclose(solution.patch_radiosity, 0.5 / (1 - 0.7), rtol=1e-4)


def test_coloured_scene_with_occluder_needs_everything():
    effects = analyse(load_scene("cornell-box"))
    assert (effects.channels, effects.occlusion, effects.interreflection, effects.emitters) == (3, True, True, 1)


def test_black_receivers_report_no_interreflection():
    data = closed_cube(reflectance=0.0, emitting={"ceiling"})
    assert analyse(scene_from_dict(data)).interreflection is False
    # one reflective surface alone cannot interreflect either: a plane cannot see itself
    assert analyse(scene_from_dict(opposed_squares(1.0))).interreflection is False


def test_no_emitter_is_refused_before_any_work():
    with pytest.raises(SceneError, match="nothing emits"):
        solve(scene_from_dict(closed_cube(emission=0.0), require_emitter=False))


def test_channel_skip_matches_full_solve(gpu):
    scene = grey_room_with_occluder()
    analysed, full = solve_both(gpu, scene, subdiv=3, hemicube_res=64, tolerance=1e-7)
    assert analysed.report.work.channels_solved == 1 and full.report.work.channels_solved == 3
    assert analysed.report.effects.occlusion is True
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-5, atol=1e-9)


def test_occlusion_skip_matches_hemicubes_with_no_renders(gpu):
    """Convex room lit by its ceiling: analytic unoccluded factors vs hemi-cubes. They differ only
    by the hemi-cube's aliasing (≈ 0.7 / pixels across a patch), so per-face means agree within 1 %."""
    scene = scene_from_dict(closed_cube(reflectance=0.6, emitting={"ceiling"}))
    analysed, full = solve_both(gpu, scene, subdiv=4, hemicube_res=256, tolerance=1e-7)
    assert analysed.report.work.hemicubes == 0 and full.report.work.hemicubes == 96 * 4  # 2 x 2 per patch
    for index in range(6):
        np.testing.assert_allclose(area_weighted_mean(analysed, index), area_weighted_mean(full, index), rtol=0.01)


def test_interreflection_skip_matches_linear_solve(gpu):
    """Receiver under a black emitter: one bounce is the whole answer."""
    scene = scene_from_dict(opposed_squares(1.0))
    analysed, full = solve_both(gpu, scene, subdiv=4, hemicube_res=64, tolerance=1e-8)
    assert analysed.report.work.linear_solve is False and full.report.work.linear_solve is True
    assert full.report.details.iterations > 0
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-3, atol=1e-7)


def test_black_patches_get_no_hemicube(gpu):
    """The Cornell box with a black light: the light's rows are never used, so never rendered."""
    data = load_scene("cornell-box").to_dict()
    for entry in data["surfaces"]:
        if entry["name"] == "light":
            entry["reflectance"] = [0.0, 0.0, 0.0]
    scene = scene_from_dict(data)
    analysed, full = solve_both(gpu, scene, subdiv=2, hemicube_res=64, tolerance=1e-7)
    assert analysed.report.work.hemicubes == full.report.work.hemicubes - 4 * 4  # 4 patches of 2 x 2
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-5, atol=1e-9)


def test_progressive_occlusion_skip_matches_visibility_maps(gpu):
    """Convex room lit by its ceiling: without visibility maps the same answer, and no maps drawn."""
    scene = scene_from_dict(closed_cube(reflectance=0.6, emitting={"ceiling"}))
    analysed, full = (solve(scene, solve_settings(subdiv=2, elements=2, tolerance=1e-3, skip_unneeded=skip), gpu=gpu)
                      for skip in (True, False))
    assert analysed.report.work.visibility_maps == 0
    assert full.report.work.visibility_maps == full.report.details.shots > 0
    # the search variant's lookups along the room's edges differ slightly from V = 1
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=0.01)


def test_progressive_interreflection_skip_shoots_only_the_emitter(gpu):
    scene = scene_from_dict(opposed_squares(1.0))
    analysed, full = (solve(scene, solve_settings(subdiv=2, elements=2, tolerance=1e-6, skip_unneeded=skip), gpu=gpu)
                      for skip in (True, False))
    assert analysed.report.details.shots == 1  # the emitter once, whole (one surface, nothing occludes)
    assert analysed.report.work.residual_updates is False
    assert full.report.details.shots > analysed.report.details.shots
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=1e-4, atol=1e-7)


def test_effects_summary_names_what_was_skipped(gpu):
    scene = scene_from_dict(closed_cube(reflectance=0.0, emitting={"ceiling"}))
    solution = solve(scene, solve_settings(method="hemicube", subdiv=2), gpu=gpu)

    line = solution.report.summary_line()
    assert line.startswith("1 channel(s) · no occlusion (skipped) · direct light only · 1 emitter(s) · 0 hemi-cubes")


def test_progressive_channel_skip_matches_full(gpu):
    """A grey scene with an occluder: one-channel (R32F) textures give the RGB solve's answer."""
    scene = grey_room_with_occluder()
    analysed, full = (solve(scene, solve_settings(subdiv=2, elements=2, tolerance=1e-3, skip_unneeded=skip), gpu=gpu)
                      for skip in (True, False))
    assert analysed.report.work.channels_solved == 1 and full.report.work.channels_solved == 3
    assert analysed.report.work.texel_bytes * 4 == full.report.work.texel_bytes
    assert analysed.report.details.shots == full.report.details.shots
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=1e-5, atol=1e-9)


def test_the_analysis_memory_stays_flat_as_the_scene_grows():
    """The pairwise plane tests run in chunks whose arrays are bounded, not 256 rows against
    every corner: on a floor of 12 000 reflective squares under a ceiling the analysis peaks at
    33 MB of Python-traced memory, held under 80 (the 256-row chunks took 195 MB here, 1 GB on
    the 64k-triangle room), and still finds the interreflection and the occlusion."""
    import tracemalloc

    side = 110
    step = 1.0 / side
    x, y = np.meshgrid(np.arange(side) * step, np.arange(side) * step)
    squares = np.stack([np.stack([x, y, np.zeros_like(x)], -1), np.stack([x + step, y, np.zeros_like(x)], -1),
                        np.stack([x + step, y + step, np.zeros_like(x)], -1),
                        np.stack([x, y + step, np.zeros_like(x)], -1)], axis=2).reshape(-1, 4, 3)
    surfaces = [surface(f"tile {k}", corners.tolist(), 0.5, 0.0) for k, corners in enumerate(squares)]
    ceiling = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]  # facing down
    surfaces += [surface("ceiling", ceiling, 0.5, 1.0),
                 surface("block", [[0.4, 0.4, 0.5], [0.4, 0.6, 0.5], [0.6, 0.6, 0.5], [0.6, 0.4, 0.5]], 0.5, 0.0)]
    scene = scene_from_dict({"surfaces": surfaces})
    assert len(scene) > 12_000
    tracemalloc.start()
    try:
        effects = analyse(scene)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert effects.interreflection and effects.occlusion
    assert peak < 80 * 2 ** 20, f"{peak / 2 ** 20:.0f} MB"
