"""Write the sample .blend files into sample_blends/: cornell_box, room, and the issue-11 samples.

Run with the bpy module (`.venv/bin/python tools/make_sample_blends.py`) or with
Blender (`blender -b --factory-startup --python tools/make_sample_blends.py`): the files are in
the format of the Blender that made them, so each Blender can open the ones it made (a file saved
by Blender 5.x does not open in 4.x). `--output-dir DIR` (after `--` under Blender) writes them
elsewhere than sample_blends/.

cornell_box.blend: the bundled Cornell box (radiosity_addon/core/scene/scenes/cornell-box.json),
turned from its y-up data to Blender's z-up, one object per named part, Principled
materials with the scene's reflectance and emission (roughness 1, no specular, so a
Cycles bake of the same file sees the same diffuse scene).

room.blend: what a Blender user would make: a room with two materials on one mesh, a
table with a Bevel modifier, a hexagonal pyramid (triangles and an n-gon base), an
emissive ceiling panel, a camera. Neither file has 'Lightmap' UV maps: the add-on makes them.

The files below exercise what Blender renders and a radiosity bake must follow (issue 11). Each
is small (a few hundred faces at most, metres), its materials purely diffuse where Cycles allows
(Principled: roughness 1, no specular), and each mesh that gets a lightmap has a 'Lightmap' UV
map made here by Lightmap Pack, so the add-on and Cycles' reference bake the very same file:

- emissive_ceiling.blend: a closed room whose only light is an emissive plane 4 mm under the
  ceiling (a Principled emission: two-sided, as Blender's emission is), a closed crate on the floor;
- thin_walls.blend: a single-plane partition (no thickness) with a warm point lamp on one side and
  a cool one on the other, and a single-plane shelf board;
- textured.blend: a floor with a checker Image Texture (made here with numpy, packed), a back wall
  with a procedural Checker Texture, and a red striped rug (a packed image) on the floor next to
  the plain right wall, under an area lamp;
- node_materials.blend: a Diffuse BSDF, an Emission shader (the panel that lights the room), a Mix
  Shader of Diffuse and Emission, an Add Shader, and a cube with no material (Blender's default);
- instances.blend: a chair made once in a collection that is not in the scene, placed by a
  collection instance under a point lamp, and a linked duplicate of the chair's mesh.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.blend_scenes import (add_camera, add_lamp, box, diffuse_material,  # noqa: E402
                                                lightmap_pack, looking_at, mesh_object, reset, select_meshes)
from bench.shapes import box_between, merge  # noqa: E402

CORNELL_JSON = ROOT / "radiosity_addon/core/scene/scenes/cornell-box.json"
OUT_DIR = ROOT / "sample_blends"


def save(name: str) -> Path:
    OUT_DIR.mkdir(exist_ok=True)
    path = OUT_DIR / name
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    print(f"wrote {path} ({path.stat().st_size // 1024} KiB)")
    return path


def y_up_to_z_up(point):
    x, y, z = point
    return (x, -z, y)  # +90 degrees about X: keeps the winding (fronts stay fronts)


def make_cornell_box() -> Path:
    reset()
    data = json.loads(CORNELL_JSON.read_text())
    surfaces = data["surfaces"]
    materials = {}
    parts: dict[str, list] = {}
    for surface in surfaces:
        key = (tuple(surface["reflectance"]), tuple(surface["emission"]))
        if key not in materials:
            name = {"light": "Light", "left_wall": "Red", "right_wall": "Green"}.get(surface["object"], "White")
            materials[key] = diffuse_material(name, surface["reflectance"], surface["emission"])
        parts.setdefault(surface["object"], []).append((surface, materials[key]))
    for object_name, entries in parts.items():
        vertices, faces, object_materials, face_materials = [], [], [], []
        for surface, material in entries:
            if material not in object_materials:
                object_materials.append(material)
            faces.append(list(range(len(vertices), len(vertices) + len(surface["vertices"]))))
            vertices.extend(y_up_to_z_up(v) for v in surface["vertices"])
            face_materials.append(object_materials.index(material))
        mesh_object(object_name, vertices, faces, object_materials, face_materials)
    # the Cornell camera: 0.8 m in front of the open side, looking in (+z of the data = -y in Blender)
    camera = data.get("camera", {"eye": [0.278, 0.273, -0.8], "forward": [0, 0, 1], "fov_y_degrees": 39.3076})
    assert camera["forward"] == [0, 0, 1], "the sample's camera rotation assumes the data looks along +z"
    add_camera(y_up_to_z_up(camera["eye"]), (90.0, 0.0, 180.0), camera["fov_y_degrees"])
    # the box is 0.55 m wide: patches of 0.1 m rather than the default 0.5 m
    bpy.context.scene.radiosity.patch_size = 0.1
    select_meshes()
    return save("cornell_box.blend")


def make_room() -> Path:
    reset()
    walls = diffuse_material("Plaster", (0.75, 0.74, 0.70))
    floor = diffuse_material("Oak Floor", (0.45, 0.30, 0.18))
    table_top = diffuse_material("Blue Paint", (0.15, 0.25, 0.60))
    stone = diffuse_material("Stone", (0.55, 0.55, 0.52))
    lamp = diffuse_material("Ceiling Panel", (0.8, 0.8, 0.8), emission=(6.0, 5.6, 4.8))

    vertices, faces = box((0.0, 0.0, 1.25), (4.0, 3.0, 2.5), inward=True)
    # face 0 is the floor (z = 0): its own material
    mesh_object("Room", vertices, faces, [walls, floor], [1, 0, 0, 0, 0, 0])

    vertices, faces = box((0.0, 0.0, 0.0), (1.2, 0.8, 0.6))
    table = mesh_object("Table", vertices, faces, [table_top])
    table.location = (0.6, 0.2, 0.3)
    table.rotation_euler = (0.0, 0.0, math.radians(20.0))
    bevel = table.modifiers.new("Bevel", "BEVEL")
    bevel.width = 0.04
    bevel.segments = 1

    sides = 6
    ring = [(0.35 * math.cos(2 * math.pi * k / sides), 0.35 * math.sin(2 * math.pi * k / sides), 0.0)
            for k in range(sides)]
    apex = (0.0, 0.0, 0.7)
    faces = [tuple(reversed(range(sides)))] + [(k, (k + 1) % sides, sides) for k in range(sides)]
    pyramid = mesh_object("Pyramid", ring + [apex], faces, [stone])
    pyramid.location = (-0.5, 0.9, 0.0)

    panel = [(-0.5, -0.3, 0.0), (-0.5, 0.3, 0.0), (0.5, 0.3, 0.0), (0.5, -0.3, 0.0)]  # faces down
    light = mesh_object("Ceiling Light", panel, [(0, 1, 2, 3)], [lamp])
    light.location = (0.0, 0.0, 2.49)

    add_camera((-1.8, -1.3, 1.6), (72.0, 0.0, -55.0), 80.0)
    select_meshes()
    return save("room.blend")


# ---------------------------------------------------------------- the issue-11 samples

def new_material(name: str):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:  # Blender 4.x; 5.x materials always have nodes
        material.use_nodes = True
    return material


def shader_material(name: str, kind: str, colour=(0.8, 0.8, 0.8), emission=(0.0, 0.0, 0.0), strength=0.0,
                    factor=0.5):
    """A node material a user would make: "diffuse" (Diffuse BSDF), "emission" (Emission shader),
    "mix" (Mix Shader: (1 - factor) Diffuse + factor Emission) or "add" (Add Shader: Diffuse + Emission)."""
    material = new_material(name)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    for node in list(nodes):
        if node.bl_idname != "ShaderNodeOutputMaterial":
            nodes.remove(node)
    output = nodes["Material Output"]
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*colour, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0  # Lambert, not Oren-Nayar
    glow = nodes.new("ShaderNodeEmission")
    glow.inputs["Color"].default_value = (*emission, 1.0)
    glow.inputs["Strength"].default_value = strength
    if kind == "diffuse":
        nodes.remove(glow)
        links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    elif kind == "emission":
        nodes.remove(diffuse)
        links.new(glow.outputs["Emission"], output.inputs["Surface"])
    else:
        combine = nodes.new("ShaderNodeMixShader" if kind == "mix" else "ShaderNodeAddShader")
        if kind == "mix":
            combine.inputs["Fac"].default_value = factor
        first, second = (1, 2) if kind == "mix" else (0, 1)
        links.new(diffuse.outputs["BSDF"], combine.inputs[first])
        links.new(glow.outputs["Emission"], combine.inputs[second])
        links.new(combine.outputs["Shader"], output.inputs["Surface"])
    material.diffuse_color = (*colour, 1.0)
    return material


def packed_image(name: str, srgb: np.ndarray):
    """A byte image of the (H, W, 3) sRGB-encoded values `srgb` (row 0 at the bottom), packed into
    the file as PNG: Cycles decodes it from sRGB as it does any colour image."""
    height, width = srgb.shape[:2]
    image = bpy.data.images.new(name, width, height, alpha=False)
    rgba = np.concatenate([srgb, np.ones((height, width, 1))], axis=-1).astype(np.float32)
    image.pixels.foreach_set(rgba.ravel())
    image.pack()
    return image


def checker_pixels(checks: int, size: int, light, dark) -> np.ndarray:
    cells = (np.arange(size) * checks // size)
    odd = (cells[:, None] + cells[None, :]) % 2 == 1
    return np.where(odd[..., None], np.asarray(dark, dtype=float), np.asarray(light, dtype=float))


def stripe_pixels(stripes: int, size: int, light, dark) -> np.ndarray:
    band = (np.arange(size) * stripes // size) % 2 == 1
    row = np.where(band[:, None], np.asarray(dark, dtype=float), np.asarray(light, dtype=float))
    return np.broadcast_to(row[None], (size, size, 3)).copy()


def textured_material(name: str, image=None, procedural=None):
    """A purely diffuse Principled BSDF whose Base Color is an Image Texture on the 'UVMap' UV map,
    or a procedural Checker Texture (`procedural` = (colour1, colour2, scale), Generated coordinates)."""
    material = diffuse_material(name, (0.8, 0.8, 0.8))
    nodes, links = material.node_tree.nodes, material.node_tree.links
    principled = nodes["Principled BSDF"]
    if image is not None:
        texture = nodes.new("ShaderNodeTexImage")
        texture.image = image
        coordinates = nodes.new("ShaderNodeUVMap")
        coordinates.uv_map = "UVMap"
        links.new(coordinates.outputs["UV"], texture.inputs["Vector"])
    else:
        first, second, scale = procedural
        texture = nodes.new("ShaderNodeTexChecker")
        texture.inputs["Color1"].default_value = (*first, 1.0)
        texture.inputs["Color2"].default_value = (*second, 1.0)
        texture.inputs["Scale"].default_value = scale
    links.new(texture.outputs["Color"], principled.inputs["Base Color"])
    return material


def planar_uv(obj, axes=(0, 1), name: str = "UVMap") -> None:
    """A texture UV map spanning the object's bounds along two local axes (0-1 over each)."""
    mesh = obj.data
    layer = mesh.uv_layers.get(name) or mesh.uv_layers.new(name=name)
    positions = np.array([v.co[:] for v in mesh.vertices])
    low, high = positions.min(axis=0), positions.max(axis=0)
    span = np.where(high - low > 0, high - low, 1.0)
    for loop in mesh.loops:
        point = (positions[loop.vertex_index] - low) / span
        layer.data[loop.index].uv = (point[axes[0]], point[axes[1]])


