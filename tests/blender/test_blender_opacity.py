"""Alpha-cut materials in Blender: which materials let light through, their opacity as Cycles
evaluates it, and a floor under a cut-out card baked against Cycles texel by texel."""

from __future__ import annotations

import math

import blender_support as support
import bpy
import numpy as np

from bench.blend_scenes import diffuse_material, mesh_object, reset
from bench.cycles import bake_object
from radiosity_addon.blender.export import export_scene
from radiosity_addon.blender.lightmap_uv import add_lightmap_uvs
from radiosity_addon.blender.opacity import bake_opacity, lets_light_through
from radiosity_addon.blender.tags import CREATED_UV

CELLS = 6  # the card's checker: squares of alpha 0 and 1


def checker_image(size: int = 96):
    image = bpy.data.images.new("Leaf mask", size, size, alpha=True)
    i, j = np.meshgrid(np.arange(size), np.arange(size), indexing="ij")
    clear = ((i * CELLS) // size + (j * CELLS) // size) % 2 == 0
    pixels = np.ones((size, size, 4), dtype=np.float32)
    pixels[..., :3] = (0.2, 0.6, 0.1)
    pixels[..., 3] = np.where(clear, 0.0, 1.0)
    image.pixels.foreach_set(pixels.ravel())
    image.pack()
    return image


def cut_out_material(image):
    """A Principled BSDF whose Base Color and Alpha come from the image, as glTF imports leaves."""
    material = bpy.data.materials.new("Leaf")
    if material.node_tree is None:
        material.use_nodes = True
    nodes = material.node_tree.nodes
    principled = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    principled.inputs["Roughness"].default_value = 1.0
    principled.inputs["Specular IOR Level"].default_value = 0.0
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    material.node_tree.links.new(texture.outputs["Color"], principled.inputs["Base Color"])
    material.node_tree.links.new(texture.outputs["Alpha"], principled.inputs["Alpha"])
    return material


def card_scene():
    """A grey 4 x 4 m floor, a 1.5 x 1.5 m cut-out card 1 m above it, a sun at an angle and a blue
    sky (a canopy's set-up: the shade is the sky's light through the leaves and around them)."""
    support.ensure_addon()
    reset(world_colour=(0.3, 0.4, 0.6))
    grey = diffuse_material("grey", (0.6, 0.6, 0.6))
    floor = mesh_object("Floor", [(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], [(0, 1, 2, 3)], [grey])
    card = mesh_object("Card", [(-0.75, -0.75, 1), (0.75, -0.75, 1), (0.75, 0.75, 1), (-0.75, 0.75, 1)],
                       [(0, 1, 2, 3)], [cut_out_material(checker_image())])
    uv = card.data.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", np.array([0, 0, 1, 0, 1, 1, 0, 1], dtype=np.float32))
    uv.active_render = True
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.radians(20), math.radians(-15), 0.0)
    bpy.context.scene.collection.objects.link(sun)
    floor.radiosity.lightmap_resolution = 128
    card.radiosity.lightmap_resolution = 32
    settings = bpy.context.scene.radiosity
    settings.content = "combined"
    bpy.context.view_layer.update()
    return floor, card


def test_a_cut_out_material_lets_light_through_and_its_opacity_is_the_images_alpha():
    _, card = card_scene()
    leaf, grey = bpy.data.materials["Leaf"], bpy.data.materials["grey"]
    assert lets_light_through(leaf) and not lets_light_through(grey) and not lets_light_through(None)
    before = len(bpy.data.materials), len(bpy.data.objects), len(bpy.data.images)
    alpha = bake_opacity([leaf])["Leaf"]
    assert (len(bpy.data.materials), len(bpy.data.objects), len(bpy.data.images)) == before  # nothing left
    assert alpha.shape == (96, 96)
    i, j = np.meshgrid(np.arange(96), np.arange(96), indexing="ij")
    expected = ((i * CELLS) // 96 + (j * CELLS) // 96) % 2 == 1
    assert np.mean((alpha >= 0.5) == expected) > 0.97  # Cycles' texels, filtered at the squares' edges
    inner = (i % 16 >= 2) & (i % 16 < 14) & (j % 16 >= 2) & (j % 16 < 14)
    assert np.all((alpha >= 0.5)[inner] == expected[inner])


def test_the_export_hands_the_core_each_faces_texture_and_uvs():
    floor, card = card_scene()
    add_lightmap_uvs(bpy.context, [floor, card], 0.1)
    exported = export_scene(bpy.context.evaluated_depsgraph_get(), [floor, card], [])
    opacity = exported.scene.opacity
    assert opacity is not None and len(opacity.images) == 1
    on_card = exported.scene.object_index == exported.scene.object_names.index("Card")
    assert np.all(opacity.index[on_card] == 0) and np.all(opacity.index[~on_card] == -1)
    corners, uv = exported.scene.corners[on_card][0], opacity.uv[on_card][0]
    np.testing.assert_allclose(uv, (corners[:, :2] + 0.75) / 1.5, atol=1e-6)  # the card's own UV map


def test_a_floor_under_a_cut_out_card_bakes_like_cycles():
    floor, card = card_scene()
    support.select_only([floor, card])
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    ours = support.image_rgba(bpy.data.images["Floor_lightmap"])
    for obj in (floor, card):
        obj.data[CREATED_UV] = False  # keep the Lightmap UV maps for Cycles
    assert bpy.ops.radiosity.remove_bake() == {"FINISHED"}
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.use_denoising = "CPU", 64, False
    cycles.max_bounces = cycles.diffuse_bounces = 16
    cycles.transparent_max_bounces = 16
    reference = bake_object(floor, ours.shape[1], ours.shape[0], 64)
    both = (ours[..., 3] > 0.5) & (reference[..., 3] > 0.5)
    light = ours[..., :3].mean(axis=2)
    traced = reference[..., :3].mean(axis=2)
    # the card's shadow: where Cycles' floor is darker than the open floor
    shadow = both & (traced < 0.8 * np.percentile(traced[both], 90))
    assert shadow.sum() > 0.05 * both.sum()
    # measured: 1.5 % and 6 % (Cycles at 256 samples: 1.3 %); the issue asks 5 % and 15 %
    assert abs(light[shadow].mean() / traced[shadow].mean() - 1) < 0.05
    rms = np.sqrt(np.mean((light - traced)[shadow] ** 2)) / np.sqrt(np.mean(traced[shadow] ** 2))
    assert rms < 0.15  # the dappled pattern texel by texel (Cycles' 64 samples add their noise)
