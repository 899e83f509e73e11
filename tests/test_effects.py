"""Scene analysis: each skip gives the full simulation's result with measurably less work."""

import numpy as np
import pytest
from scenes import area_weighted_mean, closed_cube, opposed_squares, surface

from radiosity_addon.core.effects import analyse
from radiosity_addon.core.scene import SceneError, load_scene, scene_from_dict
from radiosity_addon.core.solution import SolveSettings
from radiosity_addon.core.solve import solve


def solve_both(ctx, scene, **settings):
    """(analysed, full) solutions of one scene."""
    return tuple(solve(scene, SolveSettings(method="hemicube", skip_unneeded=skip, **settings), ctx=ctx)
                 for skip in (True, False))


def grey_room_with_occluder():
    """A closed grey cube with a small grey panel floating inside: grey but occluded."""
    data = closed_cube(reflectance=0.6, emitting={"ceiling"})
    data["surfaces"].append(surface("panel", [[0.3, 0.3, 0.5], [0.7, 0.3, 0.5], [0.7, 0.7, 0.5],
                                              [0.3, 0.7, 0.5]], 0.6, 0.0))
    return scene_from_dict(data)


def test_grey_convex_room_one_channel_no_occlusion(ctx):
    scene = scene_from_dict(closed_cube(reflectance=0.7, emission=0.5))
    effects = analyse(scene)
    assert (effects.channels, effects.occlusion, effects.interreflection, effects.emitters) == (1, False, True, 6)
    solution = solve(scene, SolveSettings(method="hemicube", subdiv=2, tolerance=1e-7), ctx=ctx)
    report = solution.report["effects"]
    assert report["channels"] == 1 and report["occlusion"] is False and report["hemicubes"] == 0
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


def test_channel_skip_matches_full_solve(ctx):
    scene = grey_room_with_occluder()
    analysed, full = solve_both(ctx, scene, subdiv=3, hemicube_res=64, tolerance=1e-7)
    assert analysed.report["effects"]["channels_solved"] == 1 and full.report["effects"]["channels_solved"] == 3
    assert analysed.report["effects"]["occlusion"] is True
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-5, atol=1e-9)


def test_occlusion_skip_matches_hemicubes_with_no_renders(ctx):
    """Convex room lit by its ceiling: analytic unoccluded factors vs hemi-cubes. They differ only
    by the hemi-cube's aliasing (≈ 0.7 / pixels across a patch), so per-face means agree within 1 %."""
    scene = scene_from_dict(closed_cube(reflectance=0.6, emitting={"ceiling"}))
    analysed, full = solve_both(ctx, scene, subdiv=4, hemicube_res=256, tolerance=1e-7)
    assert analysed.report["effects"]["hemicubes"] == 0 and full.report["effects"]["hemicubes"] == 96
    for index in range(6):
        np.testing.assert_allclose(area_weighted_mean(analysed, index), area_weighted_mean(full, index), rtol=0.01)


def test_interreflection_skip_matches_linear_solve(ctx):
    """Receiver under a black emitter: one bounce is the whole answer."""
    scene = scene_from_dict(opposed_squares(1.0))
    analysed, full = solve_both(ctx, scene, subdiv=4, hemicube_res=64, tolerance=1e-8)
    assert analysed.report["effects"]["linear_solve"] is False and full.report["effects"]["linear_solve"] is True
    assert full.report["iterations"] > 0
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-3, atol=1e-7)


def test_black_patches_get_no_hemicube(ctx):
    """The Cornell box with a black light: the light's rows are never used, so never rendered."""
    data = load_scene("cornell-box").to_dict()
    for entry in data["surfaces"]:
        if entry["name"] == "light":
            entry["reflectance"] = [0.0, 0.0, 0.0]
    scene = scene_from_dict(data)
    analysed, full = solve_both(ctx, scene, subdiv=2, hemicube_res=64, tolerance=1e-7)
    assert analysed.report["effects"]["hemicubes"] == full.report["effects"]["hemicubes"] - 4
    np.testing.assert_allclose(analysed.patch_radiosity, full.patch_radiosity, rtol=1e-5, atol=1e-9)


def test_progressive_occlusion_skip_matches_visibility_maps(ctx):
    """Convex room lit by its ceiling: without visibility maps the same answer, and no maps drawn."""
    scene = scene_from_dict(closed_cube(reflectance=0.6, emitting={"ceiling"}))
    analysed, full = (solve(scene, SolveSettings(subdiv=2, elements=2, tolerance=1e-3, skip_unneeded=skip), ctx=ctx)
                      for skip in (True, False))
    assert analysed.report["effects"]["visibility_maps"] == 0
    assert full.report["effects"]["visibility_maps"] == full.report["shots"] > 0
    # the search variant's lookups along the room's edges differ slightly from V = 1
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=0.01)


def test_progressive_interreflection_skip_shoots_only_the_emitter(ctx):
    scene = scene_from_dict(opposed_squares(1.0))
    analysed, full = (solve(scene, SolveSettings(subdiv=2, elements=2, tolerance=1e-6, skip_unneeded=skip), ctx=ctx)
                      for skip in (True, False))
    assert analysed.report["shots"] == 4  # the emitter's four patches, once each
    assert analysed.report["effects"]["residual_updates"] is False
    assert full.report["shots"] > analysed.report["shots"]
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=1e-4, atol=1e-7)


def test_effects_summary_names_what_was_skipped(ctx):
    scene = scene_from_dict(closed_cube(reflectance=0.0, emitting={"ceiling"}))
    solution = solve(scene, SolveSettings(method="hemicube", subdiv=2), ctx=ctx)
    from radiosity_addon.core.effects import effects_summary

    line = effects_summary(solution.report)
    assert line.startswith("1 channel(s) · no occlusion (skipped) · direct light only · 1 emitter(s) · 0 hemi-cubes")


def test_progressive_channel_skip_matches_full(ctx):
    """A grey scene with an occluder: one-channel (R32F) textures give the RGB solve's answer."""
    scene = grey_room_with_occluder()
    analysed, full = (solve(scene, SolveSettings(subdiv=2, elements=2, tolerance=1e-3, skip_unneeded=skip), ctx=ctx)
                      for skip in (True, False))
    assert analysed.report["effects"]["channels_solved"] == 1 and full.report["effects"]["channels_solved"] == 3
    assert analysed.report["effects"]["texel_bytes"] * 4 == full.report["effects"]["texel_bytes"]
    assert analysed.report["shots"] == full.report["shots"]
    np.testing.assert_allclose(analysed.element_radiosity, full.element_radiosity, rtol=1e-5, atol=1e-9)
