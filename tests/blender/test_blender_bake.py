"""The add-on's bake through the bpy module: write-back, re-bake, restore, cancel and refusals."""

from __future__ import annotations

import time

import blender_support as support  # noqa: F401  (sets BLENDER_USER_RESOURCES before bpy loads)
import bpy
import numpy as np
import pytest

from radiosity_addon.blender.bake import bake_blocking, baked_materials
from radiosity_addon.blender.export import export_scene
from radiosity_addon.blender.lightmap_uv import add_lightmap_uvs
from radiosity_addon.blender.lights import render_lamps
from radiosity_addon.blender.material_bake import bake_material_maps, is_uniform
from radiosity_addon.core import SolveCancelled


def bake():
    """The operator as a script calls it (EXEC_DEFAULT: blocks until done)."""
    return bpy.ops.radiosity.bake()


def mesh_objects():
    return [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]


def test_cornell_bake_writes_an_image_uv_map_and_wiring_per_object():
    support.open_blend(support.CORNELL)
    baked = list(bpy.context.selected_objects)
    assert len(baked) == 8
    assert bake() == {"FINISHED"}
    for obj in baked:
        image = bpy.data.images.get(f"{obj.name}_lightmap")
        assert image is not None, obj.name
        assert image.is_float and image.packed_file is not None
        rgba = support.image_rgba(image)
        covered = rgba[..., 3] > 0
        assert covered.mean() > 0.2, f"{obj.name}: lightmap mostly empty"
        assert np.all(np.isfinite(rgba)) and rgba[..., :3][covered].max() > 0, obj.name
        assert "Lightmap" in obj.data.uv_layers
        for slot in obj.material_slots:
            wiring = support.lightmap_wiring(slot.material)
            assert wiring == {"image": image.name, "interpolation": "Linear", "uv_map": "Lightmap"}, obj.name
    # the light is the brightest thing, the red wall is red, the green wall green
    mean = {obj.name: support.image_rgba(bpy.data.images[f"{obj.name}_lightmap"])[..., :3].reshape(-1, 3)
            [support.image_rgba(bpy.data.images[f"{obj.name}_lightmap"])[..., 3].ravel() > 0].mean(axis=0)
            for obj in baked}
    assert mean["light"].max() > 5 * max(m.max() for name, m in mean.items() if name != "light")
    assert mean["left_wall"][0] > 2 * mean["left_wall"][1]
    assert mean["right_wall"][1] > 2 * mean["right_wall"][0]
    # the panel's record of what the scene analysis let this bake simulate
    last = bpy.context.scene.radiosity.last_bake
    assert last.startswith("3 channel(s) · occlusion · interreflection · 1 emitter(s)"), last


def test_two_bakes_leave_one_image_per_object_and_no_extra_materials():
    support.open_blend(support.CORNELL)
    assert bake() == {"FINISHED"}
    first = support.blend_state()
    # a re-bake reads the materials through their own shading, not through the bake they show
    floor = bpy.data.objects["floor"]
    outputs = [(n.name, n.is_active_output) for n in floor.active_material.node_tree.nodes
               if n.bl_idname == "ShaderNodeOutputMaterial"]
    maps = bake_material_maps(bpy.context, [floor], {"floor": (8, 8)})["floor"]
    np.testing.assert_allclose(maps.albedo.mean(axis=(0, 1)), [0.725, 0.71, 0.68], atol=2e-3)
    assert maps.emission.max() == 0
    assert [(n.name, n.is_active_output) for n in floor.active_material.node_tree.nodes
            if n.bl_idname == "ShaderNodeOutputMaterial"] == outputs
    assert bake() == {"FINISHED"}
    second = support.blend_state()
    assert second["images"] == first["images"] == sorted(f"{o.name}_lightmap" for o in mesh_objects())
    assert sorted(second["materials"]) == sorted(first["materials"])
    assert second == first