def inward_room(name: str, size, materials, face_materials=None):
    """A closed room (an inward-facing box) standing on z = 0, centred on x = y = 0. Face order:
    floor, ceiling, -y, +y, -x, +x walls."""
    vertices, faces = box((0.0, 0.0, size[2] / 2), size, inward=True)
    return mesh_object(name, vertices, faces, materials, face_materials)


def quad(name: str, corners, material):
    """One face; corners counter-clockwise seen from its front."""
    return mesh_object(name, corners, [(0, 1, 2, 3)], [material])


def finish_sample(file_name: str, camera_at, look_at, lens_degrees: float = 70.0) -> Path:
    add_camera(camera_at, looking_at(camera_at, look_at), lens_degrees)
    meshes = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    lightmap_pack(meshes)
    for obj in meshes:  # texture UVs (when any) stay the active map; 'Lightmap' is only for the bake
        obj.data.uv_layers.active_index = 0
    select_meshes()
    return save(file_name)


def make_emissive_ceiling() -> Path:
    reset()
    white = diffuse_material("White Plaster", (0.7, 0.7, 0.7))
    red = diffuse_material("Red Paint", (0.6, 0.12, 0.1))
    green = diffuse_material("Green Paint", (0.12, 0.45, 0.15))
    inward_room("Room", (2.4, 2.4, 2.4), [white, red, green], [0, 0, 0, 0, 1, 2])
    vertices, faces = box((0.5, 0.3, 0.3), (0.6, 0.6, 0.6))
    crate = mesh_object("Crate", vertices, faces, [diffuse_material("Crate Grey", (0.5, 0.5, 0.45))])
    crate.rotation_euler = (0.0, 0.0, math.radians(25.0))
    lamp = diffuse_material("Light Panel", (0.8, 0.8, 0.8), emission=(12.0, 11.0, 9.0))
    half = 0.3  # faces down, 4 mm under the 2.4 m ceiling
    quad("Ceiling Light", [(-half, -half, 0), (-half, half, 0), (half, half, 0), (half, -half, 0)], lamp).location = \
        (0.0, 0.0, 2.4 - 0.004)
    return finish_sample("emissive_ceiling.blend", (0.0, -1.15, 1.3), (0.0, 0.5, 1.0))


