"""compare.py's metrics on small arrays whose answers are worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from bench import compare


def image(*texels):
    """A one-row lightmap of (r, g, b, alpha) texels."""
    return np.array([texels], dtype=np.float64)


OURS = {"A": image((2, 2, 3, 1), (1, 2, 3, 1)), "B": image((9, 9, 9, 1), (1, 0, 0, 1))}
REFERENCE = {"A": image((1, 2, 3, 1), (1, 2, 3, 1)), "B": image((0, 0, 0, 0), (2, 0, 0, 1))}


def test_texel_rms_counts_every_common_texel_once():
    texels = compare.common_texels(OURS, REFERENCE)
    assert [m.tolist() for m in texels.values()] == [[[True, True]], [[False, True]]]  # B's first: not baked
    # A: |(1, 0, 0)|² = 1 against 2 · (1 + 4 + 9) = 28; B: |(−1, 0, 0)|² = 1 against 4
    assert compare.texel_relative_rms(OURS, REFERENCE, texels) == pytest.approx(np.sqrt(2 / 32))


def test_mask_limits_the_texels():
    texels = compare.common_texels(OURS, REFERENCE, {"A": np.array([[True, False]])})
    assert compare.texel_relative_rms(OURS, REFERENCE, texels) == pytest.approx(np.sqrt(2 / 18))


def test_object_means_errors_and_worst_object():
    errors = compare.object_errors(OURS, REFERENCE, compare.common_texels(OURS, REFERENCE))
    assert errors["A"]["ours"] == pytest.approx([1.5, 2, 3])
    assert errors["A"]["relative"] == pytest.approx([0.5, 0, 0])
    assert errors["A"]["relative_rgb"] == pytest.approx(0.5 / 6)
    assert errors["B"]["relative"][0] == pytest.approx(-0.5)
    assert np.isnan(errors["B"]["relative"][1:]).all()  # the reference's green and blue are 0
    assert errors["B"]["texels"] == 1
    assert (errors["A"]["rms"], errors["B"]["rms"]) == (pytest.approx(np.sqrt(1 / 28)), pytest.approx(0.5))
    assert compare.worst_object(errors) == ("B", pytest.approx(-0.5))


def test_compare_summary_inside_and_out():
    result = compare.compare(OURS, REFERENCE, inside={"A": np.array([[True, False]]), "B": np.array([[True, True]])})
    assert result["texel_rms"] == pytest.approx(0.25)
    assert result["texel_rms_inside"] == pytest.approx(1 / 3)
    assert (result["texels"], result["texels_inside"]) == (3, 2)


def test_relative_noise():
    noise = {"A": image((0.1, 0, 0, 1), (0, 0.2, 0, 1)), "B": image((5, 5, 5, 0), (0, 0, 0, 1))}
    texels = compare.common_texels(OURS, REFERENCE)
    assert compare.relative_noise(noise, REFERENCE, texels) == pytest.approx(np.sqrt(0.05 / 32))


def test_object_balanced_rms_weighs_each_object_by_its_texels_not_its_brightness():
    texels = compare.common_texels(OURS, REFERENCE)
    # A: E = 1 / 28 over 2 texels; B: E = 1 / 4 over 1 texel (the plain texel RMS: sqrt(2 / 32))
    assert compare.object_balanced_rms(OURS, REFERENCE, texels) == pytest.approx(np.sqrt((2 / 28 + 1 / 4) / 3))
    bright = {name: image * np.array([10.0, 10.0, 10.0, 1.0]) if name == "A" else image
              for name, image in REFERENCE.items()}
    brighter_ours = {name: OURS[name] * np.array([10.0, 10.0, 10.0, 1.0]) if name == "A" else OURS[name]
                     for name in OURS}  # A ten times as bright, its error too: no change balanced
    assert compare.object_balanced_rms(brighter_ours, bright, texels) == pytest.approx(np.sqrt((2 / 28 + 1 / 4) / 3))
    assert compare.texel_relative_rms(brighter_ours, bright, texels) == pytest.approx(np.sqrt(101 / 2804))


def test_object_balanced_rms_takes_the_references_noise_out():
    texels = compare.common_texels(OURS, REFERENCE)
    noise = {"A": image((0.5, 0, 0, 1), (0, 0.5, 0, 1)), "B": image((0, 0, 0, 0), (2, 0, 0, 1))}
    # A: 1 − 0.5 = 0.5 against 28; B: 1 − 4 < 0 leaves 0
    assert compare.object_balanced_rms(OURS, REFERENCE, texels, noise) == pytest.approx(np.sqrt(2 * 0.5 / 28 / 3))
    result = compare.compare(OURS, REFERENCE, noise=noise)
    assert result["balanced_bias"] == pytest.approx(np.sqrt(2 * 0.5 / 28 / 3))
    assert result["balanced_rms"] == pytest.approx(np.sqrt((2 / 28 + 1 / 4) / 3))


def test_sizes_must_match():
    with pytest.raises(ValueError, match="bake the reference at our sizes"):
        compare.common_texels({"A": np.zeros((2, 2, 4))}, {"A": np.zeros((2, 3, 4))})


def test_rasterized_positions_interpolate_the_corners_and_areas_divide_the_surface():
    # the UV square in two triangles onto the world rectangle x ∈ [0, 2], y ∈ [0, 1] at z = 5
    uv = np.array([[(0, 0), (1, 0), (1, 1)], [(0, 0), (1, 1), (0, 1)]], dtype=float)
    world = np.array([[(0, 0, 5), (2, 0, 5), (2, 1, 5)], [(0, 0, 5), (2, 1, 5), (0, 1, 5)]], dtype=float)
    positions, areas = compare.rasterize_texels(uv, world, width=4, height=2)
    rows, columns = np.mgrid[0:2, 0:4]
    expected = np.stack([(columns + 0.5) / 2, (rows + 0.5) / 2, np.full((2, 4), 5.0)], axis=-1)
    np.testing.assert_allclose(positions, expected, atol=1e-12)
    np.testing.assert_allclose(areas, 2.0 / 8)  # 2 m² over 8 texels


def test_rasterizing_one_triangle_covers_the_texel_centres_inside_it():
    # the lower right half of a 4 × 4 map: centres with v ≤ u, the diagonal's 4 included: 10 texels
    uv = np.array([[(0, 0), (1, 0), (1, 1)]], dtype=float)
    world = np.array([[(0, 0, 0), (3, 0, 0), (3, 0, 3)]], dtype=float)  # 4.5 m² on 8 texels' worth of UV
    positions, areas = compare.rasterize_texels(uv, world, width=4, height=4)
    covered = ~np.isnan(positions[..., 0])
    rows, columns = np.mgrid[0:4, 0:4]
    assert covered.tolist() == (rows <= columns).tolist()
    np.testing.assert_allclose(areas[covered], 4.5 / 8)


def test_weights_make_the_rms_area_weighted():
    texels = compare.common_texels(OURS, REFERENCE)
    weights = {"A": np.array([[3.0, 1.0]]), "B": np.array([[np.nan, 2.0]])}  # B's first is not compared anyway
    # A: 3 · 1 against (3 + 1) · 14; B: 2 · 1 against 2 · 4
    assert compare.texel_relative_rms(OURS, REFERENCE, texels, weights) == pytest.approx(np.sqrt(5 / 64))
    assert compare.compare(OURS, REFERENCE, weights=weights)["texel_rms"] == pytest.approx(np.sqrt(5 / 64))
    weights["A"] = np.array([[np.nan, 1.0]])  # a texel without a weight counts 0: A gives 0 against 14
    assert compare.texel_relative_rms(OURS, REFERENCE, texels, weights) == pytest.approx(np.sqrt(2 / 22))


def test_inside_box_with_margin_and_uncovered_texels():
    positions = np.array([[(0.5, 0.5, 0.5), (-0.005, 0.2, 0.2), (-0.05, 0.2, 0.2), (np.nan, np.nan, np.nan)]])
    inside = compare.inside_box(positions, (0, 0, 0), (1, 1, 1), margin=0.01)
    assert inside.tolist() == [[True, True, False, False]]


def test_cycles_to_reach_interpolates_between_the_rows_that_bracket_the_error():
    """error = 0.4 n^-0.5 and seconds = 0.2 + 0.02 n are recovered exactly between rows; an
    error outside the rows has no answer."""
    rows = [(n, 0.2 + 0.02 * n, 0.4 * n ** -0.5) for n in (16, 64, 80, 96, 256)]
    reached = compare.cycles_to_reach(0.05, rows[::-1])  # 64 samples
    assert reached["between"] == (16, 64)
    assert reached["samples"] == pytest.approx(64.0) and reached["seconds"] == pytest.approx(1.48)
    reached = compare.cycles_to_reach(0.4 * 90 ** -0.5, rows)
    assert reached["between"] == (80, 96)
    assert reached["samples"] == pytest.approx(90.0) and reached["seconds"] == pytest.approx(2.0)
    assert compare.cycles_to_reach(0.2, rows) is None and compare.cycles_to_reach(0.01, rows) is None


def test_without_reference_noise_takes_the_noise_out_of_the_squared_error():
    assert compare.without_reference_noise(0.05, 0.014) == pytest.approx((0.05 ** 2 - 0.014 ** 2) ** 0.5)
    assert compare.without_reference_noise(0.01, 0.014) == 0.0


def test_pictures_show_ours_cycles_and_the_signed_difference(tmp_path):
    from bench import pictures
    reference = np.ones((8, 16, 4))
    reference[..., :3] = 0.5
    ours = reference.copy()
    ours[:, :4, :3] = 0.75  # +50 %: full red
    ours[:, 4:8, :3] = 0.25  # -50 %: full blue
    ours[0, :, 3] = 0.0  # not covered (our bottom row): black in every panel
    picture = pictures.side_by_side(ours, reference)
    scale = 256 // 16
    assert picture.shape == (8 * scale, 3 * 16 * scale + 2 * pictures.GAP, 3)
    third = 16 * scale + pictures.GAP
    difference = picture[:, 2 * third:]
    top = 0  # Blender's row 7, the top of the picture
    assert tuple(difference[top, 0]) == (230, 40, 30) and tuple(difference[top, 5 * scale]) == (30, 80, 230)
    assert tuple(difference[top, 10 * scale]) == (128, 128, 128)
    panels = np.concatenate([picture[-1, k * third:k * third + 16 * scale] for k in range(3)])
    assert not panels.any()  # row 0 of the lightmaps, uncovered, is the picture's last row
    # one exposure: the reference's 99th percentile is white, ours as bright there
    assert tuple(picture[top, third + 10 * scale]) == (255, 255, 255) == tuple(picture[top, 10 * scale])
    written = pictures.write_pictures(tmp_path, "good_", {"Floor Tiles": ours}, {"Floor Tiles": reference})
    assert [path.name for path in written] == ["good_Floor_Tiles.png"] and written[0].read_bytes()[:4] == b"\x89PNG"
