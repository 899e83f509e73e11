"""Every stage of a bake grows about linearly with the scene: the benchmark's furnished room at
~1.2k and ~3.9k triangles (3.2 x), baked stage by stage as the add-on bakes it
(bench/scaling.py), each stage's time compared as a ratio. The progressive solve
runs a fixed number of shots, so its per-shot cost is what is compared; that a denser scene needs
no more shots is test_clusters.py's (the Cornell box at 4 x the patches), the rooms' counts the
bench's (tools/measure_scaling.py). The hemi-cube method's form factors are O(P^2)
by nature (its memory guard refuses large scenes before any work: test_hemicube.py)."""

from __future__ import annotations

import blender_support  # noqa: F401  (sets BLENDER_USER_RESOURCES before bpy loads)
import pytest

from bench.scaling import bake_room_in_stages

GROWTH = 1.3  # a stage may take at most (size ratio)^GROWTH the time (quadratic: ratio^2 = 10 x here)
FLOOR = 0.5  # seconds a stage may add whatever the ratio: start-up costs, and the scene analysis's
# pair tests, which stop at a fixed budget (scene/analysis.py PAIR_BUDGET: ~0.3 s at most)
SOLVE = {"quality": "draft", "method": "progressive", "max_shots": 64, "refinements": 1}


@pytest.fixture(scope="module")
def rooms():
    return [bake_room_in_stages(target, SOLVE, material_maps=False) for target in (1000, 4000)]


@pytest.mark.slow
def test_the_solve_and_the_lightmaps_grow_with_the_room_not_faster(rooms):
    small, big = rooms
    ratio = big["triangles"] / small["triangles"]
    assert 3.0 < ratio < 3.5 and big["shots"] == small["shots"] == 64
    assert big["patches"] <= ratio ** 1.1 * small["patches"], (big["patches"], small["patches"])
    assert big["texels"] <= ratio ** 1.1 * small["texels"], (big["texels"], small["texels"])
    stages = set(small["stage_seconds"]) | set(big["stage_seconds"])
    assert {"export", "analyse", "subdivide", "refine", "direct_light", "shoot", "lightmaps", "write-back"} <= stages


@pytest.mark.timing  # wall-clock ratios: `make test-timing`, on a quiet machine, not in `make test`
def test_every_stage_grows_about_linearly_with_the_room(rooms):
    small, big = rooms
    ratio = big["triangles"] / small["triangles"]
    stages = set(small["stage_seconds"]) | set(big["stage_seconds"])
    grown = {name: (small["stage_seconds"].get(name, 0.0), big["stage_seconds"].get(name, 0.0)) for name in stages}
    too_fast = {name: times for name, times in grown.items() if times[1] > ratio ** GROWTH * times[0] + FLOOR}
    assert not too_fast, (ratio, too_fast, grown)
