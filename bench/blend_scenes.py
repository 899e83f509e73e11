"""Building Blender scenes from Python (the `bpy` module or Blender): the sample files
(tools/make_sample_blends.py), the Blender tests' scenes and the benchmark's share these.

Dev-only, like the rest of the benchmark: it is not in the extension.
"""

from __future__ import annotations

import math

import bpy

from .shapes import box  # noqa: F401  (the sample files' scripts import it from here)


def register_addon() -> None:
    """The add-on's settings are saved with the files, so its properties must exist."""
    if not hasattr(bpy.types.Scene, "radiosity"):
        from radiosity_addon.blender import register

        register()


def reset(world_colour=None) -> None:
    """An empty session with the add-on registered and a black world, or a uniform sky of
    `world_colour` (RGB radiance)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register_addon()
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 backups in the repository
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 512
    colour = tuple(world_colour) if world_colour is not None else (0.0, 0.0, 0.0)
    world = bpy.data.worlds.new("Sky" if world_colour is not None else "Dark")
    world.color = colour
    # a new world's node tree shines a 0.05 grey: the radiosity bake has no sky, so neither may Cycles
    for node in (world.node_tree.nodes if world.node_tree else ()):
        if node.bl_idname == "ShaderNodeBackground":
            node.inputs["Color"].default_value = (*colour, 1.0)
            node.inputs["Strength"].default_value = 1.0 if world_colour is not None else 0.0
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
    return camera


def looking_at(location, target) -> tuple:
    """The rotation (Euler XYZ, degrees) of a camera or lamp at `location` pointing its −Z at `target`."""
    from mathutils import Vector

    direction = Vector(target) - Vector(location)
    return tuple(math.degrees(a) for a in direction.to_track_quat("-Z", "Y").to_euler())


def add_lamp(name: str, kind: str, location, rotation_degrees, colour=(1.0, 1.0, 1.0), **settings):
    """A lamp object; `settings` are the light data's own (energy, size, size_y, shape, angle...)."""
    light = bpy.data.lights.new(name, kind)
    light.color = colour
    for key, value in settings.items():
        setattr(light, key, value)
    lamp = bpy.data.objects.new(name, light)
    lamp.location = location
    lamp.rotation_euler = [math.radians(a) for a in rotation_degrees]
    bpy.context.scene.collection.objects.link(lamp)
    return lamp


def lightmap_pack(objects, uv_name: str = "Lightmap", margin: float = 0.1) -> None:
    """Give each object's mesh a `uv_name` UV map made by Lightmap Pack, as a user would (one
    operator call, each mesh packed into its own 0–1 square; `margin` as the add-on's default)."""
    import contextlib
    import io

    owners = list({obj.data.name: obj for obj in objects}.values())  # the operator packs meshes
    for obj in owners:
        layer = obj.data.uv_layers.get(uv_name) or obj.data.uv_layers.new(name=uv_name, do_init=False)
        obj.data.uv_layers.active = layer
    with contextlib.redirect_stdout(io.StringIO()), \
            bpy.context.temp_override(selected_objects=owners, active_object=owners[0], object=owners[0]):
        bpy.ops.uv.lightmap_pack(PREF_CONTEXT="ALL_FACES", PREF_PACK_IN_ONE=False, PREF_NEW_UVLAYER=False,
                                 PREF_MARGIN_DIV=margin)


def evaluated_triangles(objects) -> dict[str, int]:
    """Triangles per mesh object as rendered: modifiers applied, n-gons triangulated."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    counts = {}
    for obj in objects:
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            mesh.calc_loop_triangles()
            counts[obj.name] = len(mesh.loop_triangles)
        finally:
            evaluated.to_mesh_clear()
    return counts


def save_blend(path) -> None:
    from pathlib import Path

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(path.resolve()), compress=True)


def select_meshes() -> None:
    meshes = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    for obj in meshes:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