def test_uniform_materials_are_probed_once_and_only_varying_ones_get_maps():
    context = support.open_blend(support.CORNELL)
    baked = list(context.selected_objects)
    add_lightmap_uvs(context, baked, context.scene.radiosity.uv_margin)  # as the bake does first
    floor, tall = bpy.data.objects["floor"], bpy.data.objects["tall_block"]
    assert all(is_uniform(slot.material) for obj in baked for slot in obj.material_slots) and is_uniform(None)
    # Cycles' own albedo of the floor, baked into a map the way a textured object's is
    floor_albedo = bake_material_maps(context, [floor], {"floor": (8, 8)})["floor"].albedo.mean(axis=(0, 1))
    # the tall block's material becomes a checker (a linked Base Color): it needs a map
    checker_material = tall.material_slots[0].material.copy()
    tall.material_slots[0].link, tall.material_slots[0].material = "OBJECT", checker_material
    tree = checker_material.node_tree
    principled = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    checker = tree.nodes.new("ShaderNodeTexChecker")
    tree.links.new(checker.outputs["Color"], principled.inputs["Base Color"])
    assert not is_uniform(checker_material)
    mix = bpy.data.materials.new("mix of two diffuse shaders")
    if mix.node_tree is None:  # Blender 4.x makes the node tree on request
        mix.use_nodes = True
    nodes = mix.node_tree.nodes
    output = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    shader = nodes.new("ShaderNodeMixShader")
    for socket in (1, 2):
        mix.node_tree.links.new(nodes.new("ShaderNodeBsdfDiffuse").outputs[0], shader.inputs[socket])
    mix.node_tree.links.new(shader.outputs[0], output.inputs["Surface"])
    assert is_uniform(mix)
    mix.node_tree.links.new(nodes.new("ShaderNodeFresnel").outputs[0], shader.inputs["Fac"])
    assert not is_uniform(mix)

    options = context.scene.radiosity.bake_options(baked)
    exported = export_scene(context.evaluated_depsgraph_get(), baked, lamps=render_lamps(context.view_layer),
                            world=context.scene.world)
    before = support.blend_state()
    scene, _ = baked_materials(context, exported, baked, options)
    assert support.blend_state() == before  # probes, their scene and images are gone again
    assert list(scene.material_maps) == ["tall_block"]
    faces = scene.object_index == scene.object_names.index("floor")
    np.testing.assert_allclose(scene.reflectance[faces], np.broadcast_to(floor_albedo, (faces.sum(), 3)), atol=1e-3)
    light = scene.object_index == scene.object_names.index("light")
    assert np.all(scene.emission[light] > 1) and np.all(scene.emission[~light] == 0)


@pytest.mark.parametrize("sample", [support.CORNELL, support.ROOM], ids=["cornell", "room"])
def test_restore_brings_back_the_original_node_trees(sample):
    support.open_blend(sample)
    before = support.blend_state()
    assert bake() == {"FINISHED"}
    assert support.blend_state() != before
    assert bpy.ops.radiosity.remove_bake() == {"FINISHED"}
    assert support.blend_state() == before


def test_room_with_ngon_triangles_modifier_and_materials_bakes():
    support.open_blend(support.ROOM)
    assert bake() == {"FINISHED"}
    for obj in mesh_objects():
        image = bpy.data.images[f"{obj.name}_lightmap"]
        rgba = support.image_rgba(image)
        assert rgba[..., 3].any() and rgba[..., :3].max() > 0, obj.name
    # two materials on the room mesh, each showing the room's lightmap
    room = bpy.data.objects["Room"]
    assert len(room.material_slots) == 2
    for slot in room.material_slots:
        assert support.lightmap_wiring(slot.material)["image"] == "Room_lightmap"


def test_cancel_leaves_the_file_unchanged():
    context = support.open_blend(support.CORNELL)
    before = support.blend_state()
    with pytest.raises(SolveCancelled):
        bake_blocking(context, context.scene.radiosity.bake_options(context.selected_objects), should_cancel=lambda: True)
    assert support.blend_state() == before


def refused(message_part: str):
    before = support.blend_state()
    with pytest.raises(RuntimeError) as error:
        bake()
    text = str(error.value).strip()
    assert len(text.splitlines()) == 1 and "Traceback" not in text, text
    assert message_part in text, text
    assert support.blend_state() == before


def test_no_selection_is_refused_unchanged():
    support.open_blend(support.CORNELL)
    support.select_only([])
    refused("select the mesh objects")


def test_non_mesh_selection_is_refused_unchanged():
    support.open_blend(support.CORNELL)
    support.select_only([bpy.context.scene.camera])
    refused("no mesh among the selected objects")


def test_scene_without_emitter_is_refused_unchanged():
    support.open_blend(support.CORNELL)
    light = bpy.data.objects["light"]
    bpy.data.objects.remove(light)
    support.select_only(mesh_objects())
    refused("nothing emits light")


def test_mesh_without_faces_is_refused_unchanged():
    support.open_blend(support.CORNELL)
    mesh = bpy.data.meshes.new("loose")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0)], [(0, 1)], [])
    loose = bpy.data.objects.new("loose", mesh)
    bpy.context.scene.collection.objects.link(loose)
    support.select_only(mesh_objects())
    refused("has no faces")


