"""Adaptive refinement (core/refinement.py) and the near field it exists for: an emitter a few
millimetres from another surface (a light plane under a ceiling)."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import light_under_ceiling, opposed_squares, solve_settings, surface

from radiosity_addon.core import load_scene, scene_from_dict, solve, subdivide
from radiosity_addon.core.refinement import GAP_RESOLUTION, MIN_CUT, outline_cuts, within_budget
from radiosity_addon.core.scene.gaps import facing_gaps
from radiosity_addon.core.scene import split_patches
from radiosity_addon.core.scene.geometry import bilinear
from radiosity_addon.core.scene.analysis import effects_for


def test_facing_gaps_measure_the_distance_to_the_facing_plane():
    scene = scene_from_dict(opposed_squares(0.01))
    patches = subdivide(scene, 1, 0.5, np.zeros(len(scene), dtype=bool))
    np.testing.assert_allclose(facing_gaps(patches, np.arange(len(patches))), [0.01, 0.01], rtol=1e-9)
    far = subdivide(scene_from_dict(opposed_squares(3.0)), 1, 0.5, np.zeros(2, dtype=bool))
    assert np.isinf(facing_gaps(far, np.arange(2))).all()  # beyond twice their size: no neighbour


def test_refinement_resolves_the_gap_along_the_emitters_outline_only(gpu):
    gap = 0.01
    scene = scene_from_dict(light_under_ceiling(gap))
    solution = solve(scene, solve_settings(patch_size=0.5, elements=2, refinements=6, tolerance=1e-2), gpu=gpu)
    patches = solution.patches
    ceiling = (patches.surface == 1) & ~patches.is_back
    size = np.sqrt(patches.area[ceiling])
    assert size.min() <= GAP_RESOLUTION * gap * 1.5  # split down to about twice the gap ...
    centre = patches.center[ceiling]
    outline = np.abs(np.maximum(np.abs(centre[:, 0] - 1.0), np.abs(centre[:, 1] - 1.0)) - 0.2)
    assert size[outline > 0.3].min() >= 0.25  # ... where the light changes, not far from it
    uniform = (2.0 / size.min()) ** 2
    assert ceiling.sum() < 0.1 * uniform  # far fewer patches than splitting everything that fine


@pytest.mark.slow
def test_the_gap_at_an_emitter_is_resolved_near_its_opening_even_where_no_light_changes(gpu):
    """The emitter's back gets no direct light (no spread to split on), but light trapped between
    it and the ceiling 5 mm above escapes at the outline: both sides are split there down to
    `emitter_gap_resolution` gaps, and not in the middle of the gap nor far from the emitter."""
    gap, resolution = 0.005, 4.0
    scene = scene_from_dict(light_under_ceiling(gap))
    solution = solve(scene, solve_settings(patch_size=0.5, elements=2, refinements=6, tolerance=1e-2,
                                          emitter_gap_resolution=resolution), gpu=gpu)
    patches = solution.patches
    size = np.sqrt(patches.area)
    centre = patches.center
    from_outline = np.maximum(np.abs(centre[:, 0] - 1.0), np.abs(centre[:, 1] - 1.0)) - 0.2  # < 0 inside
    back = (patches.surface == 2) & patches.is_back  # the emitter's back, facing the ceiling
    near = np.abs(from_outline) < 0.01
    assert size[back & near].max() <= resolution * gap * 1.01
    assert size[back & (from_outline < -0.1)].min() > 2 * resolution * gap  # the middle stays coarse
    ceiling = patches.surface == 1
    assert size[ceiling & near].max() <= resolution * gap * 1.01
    assert size[ceiling & (np.abs(from_outline) > 0.3)].min() >= 0.25


def test_a_patch_is_cut_along_the_outline_that_crosses_it_nearest_its_middle():
    scene = scene_from_dict(opposed_squares(0.01))
    patches = subdivide(scene, 1, 0.5, np.zeros(len(scene), dtype=bool))
    s_axis, t_axis = patches.corners[0, 1] - patches.corners[0, 0], patches.corners[0, 3] - patches.corners[0, 0]

    def outline(s0, s1, t0, t1):  # a rectangle given in the patch's own parameters
        return np.array([patches.corners[0, 0] + s * s_axis + t * t_axis + [0, 0, 0.01]
                         for s, t in [(s0, t0), (s1, t0), (s1, t1), (s0, t1)]])

    rows = np.zeros(4, dtype=np.int64)
    outlines = np.stack([outline(0.3, 0.6, 0.2, 0.45),  # both edges cross: the nearer the middle
                         outline(0.3, 1.4, -0.5, 0.7),  # one edge per direction inside
                         outline(0.5 * MIN_CUT, 2.0, -1.0, 2.0),  # a sliver: the middle instead
                         outline(-2.0, 3.0, 3.0, 4.0)])  # beside the patch: nothing crosses it
    np.testing.assert_allclose(outline_cuts(patches, rows, outlines),
                               [[0.6, 0.45], [0.3, 0.7], [0.5, 0.5], [0.5, 0.5]], atol=1e-9)
    turned = outline(0.3, 0.6, 0.2, 0.45)[[0, 1, 2, 3]].copy()
    turned[:, :2] = (turned[:, :2] - turned[:, :2].mean(axis=0)) @ np.array([[0.8, -0.6], [0.6, 0.8]]) \
        + turned[:, :2].mean(axis=0)
    np.testing.assert_allclose(outline_cuts(patches, rows[:1], turned[None]), [[0.5, 0.5]])  # no edge along a side


def test_no_ceiling_patch_lies_astride_the_outline_of_an_emitter_under_it(gpu):
    """An emitter 5 mm under a ceiling, its outline off the ceiling's halving grid (as in the
    Cornell box): the trapped light is ~30 x the room's, and a ceiling patch half over the emitter
    would send that mean into the room from its outer half. Every ceiling patch lies on one side
    of the outline: cut along it, not halved across it."""
    gap = 0.005
    room = light_under_ceiling(gap)
    x0, x1, y0, y1 = 0.71, 1.17, 0.83, 1.29
    room["surfaces"][2]["vertices"] = [[x, y, 2.0 - gap] for x, y in [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]][::-1]
    scene = scene_from_dict(room)
    solution = solve(scene, solve_settings(method="hemicube", patch_size=2.0, refinements=6, tolerance=1e-2,
                                          emitter_gap_resolution=8.0), gpu=gpu)
    patches = solution.patches
    ceiling = patches.corners[(patches.surface == 1) & ~patches.is_back]
    inside_x = (ceiling[..., 0] > x0 - 1e-9) & (ceiling[..., 0] < x1 + 1e-9)
    inside_y = (ceiling[..., 1] > y0 - 1e-9) & (ceiling[..., 1] < y1 + 1e-9)
    over = (inside_x & inside_y).all(axis=1)
    beside = ((ceiling[..., 0] <= x0 + 1e-9).all(axis=1) | (ceiling[..., 0] >= x1 - 1e-9).all(axis=1)
              | (ceiling[..., 1] <= y0 + 1e-9).all(axis=1) | (ceiling[..., 1] >= y1 - 1e-9).all(axis=1))
    assert over.sum() >= 4 and (over | beside).all(), f"{(~(over | beside)).sum()} ceiling patches lie astride"
    size = np.sqrt(patches.area[(patches.surface == 1) & ~patches.is_back])
    assert size.min() < 8.0 * gap * 1.01  # and the rim is still resolved down to the gap rule's size


def test_refinement_keeps_within_a_patch_budget_counting_back_sides():
    scene = scene_from_dict(light_under_ceiling(0.01))
    backs = np.ones(len(scene), dtype=bool)
    patches = subdivide(scene, 2, 0.5, backs)
    wanted = np.zeros(len(patches))
    wanted[:6] = wanted[-2:] = 1.0  # fronts and backs, by priority
    for budget in (len(patches) + 7, len(patches) + 20, len(patches) + 100):
        split = split_patches(patches, within_budget(patches, wanted, budget), backs)
        assert len(split) <= budget
    assert len(split_patches(patches, within_budget(patches, wanted, 10**6), backs)) > len(patches) + 20


def test_hemicubes_see_an_emitter_four_millimetres_away_in_a_large_scene(gpu):
    """A hemi-cube's near plane once sat at 1e-3 of the scene's diameter: here 5 mm, which clipped
    the emitter 4 mm above the receiver away (the ceiling above a light plane got no light)."""
    data = opposed_squares(0.004, receiver_reflectance=0.5, emitter_emission=1.0)
    data["surfaces"].append(surface("far", [[5, 0, 0], [5, 0, 1], [5, 1, 1], [5, 1, 0]], 0.0, 0.0))
    scene = scene_from_dict(data)
    assert np.linalg.norm(scene.bounds[1] - scene.bounds[0]) > 5.0
    solution = solve(scene, solve_settings(method="hemicube", subdiv=4, hemicube_res=64, refinements=0,
                                          skip_unneeded=False), gpu=gpu)
    receiver = ~solution.patches.is_back & (solution.patches.surface == 0)
    inner = receiver & (np.abs(solution.patches.center[:, :2] - 0.5).max(axis=1) < 0.3)
    # F from an inner point to the square 4 mm above it is 0.98 or more: B = 0.5 F
    assert solution.patch_radiosity[inner, 0].min() > 0.48
    assert solution.patch_radiosity[receiver, 0].max() <= 0.5 + 1e-3  # and never more than all of it


def test_each_round_probes_only_the_patches_it_made_and_the_probe_is_the_ray_cast_light(gpu):
    """Refinement's probe (the texel pass at element centres) against a ray-cast reference on the
    box scene of test_texel_light, and after a split: the patches a round left alone are found
    (corners, surface, side), and the light they carry over is what probing them again gives."""
    from scenes import box_faces
    from test_texel_light import occluded_emitter_light

    from radiosity_addon.core.refinement import probe_direct, probe_shooters, unchanged_patches

    def probe_light(*args):  # lamps' and emitters' light plus the sky's
        return sum(probe_direct(*args))

    low, high = np.array([0.8, 0.8, 0.0]), np.array([1.2, 1.2, 0.4])
    emitter = [[0.75, 0.75, 1.5], [0.75, 1.25, 1.5], [1.25, 1.25, 1.5], [1.25, 0.75, 1.5]]
    floor = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
    scene = scene_from_dict({"surfaces": [surface("floor", floor, 0.5, 0.0)]
                             + [surface(f"box {k}", c, 0.5, 0.0, obj="box") for k, c in enumerate(box_faces(low, high))]
                             + [surface("emitter", emitter, 0.0, 10.0)]})
    effects, backs = effects_for(scene, True)
    settings = solve_settings(patch_size=0.5)
    patches = subdivide(scene, None, 0.5, backs)
    shooters = probe_shooters(scene, patches, effects)
    light = probe_light(gpu, scene, patches, np.arange(len(patches)), shooters, settings, effects, 4)
    floor_rows = np.flatnonzero(patches.surface == 0)
    s = (np.arange(4) + 0.5) / 4  # the element centres, row by row
    points = bilinear(patches.corners[floor_rows], *np.meshgrid(s, s)).reshape(-1, 3)
    exact = occluded_emitter_light(points, emitter, 10.0, low, high)
    measured = light[floor_rows].reshape(-1, 3)[:, 0]
    assert exact.max() > 0.2 and (exact == 0).sum() > 10
    # exact but in the penumbra, where each of the emitter's 8 x 8 pieces is seen or not as a whole
    assert np.abs(measured - exact).max() < 0.04 * exact.max()
    assert np.sqrt(((measured - exact) ** 2).mean()) < 0.005 * exact.max()
    # draft's and good's probe (`probe_pieces` 4): 4 x 4 pieces, a coarser penumbra, exact outside it
    coarse_shooters = probe_shooters(scene, patches, effects, 4)
    assert len(coarse_shooters) == 16 and len(shooters) == 64
    coarse = probe_light(gpu, scene, patches, floor_rows, coarse_shooters, settings, effects, 4).reshape(-1, 3)[:, 0]
    umbra_or_lit = (exact == 0) | (exact > 0.999 * occluded_emitter_light(points, emitter, 10.0, low, low))
    np.testing.assert_allclose(coarse[umbra_or_lit], exact[umbra_or_lit], rtol=2e-3, atol=1e-4 * exact.max())
    assert np.abs(coarse - exact).max() < 0.04 * exact.max()

    split = np.zeros(len(patches), dtype=bool)
    split[floor_rows[:3]] = True
    after = split_patches(patches, split, backs)
    of = unchanged_patches(patches, after)
    assert (of < 0).sum() == 12 and len(after) == len(patches) + 9
    kept = np.flatnonzero(of >= 0)
    np.testing.assert_array_equal(after.corners[kept], patches.corners[of[kept]])
    again = probe_light(gpu, scene, after, kept, probe_shooters(scene, after, effects), settings, effects, 4)
    np.testing.assert_allclose(again, light[of[kept]], atol=1e-3 * exact.max())


def test_the_hemicube_method_measures_only_the_direct_light_refinement_did_not(gpu, monkeypatch):
    """Refinement hands on the direct light it measured; the hemi-cube method measures the patches
    its last round made and takes the rest: the same light as measuring every patch again."""
    from radiosity_addon.core.hemicube import method
    from radiosity_addon.core.refinement import refine
    from radiosity_addon.core.timing import StageTimer

    scene = scene_from_dict(light_under_ceiling(0.01))
    effects, backs = effects_for(scene, True)
    settings = solve_settings(method="hemicube", patch_size=0.5, elements=1, hemicube_elements=1, refinements=2,
                             probe_pieces=4)
    patches, refined, measured = refine(gpu, scene, subdivide(scene, None, 0.5, backs), backs, settings, effects,
                                        StageTimer())
    assert len(refined) == 2 and 0 < (~measured.known).sum() < len(patches) and measured.elements == 4
    measured_rows = []
    original = method.direct_light_at_elements
    monkeypatch.setattr(method, "direct_light_at_elements",
                        lambda res, scene, patches, rows, *rest, **kw: measured_rows.append(rows) or original(
                            res, scene, patches, rows, *rest, **kw))
    again = method.direct_light(gpu, scene, patches, settings, effects, 1)
    taken = method.direct_light(gpu, scene, patches, settings, effects, 1, measured)
    np.testing.assert_array_equal(measured_rows[0], np.arange(len(patches)))
    np.testing.assert_array_equal(measured_rows[1], np.flatnonzero(~measured.known))
    scale = again[0].max()
    assert scale > 0
    np.testing.assert_allclose(taken[0], again[0], atol=1e-4 * scale)
    np.testing.assert_allclose(taken[1], again[1], atol=1e-4 * scale)


def test_a_patch_whose_centre_a_small_surface_hides_is_split(gpu):
    """The bundled Cornell box's light hangs 5 mm under the ceiling, its unlit back up: with the
    whole ceiling one patch (as `good`'s 1 m patches made it) it gathered its light at its centre,
    right over the light's back, and came out black (1e-4 against 0.064). Split, its patches gather
    beside the light and agree with `final`'s finer ones; the walls it lights agree too."""
    scene = load_scene("cornell-box")
    names = [scene.surface(i).name for i in range(len(scene))]

    def mean_radiosity(solution, name):
        patches = solution.patches
        mask = ~patches.is_back & (patches.surface == names.index(name))
        light = solution.patch_radiosity[mask].mean(axis=1)
        return float((light * patches.area[mask]).sum() / patches.area[mask].sum()), int(mask.sum())

    unrefined = solve(scene, solve_settings(quality="good", method="hemicube", hemicube_res=32,
                                            hemicube_elements=1, refinements=0, subdiv=1), gpu=gpu)
    good = solve(scene, solve_settings(quality="good", method="hemicube", hemicube_res=32, hemicube_elements=1,
                                       subdiv=1), gpu=gpu)
    fine = solve(scene, solve_settings(quality="final", method="hemicube", hemicube_res=32, hemicube_elements=1),
                 gpu=gpu)
    assert mean_radiosity(unrefined, "ceiling") == (pytest.approx(0.0, abs=1e-3), 1)  # the fault, unrefined
    ceiling, pieces = mean_radiosity(good, "ceiling")
    assert pieces >= 4 and ceiling == pytest.approx(mean_radiosity(fine, "ceiling")[0], rel=0.05)
    for wall in ("left_wall_upper", "right_wall", "back_wall"):
        assert mean_radiosity(good, wall)[0] == pytest.approx(mean_radiosity(fine, wall)[0], rel=0.05)


def test_a_patch_is_never_larger_than_half_the_scene(gpu):
    """good's 1 m patches in the 55 cm Cornell box made every wall one sample of its light (the
    left wall's two triangles 8 % dark against Cycles): the solve caps the patch size at the
    scene's diameter / PATCHES_ACROSS_SCENE, says so in its report, and leaves a given subdivision
    and a scene larger than its patches alone."""
    from radiosity_addon.core.settings import PATCHES_ACROSS_SCENE

    scene = load_scene("cornell-box")
    capped = solve(scene, solve_settings(quality="good", method="hemicube", hemicube_res=16, hemicube_elements=1,
                                         refinements=0), gpu=gpu)
    assert capped.report.settings.patch_size == pytest.approx(scene.diameter / PATCHES_ACROSS_SCENE)
    assert capped.report.settings.patch_size < 0.5 and len(capped.patches) > len(scene)
    subdivided = solve(scene, solve_settings(quality="good", method="hemicube", hemicube_res=16,
                                             hemicube_elements=1, refinements=0, subdiv=1), gpu=gpu)
    assert subdivided.report.settings.patch_size == 1.0 and len(subdivided.patches) == len(scene)
