"""The texel pass's visibility from the surfaces (`shooting.surface_visibility`), not the patches:
the same light as the patches' own item buffers give, whatever refinement did to the split, and
the atlas kept on the GPU and drawn once for the same shots."""

from __future__ import annotations

import numpy as np

from radiosity_addon.core import load_scene, subdivide
from radiosity_addon.core.gpu import GPU
from radiosity_addon.core.gpu.resources import MAX_KEPT
from radiosity_addon.core.refinement import probe_shooters
from radiosity_addon.core.scene import split_patches, surface_patches
from radiosity_addon.core.scene.analysis import effects_for
from radiosity_addon.core.shooting import ShotVisibility, TexelReceivers, surface_visibility
from radiosity_addon.core.shooting.direct import light_at_points
from radiosity_addon.core.shooting.sky import element_frames

RESOLUTION = 256


def refined_cornell_box():
    """The Cornell box split unevenly (every other patch once more), so that its patches are of
    mixed sizes with T-junctions between them, and the probe's shots (emitter pieces)."""
    scene = load_scene("cornell-box")
    effects, backs = effects_for(scene, True)
    patches = subdivide(scene, None, 0.25, backs)
    patches = split_patches(patches, np.arange(len(patches)) % 2 == 0, backs)
    return scene, patches, backs, effects, probe_shooters(scene, patches, effects, 4)


def points_of(patches, elements=3):
    points = element_frames(patches, elements)[0]
    return points, np.repeat(np.arange(len(patches)), elements * elements)


def light_from_patch_items(gpu, scene, patches, points, owners, shooters):
    """The texel pass with the patches' own item buffers (what it used before the surfaces')."""
    with gpu.resources() as res:
        shots = ShotVisibility(res, patches, RESOLUTION, "hemicube", scene.diameter)
        receivers = TexelReceivers(res, points, patches.normal[owners], patches.plane[owners], "exact", shots)
        receivers.shoot_all(shooters)
        return receivers.read_light()


def test_surface_patches_are_the_surfaces_with_the_same_backs():
    scene, patches, _, _, _ = refined_cornell_box()
    surfaces = surface_patches(scene, patches)
    assert surfaces.front_count == len(scene)
    np.testing.assert_array_equal(surfaces.surface[:len(scene)], np.arange(len(scene)))
    np.testing.assert_allclose(surfaces.area[:len(scene)].sum(), patches.area[~patches.is_back].sum(), rtol=1e-9)
    np.testing.assert_array_equal(np.unique(surfaces.surface[surfaces.is_back]),
                                  np.unique(patches.surface[patches.is_back]))


def test_the_surfaces_items_give_the_light_the_patches_items_give(gpu):
    scene, patches, _, effects, shooters = refined_cornell_box()
    assert effects.occlusion and len(shooters) >= 16
    points, owners = points_of(patches)
    ours = light_at_points(gpu.resources(), scene, patches, points, owners, shooters, "hemicube", RESOLUTION, True)
    theirs = light_from_patch_items(gpu, scene, patches, points, owners, shooters)
    scale = theirs.max()
    lit = theirs.sum(axis=1) > 1e-3 * scale
    assert 0.3 < lit.mean() < 0.95  # lit and shadowed points alike
    differs = np.abs(ours - theirs).max(axis=1) > 1e-4 * scale
    assert differs.mean() < 0.01, differs.mean()  # a pixel at a patch edge here and there
    np.testing.assert_allclose(ours.sum(axis=0), theirs.sum(axis=0), rtol=2e-3)


def test_the_kept_atlas_is_drawn_once_for_the_same_shots_whatever_the_split():
    scene, patches, backs, _, shooters = refined_cornell_box()
    finer = split_patches(patches, np.ones(len(patches), dtype=bool), backs)
    assert len(finer) > len(patches)
    with GPU() as gpu:
        light_at_points(gpu.resources(), scene, patches, *points_of(patches), shooters, "hemicube", RESOLUTION, True)
        assert gpu.kept_count == 1
        with gpu.resources() as res:  # the kept atlas, as the next pass on the finer split will find it
            atlas = surface_visibility(res, scene, finer, RESOLUTION, "hemicube").atlas
        assert gpu.kept_count == 1 and atlas.draws_skipped == 0
        drawn = atlas.triangles_drawn
        again = light_at_points(gpu.resources(), scene, finer, *points_of(finer), shooters, "hemicube",
                                RESOLUTION, True)
        assert gpu.kept_count == 1 and atlas.draws_skipped == 1 and atlas.triangles_drawn == drawn
    with GPU() as fresh:  # what a GPU that kept nothing gives for the finer split
        expected = light_at_points(fresh.resources(), scene, finer, *points_of(finer), shooters, "hemicube",
                                   RESOLUTION, True)
    np.testing.assert_array_equal(again, expected)


class Released:
    def __init__(self, log, name):
        self.log, self.name = log, name

    def release(self):
        self.log.append(self.name)


def test_kept_objects_are_made_once_and_released_least_recently_used_first_and_on_close():
    released = []
    with GPU() as gpu:
        made = [gpu.kept(("test", k), lambda scope, k=k: scope.adopt(Released(released, k))) for k in range(MAX_KEPT)]
        assert gpu.kept(("test", 0), lambda scope: None) is made[0]  # kept; now the most recently used
        gpu.kept(("test", MAX_KEPT), lambda scope: scope.adopt(Released(released, MAX_KEPT)))
        assert released == [1] and gpu.kept_count == MAX_KEPT
    assert sorted(released) == list(range(MAX_KEPT + 1))
