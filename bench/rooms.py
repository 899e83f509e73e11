"""Furnished rooms of the kind Blender users bake, from ~1k to ~100k triangles: the benchmark's
realistic scenes (dev only, like the rest of the benchmark).

    python -m bench.rooms --triangles 4000 --output out/rooms/room_4k.blend

The room (room_layout.py has its geometry): 6 × 4 × 2.8 m inside; floor, ceiling and walls are
closed slabs with thickness; a window opening with a frame in the south wall and a SUN lamp
shining through it onto the floor and the table; an AREA lamp over the sofa; an emissive ceiling
panel; a table with chairs (linked duplicates of one mesh), a shelf with rows of books inside it,
a sofa and its cushions with Bevel and Subdivision Surface modifiers, a rug, a vase and a bowl;
single sheets without thickness too: a curtain, a painting 1 cm off a wall, the panel. Materials are
Principled BSDFs with roughness 1 and no specular, several coloured; the world is black unless
`world_colour` is given. Every mesh has a 'Lightmap' UV map made by Lightmap Pack, so the
add-on's bake and a Cycles bake of the file use the same texels. The inside's bounds are kept in
the scene's ID property `ROOM_PROPERTY` for comparisons that count only texels inside the room.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import asdict
from pathlib import Path

import bpy

from . import room_layout as layout
from .blend_scenes import (add_camera, add_lamp, diffuse_material, evaluated_triangles, lightmap_pack, looking_at,
                           mesh_object, reset, save_blend)
from .shapes import box_between, merge

ROOM_PROPERTY = "radiosity_bench_room"

# key -> (material name, base colour, emission)
MATERIALS = {
    "floor": ("Oak Floor", (0.45, 0.30, 0.18), None),
    "ceiling": ("Ceiling White", (0.80, 0.80, 0.78), None),
    "plaster": ("Plaster", (0.75, 0.74, 0.70), None),
    "paint": ("Sage Paint", (0.42, 0.52, 0.38), None),
    "frame": ("Frame White", (0.85, 0.85, 0.85), None),
    "painting": ("Painting", (0.20, 0.35, 0.60), None),
    "panel": ("Ceiling Panel", (0.80, 0.80, 0.80), (6.0, 5.7, 5.1)),
    "rug": ("Rug Red", (0.60, 0.20, 0.15), None),
    "shelf": ("Birch", (0.62, 0.50, 0.36), None),
    "table": ("Walnut", (0.35, 0.22, 0.12), None),
    "chair": ("Chair Blue", (0.15, 0.25, 0.55), None),
    "curtain": ("Curtain Linen", (0.70, 0.62, 0.50), None),
    "sofa": ("Sofa Teal", (0.20, 0.38, 0.36), None),
    "cushion": ("Cushion Mustard", (0.72, 0.55, 0.20), None),
    "ceramic": ("Ceramic", (0.70, 0.74, 0.78), None),
}
BOOK_MATERIALS = [("Book Red", (0.55, 0.10, 0.08)), ("Book Green", (0.12, 0.35, 0.15)),
                  ("Book Navy", (0.08, 0.12, 0.35)), ("Book Ochre", (0.65, 0.48, 0.15)),
                  ("Book Cream", (0.80, 0.76, 0.64))]
SUN_ELEVATION, SUN_AZIMUTH = 35.0, 15.0  # degrees above the horizon; east of north-going
CAMERA_EYE, CAMERA_TARGET, CAMERA_ANGLE = (0.35, 2.9, 1.75), (4.5, 0.9, 0.6), 85.0  # shelf, table, window


def _materials() -> dict:
    made = {key: diffuse_material(name, colour, emission or (0.0, 0.0, 0.0))
            for key, (name, colour, emission) in MATERIALS.items()}
    made["books"] = [diffuse_material(name, colour) for name, colour in BOOK_MATERIALS]
    return made


def _sun_direction() -> tuple:
    elevation, azimuth = math.radians(SUN_ELEVATION), math.radians(SUN_AZIMUTH)
    return (math.sin(azimuth) * math.cos(elevation), math.cos(azimuth) * math.cos(elevation), -math.sin(elevation))


def _add_lamps(sun_strength: float, area_power: float) -> None:
    sun_at = (3.0, -4.0, 4.0)
    towards = tuple(p + d for p, d in zip(sun_at, _sun_direction()))
    add_lamp("Sun", "SUN", sun_at, looking_at(sun_at, towards), colour=(1.0, 0.96, 0.9), energy=sun_strength)
    add_lamp("Area Light", "AREA", (1.6, 3.35, layout.HEIGHT - 0.1), (0.0, 0.0, 0.0), colour=(1.0, 0.9, 0.8),
             energy=area_power, shape="RECTANGLE", size=1.0, size_y=0.4)


def _add_furniture(detail: layout.Detail, materials: dict, seed: int) -> list:
    """The pieces that the detail sizes; returns the objects with modifiers (the sofa's)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    mesh_object("Table", *layout.table(detail), [materials["table"]])
    mesh_object("Curtain", *layout.curtain(detail), [materials["curtain"]])
    mesh_object("Vase", *layout.vase(detail), [materials["ceramic"]])
    mesh_object("Bowl", *layout.bowl(detail), [materials["ceramic"]])
    chair = mesh_object("Chair 1", *layout.chair(detail), [materials["chair"]])
    chair.data.name = "Chair"
    for index, ((x, y), yaw) in enumerate(layout.chair_places(detail.chairs)):
        if index > 0:  # linked duplicates (Alt+D): one mesh, one set of Lightmap UVs
            chair = bpy.data.objects.new(f"Chair {index + 1}", chair.data)
            bpy.context.scene.collection.objects.link(chair)
        chair.location = (x + rng.uniform(-0.04, 0.04), y + rng.uniform(-0.04, 0.04), 0.0)
        chair.rotation_euler = (0.0, 0.0, math.radians(yaw + rng.uniform(-8.0, 8.0)))
    for level in range(len(layout.SHELF_BOARDS) - 1):
        vertices, faces, colours = layout.books(detail, level, rng)
        mesh_object(f"Books {level + 1}", vertices, faces, materials["books"], colours)
    upholstered = []
    for name, boxes, key in (("Sofa", layout.SOFA_BOXES, "sofa"), ("Cushions", layout.CUSHION_BOXES, "cushion")):
        obj = mesh_object(name, *merge(*[box_between(*b) for b in boxes]), [materials[key]])
        bevel = obj.modifiers.new("Bevel", "BEVEL")
        bevel.width = layout.SOFA_BEVEL_WIDTH
        bevel.segments = detail.bevel_segments
        subdivision = obj.modifiers.new("Subdivision", "SUBSURF")
        subdivision.levels = subdivision.render_levels = detail.subdivision
        upholstered.append(obj)
    return upholstered


def build_room(triangles_target: int, seed: int = 0, world_colour=None, sun_strength: float = 4.0,
               area_power: float = 80.0) -> dict:
    """Replace the bpy session's content with the furnished room (see the module's doc).

    `triangles_target` sets the detail (layout.detail_for); `seed` the books' sizes and colours and
    the chairs' placement. Returns {"triangles" (real, evaluated, modifiers applied),
    "triangles_target", "triangles_per_object", "objects", "detail", "seconds"}.
    """
    started = time.perf_counter()
    reset(world_colour)
    detail = layout.detail_for(triangles_target)
    materials = _materials()
    for name, ((vertices, faces), key) in layout.fixed_pieces().items():
        mesh_object(name, vertices, faces, [materials[key]])
    _add_furniture(detail, materials, seed)
    _add_lamps(sun_strength, area_power)
    add_camera(CAMERA_EYE, looking_at(CAMERA_EYE, CAMERA_TARGET), CAMERA_ANGLE)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 400
    scene[ROOM_PROPERTY] = {"interior_min": [0.0, 0.0, 0.0],
                            "interior_max": [layout.WIDTH, layout.DEPTH, layout.HEIGHT],
                            "triangles_target": int(triangles_target), "seed": int(seed)}
    meshes = [obj for obj in scene.objects if obj.type == "MESH"]
    lightmap_pack(meshes)
    for obj in meshes:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    per_object = evaluated_triangles(meshes)
    return {"triangles": sum(per_object.values()), "triangles_target": int(triangles_target),
            "triangles_per_object": per_object, "objects": len(meshes), "detail": asdict(detail),
            "seconds": time.perf_counter() - started}


def save_room(path, triangles_target: int, seed: int = 0, **options) -> dict:
    """build_room(...) saved as a .blend at `path`; returns build_room's summary with "path"."""
    summary = build_room(triangles_target, seed, **options)
    save_blend(path)
    return {**summary, "path": str(path)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.rooms", description=__doc__.split("\n")[0])
    parser.add_argument("--triangles", type=int, required=True, metavar="N", help="about how many triangles")
    parser.add_argument("--output", required=True, metavar="FILE.blend")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--world-colour", type=float, nargs=3, metavar=("R", "G", "B"),
                        help="a uniform sky instead of the black world")
    args = parser.parse_args(argv)
    summary = save_room(Path(args.output), args.triangles, args.seed, world_colour=args.world_colour)
    print(f"{summary['path']}: {summary['triangles']} triangles (target {args.triangles}),"
          f" {summary['objects']} mesh objects, built in {summary['seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
