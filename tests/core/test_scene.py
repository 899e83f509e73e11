"""Scene model: loading, validation (through the CLI: one line, no traceback), subdivision."""

import json
import subprocess
import sys

import numpy as np
import pytest
from scenes import closed_cube, surface

from radiosity_addon.core import subdivide
from radiosity_addon.core import SceneError, load_scene, save_scene, scene_from_dict

SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]


def one_surface(**changes):
    entry = surface("panel", SQUARE, 0.5, 1.0)
    entry.update(changes)
    return {"surfaces": [entry]}


INVALID_SCENES = {
    "nan coordinate": (one_surface(vertices=[[0, 0, 0], [1, 0, 0], [1, float("nan"), 0], [0, 1, 0]]), "NaN"),
    "infinite coordinate": (one_surface(vertices=[[0, 0, 0], [1, 0, 0], [1, float("inf"), 0]]), "infinite"),
    "two vertices": (one_surface(vertices=[[0, 0, 0], [1, 0, 0]]), "3 or 4 vertices"),
    "five vertices": (one_surface(vertices=SQUARE + [[0.5, 1.5, 0]]), "3 or 4 vertices"),
    "zero area": (one_surface(vertices=[[0, 0, 0], [1, 0, 0], [2, 0, 0]]), "zero area"),
    "non-planar": (one_surface(vertices=[[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]]), "not planar"),
    "non-convex": (one_surface(vertices=[[0, 0, 0], [1, 0, 0], [0.2, 0.2, 0], [0, 1, 0]]), "not convex"),
    "reflectance one": (one_surface(reflectance=[1.0, 0.5, 0.5]), "reflectance"),
    "negative reflectance": (one_surface(reflectance=[-0.1, 0.5, 0.5]), "reflectance"),
    "negative emission": (one_surface(emission=[1.0, -1.0, 0.0]), "emission"),
    "no emitter": (one_surface(emission=[0, 0, 0]), "nothing emits"),
}


@pytest.mark.parametrize("case", sorted(INVALID_SCENES))
def test_invalid_scene_refused_by_cli_in_one_line(case, tmp_path):
    data, expected = INVALID_SCENES[case]
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(data))  # json writes NaN/Infinity literals, which the loader accepts
    result = subprocess.run(
        [sys.executable, "-m", "radiosity_addon", "solve", str(path), "--method", "hemicube", "--quiet"],
        capture_output=True, text=True, timeout=120,
    )
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    assert expected in lines[0]
    if case not in ("no emitter",):
        assert "'panel'" in lines[0]  # the message names the surface


def test_missing_scene_file_is_one_line(tmp_path):
    result = subprocess.run([sys.executable, "-m", "radiosity_addon", "solve", str(tmp_path / "nope.json")],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "does not exist" in result.stderr


def test_bundled_cornell_box_round_trips(tmp_path):
    scene = load_scene("cornell-box")
    assert len(scene.surfaces) == 17
    assert set(scene.objects) == {"floor", "ceiling", "back_wall", "right_wall", "left_wall",
                                  "short_block", "tall_block", "light"}
    light = next(s for s in scene.surfaces if s.name == "light")
    assert light.normal[1] < -0.99 and np.all(light.emission > 0)
    save_scene(scene, tmp_path / "copy.json")
    copy = load_scene(tmp_path / "copy.json")
    for a, b in zip(scene.surfaces, copy.surfaces):
        assert a.name == b.name and a.object_name == b.object_name
        np.testing.assert_array_equal(a.vertices, b.vertices)


def test_duplicate_names_refused():
    data = {"surfaces": [surface("a", SQUARE, 0.5, 1.0), surface("a", SQUARE, 0.5, 1.0)]}
    with pytest.raises(SceneError, match="'a'"):
        scene_from_dict(data)


@pytest.mark.parametrize("n", [1, 3, 5])
def test_subdivision_preserves_area_and_orientation(n):
    scene = load_scene("cornell-box")
    patches = subdivide(scene, n)
    assert len(patches) == 17 * n * n  # quads split n x n, triangles into n^2 triangles
    for index, surf in enumerate(scene.surfaces):
        mask = patches.surface == index
        assert patches.area[mask].sum() == pytest.approx(surf.area, rel=1e-9)
        assert np.all(patches.normal[mask] @ surf.normal > 0.999)
        # centres lie on the surface's plane
        offsets = (patches.center[mask] - surf.vertices[0]) @ surf.normal
        assert np.abs(offsets).max() < 1e-9


def test_subdivided_triangle_patches_tile_the_triangle():
    tri = [[0, 0, 0], [2, 0, 0], [0, 1, 0]]
    scene = scene_from_dict({"surfaces": [surface("t", tri, 0.5, 1.0)]})
    patches = subdivide(scene, 4)
    assert np.allclose(patches.area, 1.0 / 16)  # n^2 congruent triangles of the parent's area 1
    # the patch centres are distinct points inside the triangle
    c = patches.center
    assert np.all(c[:, 0] >= 0) and np.all(c[:, 1] >= 0) and np.all(c[:, 0] / 2 + c[:, 1] <= 1)
    assert len(np.unique(np.round(c, 9), axis=0)) == 16


def test_closed_cube_builder_faces_inward():
    scene = scene_from_dict(closed_cube())
    for surf in scene.surfaces:
        assert (np.array([0.5, 0.5, 0.5]) - surf.vertices.mean(axis=0)) @ surf.normal > 0


def test_a_world_colour_alone_counts_as_an_emitter_and_a_black_one_does_not():
    dark = one_surface(emission=[0, 0, 0])
    assert scene_from_dict({**dark, "world": {"color": [0.2, 0.3, 0.5]}}).extras["world"]["color"] == [0.2, 0.3, 0.5]
    with pytest.raises(SceneError, match="nothing emits"):
        scene_from_dict({**dark, "world": {"color": [0, 0, 0]}})


@pytest.mark.parametrize("dtype", [np.int64, np.float64])
def test_row_labels_are_np_uniques_inverse(dtype):
    """scene.rows.row_labels: the labels np.unique(axis=0, return_inverse=True) gives, for integer
    keys and float ones (-0.0 and 0.0 alike), and for no rows and one."""
    from radiosity_addon.core.scene.rows import row_labels

    rng = np.random.default_rng(11)
    rows = (rng.integers(-4, 4, (3000, 6)) * 0.37).astype(dtype)
    rows = np.concatenate([rows, rows[:1000]])
    if dtype is np.float64:
        rows[0, 0], rows[1, 0] = -0.0, 0.0
    expected = np.unique(rows, axis=0, return_inverse=True)[1].ravel()
    np.testing.assert_array_equal(row_labels(rows), expected)
    assert row_labels(rows[:0]).shape == (0,) and list(row_labels(rows[:1])) == [0]
