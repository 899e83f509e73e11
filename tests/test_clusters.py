"""Clusters of patches that shoot as one (progressive refinement; core/progressive/clusters.py).

References: exact area-to-area form factors of the closed cube (test_progressive's), the same
patches shot one by one, and the hemi-cube method on the Cornell box.
"""

from __future__ import annotations

import numpy as np
import pytest

from test_progressive import cube, cube_face_reference, face_means

from radiosity_addon.core import SolveSettings, load_scene, solve, subdivide
from radiosity_addon.core.progressive.clusters import NORMAL_BINS, ClusterShooters, build_clusters, octahedral_bins
from radiosity_addon.core.shooting import ElementTextures, PatchBuffers, PatchShooters, ShootingPass, ShotVisibility


def test_clusters_hold_every_patch_once_near_each_other_and_facing_alike():
    patches = subdivide(load_scene("cornell-box"), 8)
    levels = build_clusters(patches, 128)
    clusters = levels[-1]
    assert len(levels) == 3 and 64 < len(clusters) <= 128
    assert [level.cell for level in levels] == pytest.approx([clusters.cell / 4, clusters.cell / 2, clusters.cell])
    for finer, coarser in zip(levels, levels[1:]):  # nested: a finer cluster lies in one coarser cluster
        pairs = np.unique(np.stack([finer.of_patch, coarser.of_patch], axis=1), axis=0)
        assert len(pairs) == len(finer) > len(coarser)
    assert sorted(clusters.by_cluster.tolist()) == list(range(len(patches)))
    assert clusters.members.sum() == len(patches) and np.all(clusters.members >= 1)
    for c in range(len(clusters)):
        members = clusters.members_of(c)
        assert np.all(clusters.of_patch[members] == c)
        centers, normals = patches.center[members], patches.normal[members]
        assert np.all(np.ptp(centers, axis=0) <= clusters.cell * (1 + 1e-9))  # one grid cell
        mean = normals.sum(axis=0) / np.linalg.norm(normals.sum(axis=0))
        assert np.all(normals @ mean > np.cos(np.radians(30)))  # one normal bin
        offsets = (normals * centers).sum(axis=1)
        assert np.ptp(offsets) <= 0.5 * clusters.cell * (1 + 1e-9)  # a block's face and the wall behind it part
    # fewer patches than the target: no grouping beyond the smallest cell
    assert len(build_clusters(subdivide(load_scene("cornell-box"), 1), 4096)[-1]) == 17