def make_thin_walls() -> Path:
    reset()
    white = diffuse_material("White Plaster", (0.7, 0.7, 0.7))
    inward_room("Room", (3.0, 2.0, 2.2), [white])
    # the partition: one plane at x = 0 (front towards +x), from the -y wall to 0.6 m short of the +y wall
    board = diffuse_material("Partition Paint", (0.75, 0.72, 0.68))
    quad("Partition", [(0.0, -1.0, 0.0), (0.0, 0.4, 0.0), (0.0, 0.4, 2.2), (0.0, -1.0, 2.2)], board)
    shelf = diffuse_material("Shelf Wood", (0.55, 0.4, 0.25))  # a board without thickness, front up
    quad("Shelf", [(-1.3, -0.9, 0.8), (-0.5, -0.9, 0.8), (-0.5, -0.5, 0.8), (-1.3, -0.5, 0.8)], shelf)
    add_lamp("Warm Lamp", "POINT", (-0.8, -0.3, 1.7), (0, 0, 0), colour=(1.0, 0.75, 0.5), energy=120.0,
             shadow_soft_size=0.0)
    add_lamp("Cool Lamp", "POINT", (0.8, -0.3, 1.7), (0, 0, 0), colour=(0.5, 0.75, 1.0), energy=120.0,
             shadow_soft_size=0.0)
    return finish_sample("thin_walls.blend", (1.4, 0.9, 1.6), (-0.5, -0.6, 0.9))


