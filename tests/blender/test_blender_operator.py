"""The operator's settings: per-object resolution, selection vs occluders, material read-out and its
warnings, the panel. (The modal path is in test_blender_ui_bake.py.)"""

from __future__ import annotations

from types import SimpleNamespace

import blender_support as support
import bpy
import numpy as np
import pytest

from radiosity_addon.blender.bake import prepare
from radiosity_addon.blender.materials import MaterialReader


def test_object_resolution_override_sets_the_lightmap_size():
    support.open_blend(support.CORNELL)
    bpy.data.objects["floor"].radiosity.lightmap_resolution = 48
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    assert tuple(bpy.data.images["floor_lightmap"].size) == (48, 48)
    assert tuple(bpy.data.images["ceiling_lightmap"].size) != (48, 48)


def test_only_selected_objects_get_lightmaps_and_unselected_ones_still_light_them():
    support.open_blend(support.CORNELL)
    floor = bpy.data.objects["floor"]
    support.select_only([floor])
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    assert sorted(i.name for i in bpy.data.images) == ["floor_lightmap"]
    assert "Lightmap" not in bpy.data.objects["ceiling"].data.uv_layers
    rgba = support.image_rgba(bpy.data.images["floor_lightmap"])
    assert rgba[..., :3][rgba[..., 3] > 0].max() > 0  # lit by the unselected light
    # the floor's material is shared with unbaked walls: the floor shows a copy, the walls the original
    floor_material = floor.material_slots[0].material
    ceiling_material = bpy.data.objects["ceiling"].material_slots[0].material
    assert floor_material is not ceiling_material
    assert support.lightmap_wiring(floor_material)["image"] == "floor_lightmap"
    assert support.lightmap_wiring(ceiling_material) is None

    support.open_blend(support.CORNELL)
    bpy.context.scene.radiosity.include_unselected = False
    support.select_only([bpy.data.objects["floor"]])
    before = support.blend_state()
    with pytest.raises(RuntimeError, match="nothing emits light"):
        bpy.ops.radiosity.bake()
    assert support.blend_state() == before


def new_material(name, shader="ShaderNodeBsdfPrincipled"):
    material = bpy.data.materials.new(name)
    tree = material.node_tree
    output = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    if shader != "ShaderNodeBsdfPrincipled":
        node = tree.nodes.new(shader)
        tree.links.new(node.outputs[0], output.inputs["Surface"])
    return material, tree


def test_materials_become_reflectance_and_emission_with_warnings_for_what_cannot_bake():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    reader = MaterialReader()

    plain, tree = new_material("plain")
    principled = tree.nodes["Principled BSDF"]
    principled.inputs["Base Color"].default_value = (0.2, 0.4, 0.6, 1)
    principled.inputs["Emission Color"].default_value = (1.0, 0.5, 0.25, 1)
    principled.inputs["Emission Strength"].default_value = 4.0
    reflectance, emission = reader.colours(plain)
    # a Principled BSDF's diffuse part: specular level 0.5 keeps 1 - 0.075 x 0.5 of the base (Cycles: 0.963)
    assert np.allclose(reflectance, np.array([0.2, 0.4, 0.6]) * 0.9625) and np.allclose(emission, [4.0, 2.0, 1.0])
    assert reader.warnings == []

    textured, tree = new_material("textured")
    image = bpy.data.images.new("checker", 4, 4, float_buffer=True)
    image.pixels.foreach_set(np.tile([0.1, 0.3, 0.5, 1.0], 16).astype(np.float32))
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    tree.links.new(texture.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])
    reflectance, _ = reader.colours(textured)
    assert np.allclose(reflectance, np.array([0.1, 0.3, 0.5]) * 0.9625, atol=1e-6)
    assert any("textured" in w and "average colour" in w for w in reader.warnings)

    glossy, _ = new_material("glossy", "ShaderNodeBsdfGlossy")
    reflectance, emission = reader.colours(glossy)
    assert np.allclose(reflectance, 0.77) and not emission.any()  # the default surface's diffuse albedo
    assert any("glossy" in w and "not diffuse" in w for w in reader.warnings)

    white, tree = new_material("white")
    tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (1, 1, 1, 1)
    tree.nodes["Principled BSDF"].inputs["Specular IOR Level"].default_value = 0.0  # all of it diffuse
    reflectance, _ = reader.colours(white)
    assert reflectance.max() < 1
    assert any("white" in w and "capped" in w for w in reader.warnings)


class RecordingLayout:
    """Stands in for bpy's UILayout: records what the panel draws and checks each property exists."""

    def __init__(self, log):
        self.log = log
        self.use_property_split = self.use_property_decorate = self.enabled = False
        self.scale_y = 1.0

    def _child(self, *args, **kwargs):
        return RecordingLayout(self.log)

    row = column = box = split = _child

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, f"no property {name!r} on {data}"
        self.log.append(("prop", name))

    def operator(self, idname, **kwargs):
        category, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, category), name), idname
        self.log.append(("operator", idname))

    def label(self, **kwargs):
        self.log.append(("label", kwargs.get("text")))

    def progress(self, **kwargs):
        self.log.append(("progress", kwargs.get("factor")))

    def separator(self, **kwargs):
        pass


