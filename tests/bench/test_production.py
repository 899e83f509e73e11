"""The production family (bench/production.py: dense triangulated furniture, a sculpt-like
boulder, a 20-material triangle soup, alpha-cut leaf cards) as the add-on exports it: what the
solve works on follows the terrace's area, not its triangles, whether the terrace is ten objects
or one holding every material. Times are the bench's (tools/measure_scaling.py --family
production); here only counts, which do not depend on the machine's load."""

from __future__ import annotations

import blender_support  # noqa: F401  (sets BLENDER_USER_RESOURCES before bpy loads)

import bpy
import numpy as np
import pytest

from radiosity_addon import core
from bench import production
from radiosity_addon.blender.export import export_scene
from radiosity_addon.blender.lights import render_lamps
from radiosity_addon.core.scene.face_clusters import cluster_faces
from radiosity_addon.core.settings import QUALITY_PRESETS

PATCH_SIZE = QUALITY_PRESETS["draft"]["solve"]["patch_size"]


def exported(triangles: int, objects: int):
    built = production.build_production(triangles, objects)
    context = bpy.context
    meshes = [obj for obj in context.scene.objects if obj.type == "MESH"]
    scene = export_scene(context.evaluated_depsgraph_get(), meshes, lamps=render_lamps(context.view_layer),
                         world=context.scene.world).scene
    return built, scene


@pytest.fixture(scope="module")
def terraces():
    return {key: exported(*key) for key in ((4000, 10), (16000, 10), (16000, 1))}


def test_the_surfaces_solved_follow_the_terraces_area_not_its_triangles(terraces):
    """Four times the triangles: the opaque pieces' surfaces stay about as many (their count moves
    with where the patch-size cuts fall), and every alpha-cut leaf card (two triangles) is one
    surface; the terrace holds more cards as it grows, each a surface of its own."""
    (small_built, small), (big_built, big) = terraces[4000, 10], terraces[16000, 10]
    ratio = big_built["triangles"] / small_built["triangles"]
    assert ratio > 3.0, ratio
    assert len(big) == big_built["triangles"] and len(small) == small_built["triangles"]
    counts = {}
    for name, scene in (("small", small), ("big", big)):
        clusters = cluster_faces(scene, PATCH_SIZE)
        card_face = scene.opacity_index >= 0
        card_proxy = np.zeros(len(clusters.proxies), dtype=bool)
        card_proxy[clusters.proxy_of_face[card_face]] = True
        assert card_proxy.sum() == card_face.sum() // 2  # a card's two triangles, one surface
        assert not card_proxy[clusters.proxy_of_face[~card_face]].any()  # no card merged with anything else
        counts[name] = int((~card_proxy).sum())
        # the surfaces stand for the faces' whole area
        assert np.isclose(clusters.proxies.area.sum(), scene.area.sum(), rtol=0.05)
    assert counts["big"] <= 1.5 * counts["small"], counts
    assert counts["big"] < (~(big.opacity_index >= 0)).sum() / 8, counts


def test_one_object_of_every_material_is_solved_like_the_ten_objects(terraces):
    (ten_built, ten), (one_built, one) = terraces[16000, 10], terraces[16000, 1]
    assert one_built["objects"] == 1 and ten_built["objects"] >= 10
    assert one_built["triangles"] == ten_built["triangles"]
    assert np.isclose(one.area.sum(), ten.area.sum(), rtol=1e-6)
    ten_clusters, one_clusters = cluster_faces(ten, PATCH_SIZE), cluster_faces(one, PATCH_SIZE)
    assert abs(len(one_clusters.proxies) - len(ten_clusters.proxies)) <= 0.1 * len(ten_clusters.proxies)
    # the leaf cards cut out by their material's alpha whichever object holds them
    assert one.opacity is not None and ten.opacity is not None
    assert np.isclose((one.opacity_index >= 0).sum(), (ten.opacity_index >= 0).sum())


def test_the_solvers_job_grows_with_the_triangles_it_holds(terraces, tmp_path):
    sizes = {}
    for key in ((4000, 10), (16000, 10)):
        built, scene = terraces[key]
        path = tmp_path / f"{key[0]}.npz"
        core.save_scene(scene, path)
        assert len(core.load_scene(path)) == built["triangles"]
        sizes[key] = path.stat().st_size / built["triangles"]
    assert sizes[16000, 10] < 1.2 * sizes[4000, 10], sizes