RUG = ((0.25, -0.6), (1.4, 0.4))  # (x, y) corners: 10 cm from the +x wall at x = 1.5


def make_textured() -> Path:
    reset()
    white = diffuse_material("White Plaster", (0.75, 0.75, 0.75))
    room = inward_room("Room", (3.0, 3.0, 2.5), [white])
    # the floor and the back wall are objects of their own: the room box keeps no floor or back wall
    import bmesh  # (after bpy: Blender's own module)

    mesh = room.data
    editing = bmesh.new()
    editing.from_mesh(mesh)
    editing.faces.ensure_lookup_table()
    bmesh.ops.delete(editing, geom=[editing.faces[0], editing.faces[3]], context="FACES_ONLY")
    editing.to_mesh(mesh)
    editing.free()
    checker = packed_image("Floor Checker", checker_pixels(8, 64, (0.85, 0.85, 0.82), (0.55, 0.55, 0.52)))
    floor = quad("Floor", [(-1.5, -1.5, 0.0), (1.5, -1.5, 0.0), (1.5, 1.5, 0.0), (-1.5, 1.5, 0.0)],
                 textured_material("Checker Floor", image=checker))
    planar_uv(floor, (0, 1))
    wall = textured_material("Checker Wallpaper", procedural=((0.7, 0.6, 0.4), (0.3, 0.4, 0.6), 4.0))
    quad("Back Wall", [(-1.5, 1.5, 0.0), (1.5, 1.5, 0.0), (1.5, 1.5, 2.5), (-1.5, 1.5, 2.5)], wall)
    stripes = packed_image("Rug Stripes", stripe_pixels(6, 32, (0.85, 0.15, 0.12), (0.6, 0.08, 0.07)))
    (x0, y0), (x1, y1) = RUG
    rug = quad("Rug", [(x0, y0, 0.01), (x1, y0, 0.01), (x1, y1, 0.01), (x0, y1, 0.01)],
               textured_material("Red Rug", image=stripes))
    planar_uv(rug, (0, 1))
    add_lamp("Ceiling Lamp", "AREA", (-0.2, 0.0, 2.45), (0, 0, 0), energy=250.0, size=0.8)
    return finish_sample("textured.blend", (-1.2, -1.3, 1.7), (0.6, 0.5, 0.4))