@pytest.mark.parametrize("method", ["progressive", "hemicube"])
def test_panel_draws_the_settings_of_the_chosen_method_and_the_bake_button(method):
    from radiosity_addon.blender.panel import RENDER_PT_radiosity_bake

    support.open_blend(support.CORNELL, method=method)
    bpy.context.view_layer.objects.active = bpy.data.objects["floor"]
    log = []
    panel = SimpleNamespace(layout=RecordingLayout(log))
    RENDER_PT_radiosity_bake.draw(panel, bpy.context)
    drawn = [name for kind, name in log if kind == "prop"]
    assert ("operator", "radiosity.bake") in log and ("operator", "radiosity.remove_bake") in log
    assert "lightmap_resolution" in drawn and "texel_density" in drawn and "output" in drawn
    assert ("elements" in drawn) == (method == "progressive")
    assert ("solver" in drawn) == (method == "hemicube")


def test_patch_size_splits_big_faces_and_keeps_small_ones_whole():
    """The exporter gives the faces as they are; the core's Patch Size mode splits them."""
    from radiosity_addon.blender.export import export_scene
    from radiosity_addon.blender.lightmap_uv import add_lightmap_uvs
    from radiosity_addon.core import subdivide

    context = support.open_blend(support.ROOM)
    objects = [obj for obj in context.scene.objects if obj.type == "MESH"]
    add_lightmap_uvs(bpy.context, objects, 0.1)
    scene = export_scene(context.evaluated_depsgraph_get(), objects, []).scene
    patches = subdivide(scene, None, 0.5)

    def uv_area(uv):
        x, y = uv[..., 0], uv[..., 1]
        return 0.5 * np.abs((x * np.roll(y, -1, axis=-1) - y * np.roll(x, -1, axis=-1)).sum(axis=-1))

    for name, surfaces in scene.object_surfaces.items():
        mine = np.isin(patches.surface, surfaces)
        assert np.isclose(patches.area[mine].sum(), scene.area[surfaces].sum(), rtol=1e-9), name
        assert np.isclose(uv_area(patches.uv[mine]).sum(), uv_area(scene.uv[surfaces]).sum(), rtol=1e-6), name
        edges = np.linalg.norm(np.roll(patches.corners[mine], -1, axis=1) - patches.corners[mine], axis=2)
        assert edges.max() <= 0.5 + 1e-9, name
    room = scene.object_surfaces["Room"]
    assert len(room) == 6 and np.isin(patches.surface, room).sum() == 2 * (8 * 6 + 8 * 5 + 6 * 5)  # 4 x 3 x 2.5 m
    edges = np.linalg.norm(np.roll(scene.corners, -1, axis=1) - scene.corners, axis=2).max(axis=1)
    small = np.flatnonzero(edges <= 0.5)
    assert len(small) and np.all(np.bincount(patches.surface, minlength=len(scene))[small] == 1)
    kept = np.flatnonzero(np.isin(patches.surface, small))
    assert np.allclose(patches.corners[kept], scene.corners[patches.surface[kept]])


def test_patch_size_mode_bakes_through_the_operator():
    support.open_blend(support.ROOM, method="hemicube")
    settings = bpy.context.scene.radiosity
    settings.patch_mode, settings.patch_size = "SIZE", 1.0
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    assert all(f"{obj.name}_lightmap" in bpy.data.images
               for obj in bpy.context.scene.objects if obj.type == "MESH")


def test_mirrored_objects_keep_their_fronts_and_visible_lamps_are_exported():
    from radiosity_addon.blender.export import export_scene

    context = support.open_blend(support.ROOM)
    light = bpy.data.objects["Ceiling Light"]  # a quad facing down
    mirrored = light.copy()
    mirrored.scale = (-1.0, 1.0, 1.0)
    context.scene.collection.objects.link(mirrored)
    context.view_layer.update()
    scene = export_scene(context.evaluated_depsgraph_get(), [], [light, mirrored]).scene
    normals = {s.object_name: s.normal for s in scene.surfaces}
    assert np.allclose(normals[light.name], [0, 0, -1]) and np.allclose(normals[mirrored.name], [0, 0, -1])

    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    context.scene.collection.objects.link(lamp)
    support.select_only([bpy.data.objects["Room"]])
    plan = prepare(context, context.scene.radiosity.bake_options(context.selected_objects))
    try:
        assert [light["name"] for light in plan.worker.scene.extras["lights"]] == ["Lamp"]
    finally:
        from radiosity_addon.blender.bake import rollback

        rollback(plan)


def test_baked_objects_get_no_warning_for_inputs_cycles_bakes_but_occluders_do():
    """textured sample: the floor's Base Color is an image. Baked, Cycles bakes its albedo per
    texel (nothing is guessed, nothing to warn of); as an occluder it is read as the image's
    average, and the export says so."""
    from radiosity_addon.blender.export import export_scene

    context = support.open_blend(support.SAMPLES / "textured.blend")
    floor = bpy.data.objects["Floor"]
    others = [obj for obj in context.view_layer.objects if obj.type == "MESH" and obj is not floor]
    baked = export_scene(context.evaluated_depsgraph_get(), [floor], []).warnings
    occluding = export_scene(context.evaluated_depsgraph_get(), others[:1], [floor]).warnings
    assert not [w for w in baked if "average colour" in w or "driven by" in w], baked
    assert any("average colour" in w for w in occluding), occluding