def test_octahedral_bins_are_about_twenty_degrees_wide():
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(200_000, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    bins = octahedral_bins(normals)
    assert set(np.unique(bins)) == set(range(NORMAL_BINS ** 2))
    widest = 0.0
    for b in range(NORMAL_BINS ** 2):
        group = normals[bins == b]
        mean = group.sum(axis=0) / np.linalg.norm(group.sum(axis=0))
        widest = max(widest, np.degrees(np.arccos(np.clip(group @ mean, -1, 1))).max())
    assert 15 < widest < 30


def test_a_uniform_cluster_shoots_what_its_patches_shoot_one_by_one(gpu):
    """A quadrant of the cube's floor (4 x 4 patches of uniform unshot radiosity) as one shot: the
    opposite face gets what the sixteen patch shots give it, to 1 %, and the shot hits the rest of
    the closed cube entirely; every member's residual is cleared."""
    scene = cube(0.5, {"ceiling": 1.0})
    patches = subdivide(scene, 8)
    levels = build_clusters(patches, 48)
    clusters = levels[-1]
    members = clusters.members_of(0)
    assert len(members) == 16
    power = np.zeros(len(patches))
    power[members] = patches.area[members]
    cluster_shot = ClusterShooters(patches, clusters, level=len(levels)).shooter(0, np.full(3, power.sum()), power)
    assert cluster_shot.area == pytest.approx(patches.area[members].sum(), rel=1e-9)

    patches.emission[:] = 1.0  # every residual starts at 1: the shot must clear its members' only

    def shoot(shooters):
        with gpu.resources() as res:
            textures = ElementTextures(res, patches, 2)
            shooting = ShootingPass(res, textures, PatchBuffers(res, patches, textures, np.stack([c.of_patch for c in levels], axis=1)), "exact",
                                    ShotVisibility(res, patches, 256, "hemicube", scene.diameter))
            shooting.shoot(shooters)
            return textures.read_light(), textures.read_residual(), shooting.read_energy(len(shooters))

    light, residual, energy = shoot([cluster_shot])
    single = PatchShooters(patches)
    one_by_one = [shoot([single.shooter(int(p), np.ones(3))]) for p in members]
    reference = sum(shot[0] for shot in one_by_one)
    floor_normal = patches.normal[members[0]]
    opposite = np.where(patches.normal @ floor_normal < -0.99)[0]
    assert light[opposite].sum() == pytest.approx(reference[opposite].sum(), rel=0.01)
    assert energy[0, 0] == pytest.approx(1.0, abs=0.01)
    assert np.all(residual[members] == 0)
    others = np.setdiff1d(np.arange(len(patches)), members)
    assert np.all(residual[others] > 0)


def test_a_clustered_solve_of_the_closed_cube_matches_exact_form_factors_with_far_fewer_shots(gpu):
    scene = cube(0.9, {"ceiling": 1.0})
    reference = cube_face_reference(0.9, np.array([s.emission[0] for s in scene.surfaces]))
    settings = dict(subdiv=8, elements=2, tolerance=1e-3, refinements=0)
    alone = solve(scene, SolveSettings(**settings, shooter_clusters=0), gpu=gpu)
    clustered = solve(scene, SolveSettings(**settings, shooter_clusters=48), gpu=gpu)
    work = clustered.report.details.work
    assert work.shooter_clusters == 24 and work.cluster_shots > 0.5 * clustered.report.details.shots
    assert alone.report.details.work.shooter_clusters == 0
    assert clustered.report.details.shots < 0.2 * alone.report.details.shots
    means = face_means(clustered)[:, 0]
    assert np.all(np.abs(means / reference - 1) < 0.04), (means, reference)
    energy = clustered.report.details.energy
    assert energy["escaped"] + energy["surplus"] < 0.01 * energy["shot"]


def test_clusters_of_four_patches_keep_the_cornell_box_as_close_to_the_hemicube_in_a_third_of_the_shots(gpu):
    """Per-surface means, the same 8 x 8 patches (1 088, no refinement) in at most 256 clusters.
    Measured: 960 shots against 2 752, worst surface 4.2 % against 4.4 % (the short block's side b);
    with 128 clusters (8.5 patches each) the worst is 10 %."""
    scene = load_scene("cornell-box")
    hemicube = solve(scene, SolveSettings(method="hemicube", subdiv=8, hemicube_res=128, refinements=0), gpu=gpu)
    settings = dict(subdiv=8, elements=1, tolerance=1e-2, refinements=0)
    alone = solve(scene, SolveSettings(**settings, shooter_clusters=0), gpu=gpu)
    clustered = solve(scene, SolveSettings(**settings, shooter_clusters=256), gpu=gpu)
    assert clustered.report.details.work.cluster_shots > 0.5 * clustered.report.details.shots
    reference = face_means(hemicube)
    error = {name: np.abs(face_means(solution) - reference).max(axis=1) / reference.max(axis=1)
             for name, solution in (("alone", alone), ("clustered", clustered))}
    shown = " ".join(f"{d:.3f}" for d in error["clustered"]) + " / alone " + " ".join(f"{d:.3f}" for d in error["alone"])
    assert np.all(error["clustered"] < 0.06), shown
    assert error["clustered"].mean() < 1.5 * error["alone"].mean(), shown
    assert clustered.report.details.shots < 0.4 * alone.report.details.shots


def test_the_cost_model_counts_clusters_not_patches_as_shooters():
    from radiosity_addon.core.method_choice import predict_progressive

    patches = subdivide(load_scene("cornell-box"), 12)
    assert len(patches) > 2048
    settings = SolveSettings(shooter_clusters=1024)
    clustered = predict_progressive(patches, settings).seconds
    assert clustered == pytest.approx(predict_progressive(patches, settings, shooters=1024).seconds, rel=1e-12)
    alone = predict_progressive(patches, SolveSettings(shooter_clusters=0)).seconds
    assert alone == pytest.approx(clustered * len(patches) / 1024, rel=1e-9)
