"""Building Blender scenes from Python (the `bpy` module or Blender): the sample files
(tools/make_sample_blends.py), the Blender tests' scenes and the benchmark's share these.

Dev-only, like the rest of the benchmark: it is not in the extension.
"""

from __future__ import annotations

import math

import bpy


def register_addon() -> None:
    """The add-on's settings are saved with the files, so its properties must exist."""
    if not hasattr(bpy.types.Scene, "radiosity"):
        from ..blender import register

        register()


def reset() -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register_addon()
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 backups in the repository
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 512
    world = bpy.data.worlds.new("Dark")
    world.color = (0.0, 0.0, 0.0)
    # a new world's node tree shines a 0.05 grey: the radiosity bake has no sky, so neither may Cycles
    for node in (world.node_tree.nodes if world.node_tree else ()):
        if node.bl_idname == "ShaderNodeBackground":
            node.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
            node.inputs["Strength"].default_value = 0.0
    scene.world = world


def diffuse_material(name: str, colour, emission=(0.0, 0.0, 0.0)):
    """A Principled BSDF that is purely diffuse: the add-on's and Cycles' views agree."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:  # Blender 4.x; 5.x materials always have nodes
        material.use_nodes = True
    principled = material.node_tree.nodes["Principled BSDF"]
    principled.inputs["Base Color"].default_value = (*colour, 1.0)
    principled.inputs["Roughness"].default_value = 1.0
    principled.inputs["Specular IOR Level"].default_value = 0.0
    strength = max(emission)
    if strength > 0:
        principled.inputs["Emission Color"].default_value = (*[c / strength for c in emission], 1.0)
        principled.inputs["Emission Strength"].default_value = strength
    material.diffuse_color = (*colour, 1.0)
    return material


def mesh_object(name: str, vertices, faces, materials=(), face_materials=None):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in vertices], [], [tuple(f) for f in faces])
    for material in materials:
        mesh.materials.append(material)
    if face_materials is not None:
        mesh.polygons.foreach_set("material_index", face_materials)
    mesh.validate()
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_camera(location, rotation_degrees, angle_degrees):
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = location
    camera.rotation_euler = [math.radians(a) for a in rotation_degrees]
    camera.data.angle = math.radians(angle_degrees)
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera


def select_meshes() -> None:
    meshes = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    for obj in meshes:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]


def box(centre, size, inward=False):
    """Eight corners and six quads of an axis-aligned box; fronts face out (or in)."""
    cx, cy, cz = centre
    sx, sy, sz = (s / 2 for s in size)
    vertices = [(cx + dx * sx, cy + dy * sy, cz + dz * sz)
                for dz in (-1, 1) for dy in (-1, 1) for dx in (-1, 1)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    if inward:
        faces = [tuple(reversed(f)) for f in faces]
    return vertices, faces