def test_nan_vertices_are_refused_unchanged():
    support.open_blend(support.CORNELL)
    floor = bpy.data.objects["floor"]
    floor.data.vertices[0].co = (float("nan"), 0.0, 0.0)
    refused("NaN")


def test_failure_after_the_solve_leaves_the_file_unchanged(monkeypatch):
    """An error in the solver process (here: its lightmap stage) rolls back the UV maps made for the bake."""
    support.inject_into_solver(monkeypatch, """
import radiosity_addon.solver_process.child as child
from radiosity_addon.core import SolveError
def broken(*args, **kwargs):
    raise SolveError("simulated lightmap failure")
child.lightmap_images = broken
""")
    support.open_blend(support.CORNELL)
    refused("simulated lightmap failure")


def test_a_crash_of_the_solver_process_is_one_line_and_leaves_the_file_unchanged(monkeypatch):
    """What a segfault in the OpenGL driver does: the process dies after its first progress report."""
    support.inject_into_solver(monkeypatch, """
import os, signal
import radiosity_addon.core as core
def crashing_solve(scene, settings, progress=None, **kwargs):
    progress(0.1, "shot 1", {})
    os.kill(os.getpid(), signal.SIGSEGV)
core.solve = crashing_solve
""")
    support.open_blend(support.CORNELL)
    refused("the solver process crashed (SIGSEGV)")


def test_a_hung_solver_process_is_killed_with_one_line_and_the_file_unchanged(monkeypatch):
    """A driver call that never returns holds Python's lock, so even the heartbeat stops."""
    from radiosity_addon.blender import worker

    monkeypatch.setattr(worker, "SILENCE_LIMIT", 3.0)
    support.inject_into_solver(monkeypatch, """
import ctypes
import radiosity_addon.core as core
def hanging_solve(*args, **kwargs):
    ctypes.PyDLL(None).sleep(600)  # a C call that keeps the global interpreter lock
core.solve = hanging_solve
""")
    support.open_blend(support.CORNELL)
    started = time.monotonic()
    refused("the solver stopped responding")
    assert time.monotonic() - started < 30


def test_exr_output_is_written_next_to_the_saved_file(tmp_path):
    support.open_blend(support.CORNELL)
    bpy.context.scene.radiosity.output = "EXR"
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "copy.blend"))
    assert bake() == {"FINISHED"}
    assert sorted(p.name for p in tmp_path.glob("*.exr")) == sorted(f"{o.name}_lightmap.exr" for o in mesh_objects())
    image = bpy.data.images["floor_lightmap"]
    assert image.filepath == "//floor_lightmap.exr" and image.packed_file is None


def test_exr_output_of_an_unsaved_file_is_refused_unchanged():
    support.ensure_addon()
    bpy.ops.wm.read_homefile(use_empty=True)
    mesh = bpy.data.meshes.new("quad")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [], [(0, 1, 2, 3)])
    quad = bpy.data.objects.new("quad", mesh)
    bpy.context.scene.collection.objects.link(quad)
    support.select_only([quad])
    bpy.context.scene.radiosity.output = "EXR"
    refused("save the .blend first")


def test_missing_opengl_is_one_line_and_leaves_the_file_unchanged(monkeypatch):
    support.inject_into_solver(monkeypatch, """
import radiosity_addon.core.gpu.resources as resources
from radiosity_addon.core import GLUnavailable
def no_gl():
    raise GLUnavailable("cannot create an OpenGL 4.3 context (simulated)")
resources.create_context = no_gl
""")
    support.open_blend(support.CORNELL)
    refused("OpenGL 4.3")


def test_a_shared_material_in_two_slots_gets_one_copy_and_restores():
    support.open_blend(support.CORNELL)
    floor = bpy.data.objects["floor"]
    white = floor.material_slots[0].material
    floor.data.materials.append(white)  # a second slot showing the same shared material
    floor.data.polygons[0].material_index = 1
    support.select_only([floor])  # the walls keep showing White: the floor needs a copy
    before = support.blend_state()
    assert bake() == {"FINISHED"}
    shown = {slot.material.name for slot in floor.material_slots}
    assert len(shown) == 1 and shown != {white.name}
    assert support.lightmap_wiring(floor.material_slots[1].material)["image"] == "floor_lightmap"
    assert support.lightmap_wiring(white) is None
    assert bpy.ops.radiosity.remove_bake() == {"FINISHED"}
    assert support.blend_state() == before
