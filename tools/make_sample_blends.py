"""Write sample_blends/cornell_box.blend and sample_blends/room.blend.

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
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radiosity_addon.bench.blend_scenes import (add_camera, box, diffuse_material, mesh_object, reset,  # noqa: E402
                                                select_meshes)

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


def main(argv=None) -> int:
    global OUT_DIR
    if argv is None:  # Blender passes its own arguments; ours come after "--"
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description="write the sample .blend files")
    parser.add_argument("--output-dir", type=Path, default=OUT_DIR)
    OUT_DIR = parser.parse_args(argv).output_dir.resolve()
    make_cornell_box()
    make_room()
    return 0


if __name__ == "__main__":
    sys.exit(main())