def make_node_materials() -> Path:
    reset()
    inward_room("Room", (3.0, 3.0, 2.5), [diffuse_material("White Plaster", (0.7, 0.7, 0.7))])
    panel = shader_material("Emission Shader", "emission", emission=(1.0, 0.9, 0.75), strength=8.0)
    # a glowing sign 25 cm in front of the +y wall, its front towards -y: its back lights the wall
    quad("Emission Panel", [(-0.5, 1.25, 1.2), (0.5, 1.25, 1.2), (0.5, 1.25, 1.8), (-0.5, 1.25, 1.8)], panel)
    cubes = {
        "Diffuse Cube": (shader_material("Diffuse Shader", "diffuse", colour=(0.2, 0.5, 0.8)), (-0.9, 0.3)),
        "Mix Cube": (shader_material("Mix Shader", "mix", colour=(0.8, 0.3, 0.2), emission=(0.2, 0.6, 1.0),
                                     strength=3.0, factor=0.3), (-0.3, -0.6)),
        "Add Cube": (shader_material("Add Shader", "add", colour=(0.3, 0.75, 0.3), emission=(1.0, 1.0, 0.5),
                                     strength=0.5), (0.5, -0.2)),
        "Plain Cube": (None, (1.0, 0.6)),  # no material: Cycles shades it with Blender's default
    }
    for name, (material, (x, y)) in cubes.items():
        vertices, faces = box((x, y, 0.25), (0.5, 0.5, 0.5))
        mesh_object(name, vertices, faces, [material] if material is not None else [])
    return finish_sample("node_materials.blend", (0.0, -1.4, 1.5), (0.0, 0.6, 0.5))


CHAIR_AT = (-0.3, -0.2)  # the instanced chair, under the lamp
LAMP_HEIGHT = 2.2


def chair_shape():
    """A chair at the origin, its seat's centre above it, facing +y: seat, back and four legs (36 quads)."""
    half, seat, thick, leg, inset = 0.22, 0.45, 0.05, 0.05, 0.01  # legs inset: each part a closed box of its own
    legs = [box_between((sx, sy, 0.0), (sx + leg, sy + leg, seat))
            for sx in (-half + inset, half - inset - leg) for sy in (-half + inset, half - inset - leg)]
    return merge(box_between((-half, -half, seat), (half, half, seat + thick)),
                 box_between((-half, -half, seat + thick), (half, -half + leg, seat + thick + 0.45)), *legs)


def make_instances() -> Path:
    reset()
    inward_room("Room", (3.0, 3.0, 2.5), [diffuse_material("White Plaster", (0.7, 0.7, 0.7))])
    vertices, faces = chair_shape()
    chair_collection = bpy.data.collections.new("Chair Asset")  # not in the scene: only instanced
    chair = bpy.data.objects.new("Chair", bpy.data.meshes.new("Chair"))
    chair.data.from_pydata(vertices, [], faces)
    chair.data.materials.append(diffuse_material("Chair Wood", (0.5, 0.32, 0.18)))
    chair.data.update()
    chair_collection.objects.link(chair)
    instance = bpy.data.objects.new("Chair Instance", None)
    instance.instance_type = "COLLECTION"
    instance.instance_collection = chair_collection
    instance.location = (*CHAIR_AT, 0.0)
    instance.rotation_euler = (0.0, 0.0, math.radians(15.0))
    bpy.context.scene.collection.objects.link(instance)
    copy = bpy.data.objects.new("Chair Copy", chair.data)  # a linked duplicate (Alt+D): the same mesh
    copy.location = (0.9, 0.8, 0.0)
    copy.rotation_euler = (0.0, 0.0, math.radians(200.0))
    bpy.context.scene.collection.objects.link(copy)
    add_lamp("Lamp", "POINT", (*CHAIR_AT, LAMP_HEIGHT), (0, 0, 0), energy=150.0, shadow_soft_size=0.0)
    return finish_sample("instances.blend", (1.2, -1.4, 1.6), (-0.2, 0.0, 0.3))


SAMPLES = (make_cornell_box, make_room, make_emissive_ceiling, make_thin_walls, make_textured, make_node_materials,
           make_instances)


def main(argv=None) -> int:
    global OUT_DIR
    if argv is None:  # Blender passes its own arguments; ours come after "--"
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description="write the sample .blend files")
    parser.add_argument("--output-dir", type=Path, default=OUT_DIR)
    OUT_DIR = parser.parse_args(argv).output_dir.resolve()
    for make in SAMPLES:
        make()
    return 0


if __name__ == "__main__":
    sys.exit(main())
