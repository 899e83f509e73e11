"""Hemi-cube faces draw only the triangle clusters that reach into their frustum: never fewer
triangles than they can see (an independent point-sampled check), fewer than all, and the same
item buffers as drawing everything."""

from __future__ import annotations

import numpy as np

from radiosity_addon.core import load_scene, subdivide
from radiosity_addon.core.visibility import face_culling, hemicube


def random_triangles(count, rng, spread=0.1):
    """`count` small triangles scattered in a 10 m box, each with its own three vertices."""
    centres = rng.uniform(-5.0, 5.0, (count, 1, 3))
    corners = centres + rng.normal(0.0, spread, (count, 3, 3))
    return corners.reshape(-1, 3).astype(np.float32), np.arange(3 * count, dtype=np.uint32)


def random_faces(count, rng):
    eyes = rng.uniform(-4.0, 4.0, (count, 3))
    normals = rng.normal(size=(count, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    helper = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    tangents = np.cross(normals, helper)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    bitangents = np.cross(normals, tangents)
    return hemicube.face_instances((eyes, tangents, bitangents, normals), 8, 4, (32, 24 * ((count + 3) // 4)))


def seen_by_sampling(positions, instances, samples=12):
    """(I, T) whether any point of a barycentric grid on each triangle lies inside each face's
    frustum, from the face's own definition: c >= 0, |a| <= c, up_min c <= b <= c."""
    u, v = np.meshgrid(np.linspace(0, 1, samples), np.linspace(0, 1, samples))
    inside = u + v <= 1
    weights = np.stack([1 - u[inside] - v[inside], u[inside], v[inside]], axis=1)  # (S, 3)
    corners = positions.reshape(-1, 3, 3).astype(np.float64)
    points = np.einsum("sk,tkx->tsx", weights, corners)  # (T, S, 3)
    eye, right, up, forward, up_min = (instances[:, 0:3], instances[:, 3:6], instances[:, 6:9],
                                       instances[:, 9:12], instances[:, 16])
    offsets = points[None] - eye[:, None, None, :]  # (I, T, S, 3)
    a = np.einsum("itsx,ix->its", offsets, right)
    b = np.einsum("itsx,ix->its", offsets, up)
    c = np.einsum("itsx,ix->its", offsets, forward)
    inside = (c >= 0) & (np.abs(a) <= c) & (b <= c) & (b >= up_min[:, None, None] * c)
    return inside.any(axis=2)


def test_clusters_hold_every_triangle_once_in_bounded_compact_groups():
    rng = np.random.default_rng(5)
    positions, indices = random_triangles(4000, rng)
    clusters = face_culling.triangle_clusters(positions, indices, size=64)
    assert sorted(clusters.indices.tolist()) == indices.tolist()
    assert clusters.count.max() <= 3 * 64 and clusters.count.sum() == len(indices)
    np.testing.assert_array_equal(clusters.first, np.r_[0, np.cumsum(clusters.count)[:-1]])
    corners = positions[clusters.indices].reshape(-1, 3, 3)
    owner = np.repeat(np.arange(len(clusters)), clusters.count // 3)
    low = clusters.centre - clusters.half
    high = clusters.centre + clusters.half
    assert np.all(corners >= low[owner, None] - 1e-6) and np.all(corners <= high[owner, None] + 1e-6)
    # Morton order makes the boxes compact: far smaller than boxes of as many triangles taken at random
    random_groups = corners[rng.permutation(len(corners))][:len(corners) // 64 * 64].reshape(-1, 64 * 3, 3)
    random_diagonal = np.linalg.norm(random_groups.max(axis=1) - random_groups.min(axis=1), axis=1)
    assert np.median(np.linalg.norm(2 * clusters.half, axis=1)) < 0.5 * np.median(random_diagonal)


def test_every_face_draws_each_triangle_it_sees_and_culls_most_others():
    rng = np.random.default_rng(7)
    positions, indices = random_triangles(4000, rng)
    clusters = face_culling.triangle_clusters(positions, indices, size=16)
    instances = random_faces(12, rng).astype(np.float64)
    commands = face_culling.draw_commands(clusters, instances)
    assert commands.dtype == np.uint32 and commands.shape[1] == face_culling.COMMAND_WORDS
    assert np.all(commands[:, 1] == 1) and np.all(commands[:, 3] == 0)
    # which original triangle each drawn index range holds (every triangle has its own vertices)
    drawn = np.zeros((len(instances), len(indices) // 3), dtype=bool)
    for count, _, first, _, instance in commands:
        drawn[instance, clusters.indices[first:first + count:3] // 3] = True
    seen = seen_by_sampling(positions, instances)
    assert seen.sum() > 3000  # the check has something to check
    assert not np.any(seen & ~drawn)
    assert drawn.mean() < 0.5  # a face sees a fifth of the sphere at most


def test_culled_item_buffers_equal_drawing_everything(gpu, monkeypatch):
    scene = load_scene("cornell-box")
    patches = subdivide(scene, None, scene.diameter / 12, np.zeros(len(scene), dtype=bool))
    frames = hemicube.patch_frames(patches)
    slots = len(frames[0])  # every patch's hemi-cube, in one batch

    def items(commands):
        monkeypatch.setattr(hemicube, "draw_commands", commands)
        with gpu.resources() as res:
            atlas = hemicube.HemicubeAtlas(res, patches, 32, scene.diameter, max_slots=slots)
            atlas.draw(frames)
            return np.frombuffer(atlas.item_texture.read(), dtype=np.uint32), atlas.triangles_drawn

    def every_cluster(clusters, instances):
        instance, cluster = np.divmod(np.arange(len(instances) * len(clusters)), len(clusters))
        return np.stack([clusters.count[cluster], np.ones_like(cluster), clusters.first[cluster],
                         np.zeros_like(cluster), instance], axis=1).astype(np.uint32)

    everything, all_triangles = items(every_cluster)
    culled, culled_triangles = items(face_culling.draw_commands)
    assert slots > 100 and (everything > 0).mean() > 0.5
    np.testing.assert_array_equal(culled, everything)
    assert culled_triangles < 0.8 * all_triangles
