"""Production scenes, as users get them, from ~50k to ~500k triangles: the benchmark's dense family
(dev only, like the rest of the benchmark).

    python -m bench.production --triangles 300000 --output out/production/p300k.blend
        [--objects 30]

A terrace of 10 x 8 m under a sun and a blue sky: a tiled stone floor (an image texture) and two
walls with a window, all triangulated grids; a pergola of four posts and beams under a canopy of
alpha-cut leaf cards (a leaf-mask image on a Principled BSDF's Alpha, as glTF imports leaves); a
potted plant of leaf cards; a sofa and a table with chairs as dense rounded boxes (what a
Subdivision Surface over a bevelled box gives), a sculpt-like boulder (a noisy icosphere), and a
shelf of 20 crates with a material each, stored as a triangle soup (no vertex shared, as many
imports give meshes). The detail of every piece follows `triangles`. There are 10 objects, one per
piece; with `objects` above that the largest pieces are cut into parts to make about that many,
and with 1 the whole terrace is one object holding every material (as an import gives it).

Every mesh gets a 'Lightmap' UV map made by Smart UV Project (what a user preparing lightmaps
does), so the add-on's bake and Cycles' bake of the file use the same texels.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import sys
import time
from pathlib import Path

import bpy
import numpy as np

from . import dense_shapes as shapes
from .blend_scenes import add_camera, add_lamp, diffuse_material, evaluated_triangles, looking_at, reset, save_blend

SIZE = (10.0, 8.0)  # the terrace floor, metres
WALL_HEIGHT = 3.0
SKY = (0.35, 0.45, 0.65)
SUN_ENERGY = 4.0
LEAF_SIZE = 0.35  # a leaf card's side, metres
MAX_CANOPY_CARDS = 3000  # beyond, the canopy's share of the triangles goes to the other pieces' detail
MAX_PLANT_CARDS = 400
TILE_REPEAT = 2.5  # metres of floor per repeat of the tile image
FLOOR_GAP = 0.002  # metres between the floor and what stands on it
CANOPY_LOW, CANOPY_HIGH = (-2.6, -2.0, 2.55), (0.8, 1.4, 3.05)  # the box the canopy's leaf cards are centred in
# each piece's share of the triangles (the floor, walls and furniture carry most, as in real scenes)
SHARES = {"floor": 0.22, "walls": 0.16, "sofa": 0.15, "boulder": 0.15, "table": 0.11, "shelf": 0.08,
          "pergola": 0.06, "canopy": 0.04, "plant": 0.03}
PRODUCTION_PROPERTY = "radiosity_bench_production"


def _image(name: str, pixels: np.ndarray):
    """A packed image of float RGBA pixels (H, W, 4), row 0 at the bottom."""
    height, width = pixels.shape[:2]
    image = bpy.data.images.new(name, width, height, alpha=True)
    image.pixels.foreach_set(np.ascontiguousarray(pixels, dtype=np.float32).ravel())
    image.pack()
    return image


def _stone_tiles(size: int = 256) -> np.ndarray:
    """Tiles of three stone greys with darker joints."""
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:size, 0:size]
    cell = (y // 32) * 8 + (x // 32)
    tone = rng.uniform(0.35, 0.6, 64)[cell]
    joint = (y % 32 < 2) | (x % 32 < 2)
    grey = np.where(joint, 0.18, tone)
    return np.stack([grey * 1.05, grey, grey * 0.9, np.ones_like(grey)], axis=-1)


def _leaf_mask(size: int = 128) -> np.ndarray:
    """Five leaves of a twig on a clear card: alpha 1 inside ellipses, 0 outside."""
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size
    alpha = np.zeros((size, size))
    for cx, cy, angle, length, width in ((0.5, 0.25, 90, 0.22, 0.09), (0.3, 0.45, 130, 0.2, 0.08),
                                         (0.7, 0.45, 50, 0.2, 0.08), (0.35, 0.72, 120, 0.18, 0.07),
                                         (0.65, 0.72, 60, 0.18, 0.07)):
        a = math.radians(angle)
        dx, dy = x - cx, y - cy
        along, across = dx * math.cos(a) + dy * math.sin(a), -dx * math.sin(a) + dy * math.cos(a)
        alpha = np.maximum(alpha, ((along / length) ** 2 + (across / width) ** 2 <= 1.0).astype(float))
    stem = (np.abs(x - 0.5) < 0.015) & (y < 0.85)
    alpha = np.maximum(alpha, stem)
    green = np.stack([0.12 + 0.1 * y, 0.35 + 0.15 * y, 0.08 + 0.0 * y], axis=-1)
    return np.concatenate([green, alpha[..., None]], axis=-1)


def _textured_material(name: str, image, alpha: bool = False):
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    principled = nodes["Principled BSDF"]
    principled.inputs["Roughness"].default_value = 1.0
    principled.inputs["Specular IOR Level"].default_value = 0.0
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    links.new(texture.outputs["Color"], principled.inputs["Base Color"])
    if alpha:
        links.new(texture.outputs["Alpha"], principled.inputs["Alpha"])
    return material


def _materials() -> dict:
    made = {"stone": _textured_material("Stone Tiles", _image("stone tiles", _stone_tiles())),
            "leaf": _textured_material("Leaves", _image("leaf mask", _leaf_mask()), alpha=True),
            "plaster": diffuse_material("Plaster", (0.78, 0.74, 0.66)),
            "wood": diffuse_material("Teak", (0.42, 0.28, 0.16)),
            "fabric": diffuse_material("Sofa Linen", (0.62, 0.58, 0.50)),
            "metal": diffuse_material("Painted Steel", (0.16, 0.18, 0.2)),
            "rock": diffuse_material("Granite", (0.46, 0.44, 0.42)),
            "terracotta": diffuse_material("Terracotta", (0.62, 0.32, 0.2))}
    rng = np.random.default_rng(3)
    made["crates"] = [diffuse_material(f"Crate {k + 1}", tuple(rng.uniform(0.1, 0.8, 3))) for k in range(20)]
    return made


def _resolution(triangles: float, per_unit: float, power: float = 0.5, low: int = 1) -> int:
    """The resolution whose shape gives about `triangles`: `per_unit` triangles at resolution 1,
    growing as resolution^(1/power)."""
    return max(low, int(round((triangles / per_unit) ** power)))


def _pieces(triangles: int, materials: dict, seed: int) -> list:
    """(name, material key or list, vertices, triangles, face materials or None, texture UVs or None)."""
    rng = np.random.default_rng(seed)
    share = {key: value * triangles for key, value in SHARES.items()}
    width, depth = SIZE
    pieces = []
    n = _resolution(share["floor"], 2 * depth / width)
    m = max(1, round(n * depth / width))
    floor = shapes.grid([-width / 2, -depth / 2, 0], [width, 0, 0], [0, depth, 0], n, m)
    pieces.append(("Floor", "stone", *floor, None, floor[0][:, :2] / TILE_REPEAT))
    # walls facing the terrace: the back one (along x at y = depth/2) with a window opening, the side
    # one (along y at x = -width/2)
    per_wall = share["walls"] / 2
    n = _resolution(per_wall, 2 * WALL_HEIGHT / width)
    m = max(1, round(n * WALL_HEIGHT / width))
    back = shapes.grid([-width / 2, depth / 2, 0], [width, 0, 0], [0, 0, WALL_HEIGHT], n, m)
    centres = back[0][back[1]].mean(axis=1)
    window = (np.abs(centres[:, 0] - 1.5) < 1.2) & (np.abs(centres[:, 2] - 1.6) < 0.7)
    back = (back[0], back[1][~window])
    side = shapes.grid([-width / 2, -depth / 2, 0], [0, depth, 0], [0, 0, WALL_HEIGHT], max(1, round(n * depth / width)), m)
    pieces.append(("Walls", "plaster", *shapes.merge(back, side), None, None))
    # furniture as dense rounded boxes
    k = _resolution(share["sofa"] / 4, 12)
    sofa = shapes.merge(shapes.rounded_box([1.5, 2.6, 0.22], [2.2, 0.9, 0.44], 0.08, k),
                        shapes.rounded_box([1.5, 2.97, 0.6], [2.2, 0.2, 0.8], 0.07, k),
                        shapes.rounded_box([0.45, 2.6, 0.5], [0.18, 0.9, 0.55], 0.06, k),
                        shapes.rounded_box([2.55, 2.6, 0.5], [0.18, 0.9, 0.55], 0.06, k))
    pieces.append(("Sofa", "fabric", *sofa, None, None))
    k = _resolution(share["table"] / 25, 12)
    table = [shapes.rounded_box([1.5, 0.8, 0.72], [1.6, 0.9, 0.05], 0.02, k)]
    table += [shapes.rounded_box([1.5 + sx * 0.7, 0.8 + sy * 0.35, 0.35], [0.06, 0.06, 0.7], 0.02, k)
              for sx in (-1, 1) for sy in (-1, 1)]
    for cx, cy in ((0.9, -0.05), (2.1, -0.05), (0.9, 1.65), (2.1, 1.65)):
        table += [shapes.rounded_box([cx, cy, 0.45], [0.45, 0.45, 0.04], 0.015, k)]
        table += [shapes.rounded_box([cx + sx * 0.19, cy + sy * 0.19, 0.22], [0.035, 0.035, 0.44], 0.01, k)
                  for sx in (-1, 1) for sy in (-1, 1)]
    pieces.append(("Table And Chairs", "wood", *shapes.merge(*table), None, None))
    subdivisions = max(2, int(round(math.log(max(share["boulder"], 80) / 20, 4))))
    pieces.append(("Boulder", "rock", *shapes.boulder([-3.0, -2.2, 0.5], 0.7, subdivisions, seed=seed), None, None))
    # the shelf: 20 crates of 20 materials in one object, a triangle soup
    k = _resolution(share["shelf"] / 21, 12)
    crates, face_crate = [], []
    for c in range(20):
        row, column = divmod(c, 5)
        crate = shapes.rounded_box([-4.6, 2.0 + 0.45 * column, 0.25 + 0.45 * row], [0.5, 0.4, 0.38], 0.02, k)
        crates.append(crate)
        face_crate.append(np.full(len(crate[1]), c))
    frame = shapes.rounded_box([-4.6, 2.9, 0.95], [0.55, 2.3, 0.06], 0.01, k)
    crates.append(frame)
    face_crate.append(np.full(len(frame[1]), 0))
    pieces.append(("Shelf", "crates", *shapes.soup(*shapes.merge(*crates)), np.concatenate(face_crate), None))
    # the pergola: posts and beams, then its canopy of leaf cards
    segments = max(8, _resolution(share["pergola"] / 8, 2, power=0.5))
    rings = max(1, segments // 2)
    pergola = [shapes.cylinder([x, y, 0], 0.07, 2.6, segments, rings) for x in (-2.4, 0.6) for y in (-1.8, 1.2)]
    k = _resolution(share["pergola"] / 8, 12)
    pergola += [shapes.rounded_box([-0.9, y, 2.65], [3.4, 0.12, 0.1], 0.02, k) for y in (-1.8, 1.2)]
    pergola += [shapes.rounded_box([x, -0.3, 2.65], [0.12, 3.4, 0.1], 0.02, k) for x in (-2.4, 0.6)]
    pieces.append(("Pergola", "metal", *shapes.merge(*pergola), None, None))
    leaves = int(np.clip(share["canopy"] / 2, 40, MAX_CANOPY_CARDS))
    centres = np.column_stack([rng.uniform(low, high, leaves) for low, high in zip(CANOPY_LOW, CANOPY_HIGH)])
    normals = np.column_stack([rng.normal(0, 0.35, leaves), rng.normal(0, 0.35, leaves), np.ones(leaves)])
    ups = rng.normal(size=(leaves, 3))
    vertices, triangles_, uv = shapes.cards(centres, normals, ups, LEAF_SIZE)
    pieces.append(("Canopy", "leaf", vertices, triangles_, None, uv))
    # the potted plant: a terracotta pot and a cluster of leaf cards around its stem
    segments = max(12, _resolution(share["plant"] / 2, 2, power=0.5))
    pot = shapes.cylinder([3.6, -2.6, 0], 0.3, 0.5, segments, max(1, segments // 3), taper=1.3)
    pieces.append(("Pot", "terracotta", *pot, None, None))
    leaves = int(np.clip(share["plant"] / 4, 24, MAX_PLANT_CARDS))
    height = rng.uniform(0.55, 1.5, leaves)
    around = rng.uniform(0, 2 * math.pi, leaves)
    reach = 0.1 + 0.35 * (height - 0.5)
    centres = np.column_stack([3.6 + reach * np.cos(around), -2.6 + reach * np.sin(around), height])
    normals = np.column_stack([np.cos(around), np.sin(around), rng.uniform(0.3, 1.2, leaves)])
    vertices, triangles_, uv = shapes.cards(centres, normals, np.tile([0, 0, 1.0], (leaves, 1)), LEAF_SIZE * 0.8)
    pieces.append(("Plant", "leaf", vertices, triangles_, None, uv))
    # what stands on the floor stands a hair above it: faces coinciding with the floor's plane are a
    # coin toss for any renderer (Cycles sees the sky through them), not a test of the light
    lifted = []
    for name, key, vertices, triangles_, face_materials, uv in pieces:
        if name not in ("Floor", "Walls"):
            vertices = vertices + [0.0, 0.0, FLOOR_GAP]
        lifted.append((name, key, vertices, triangles_, face_materials, uv))
    return lifted


def array_mesh(name: str, vertices: np.ndarray, triangles: np.ndarray, materials, face_materials=None, uv=None):
    """A mesh object from arrays (no Python loop over faces) of the vertices `triangles` use; `uv`
    (per vertex) becomes its 'UVMap'."""
    used, triangles = np.unique(np.asarray(triangles), return_inverse=True)
    triangles = triangles.reshape(-1, 3)
    vertices = np.asarray(vertices)[used]
    uv = None if uv is None else np.asarray(uv)[used]
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", np.asarray(vertices, dtype=np.float32).ravel())
    mesh.loops.add(3 * len(triangles))
    mesh.loops.foreach_set("vertex_index", np.asarray(triangles, dtype=np.int32).ravel())
    mesh.polygons.add(len(triangles))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(triangles), 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(triangles), 3, dtype=np.int32))
    for material in materials:
        mesh.materials.append(material)
    if face_materials is not None:
        mesh.polygons.foreach_set("material_index", np.asarray(face_materials, dtype=np.int32))
    if uv is not None:
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", np.asarray(uv, dtype=np.float32)[np.asarray(triangles).ravel()].ravel())
    mesh.update()
    mesh.validate()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def smart_uv_lightmaps(objects, uv_name: str = "Lightmap", margin: float = 0.005) -> None:
    """Each mesh gets a `uv_name` UV map by Smart UV Project (the render UV map stays active)."""
    view_layer = bpy.context.view_layer
    for obj in objects:
        mesh = obj.data
        render = next((layer.name for layer in mesh.uv_layers if layer.active_render), None)
        layer = mesh.uv_layers.get(uv_name) or mesh.uv_layers.new(name=uv_name, do_init=False)
        mesh.uv_layers.active = layer
        view_layer.objects.active = obj
        for other in view_layer.objects:
            other.select_set(other is obj)
        with contextlib.redirect_stdout(io.StringIO()), bpy.context.temp_override(
                active_object=obj, object=obj, selected_objects=[obj], selected_editable_objects=[obj]):
            bpy.ops.object.mode_set(mode="EDIT")
            bpy.ops.mesh.select_all(action="SELECT")
            bpy.ops.uv.smart_project(angle_limit=math.radians(66), island_margin=margin, area_weight=0.0,
                                     scale_to_bounds=False)
            bpy.ops.object.mode_set(mode="OBJECT")
        if render is not None:
            mesh.uv_layers[render].active_render = True
            mesh.uv_layers.active = mesh.uv_layers[render]


def build_production(triangles_target: int, objects: int = 10, seed: int = 0) -> dict:
    """Replace the bpy session's content with the terrace (module doc) of about `triangles_target`
    triangles in about `objects` mesh objects (1: one object of every material). Returns
    {"triangles", "triangles_target", "objects", "triangles_per_object", "seconds"}."""
    started = time.perf_counter()
    reset(SKY)
    materials = _materials()
    pieces = _pieces(triangles_target, materials, seed)
    made = []
    if objects <= 1:  # everything in one object: every material in its slots, faces indexed into them
        slots, parts, face_slots, uvs = [], [], [], []
        for name, key, vertices, triangles, face_materials, uv in pieces:
            keys = materials[key] if isinstance(materials[key], list) else [materials[key]]
            first = len(slots)
            slots += keys
            parts.append((vertices, triangles))
            face_slots.append(first + (face_materials if face_materials is not None else np.zeros(len(triangles), int)))
            uvs.append(uv if uv is not None else np.zeros((len(vertices), 2)))
        vertices, triangles = shapes.merge(*parts)
        made.append(array_mesh("Terrace", vertices, triangles, slots, np.concatenate(face_slots), np.concatenate(uvs)))
    else:
        # the dense pieces cut into parts by region until there are about `objects` in all
        cuts = max(1, int(round((objects - len(pieces)) / 4)) + 1) if objects > len(pieces) else 1
        for name, key, vertices, triangles, face_materials, uv in pieces:
            keys = materials[key] if isinstance(materials[key], list) else [materials[key]]
            parts = _split_by_region(vertices, triangles, cuts if name in ("Floor", "Walls", "Boulder", "Sofa") else 1)
            for p, chosen in enumerate(parts):
                label = name if len(parts) == 1 else f"{name} {p + 1}"
                made.append(array_mesh(label, vertices, triangles[chosen], keys,
                                       None if face_materials is None else face_materials[chosen],
                                       None if uv is None else uv))
    sun_at = (4.0, -5.0, 6.0)
    towards = (sun_at[0] - 0.45, sun_at[1] + 0.55, sun_at[2] - 0.7)
    add_lamp("Sun", "SUN", sun_at, looking_at(sun_at, towards), colour=(1.0, 0.95, 0.88), energy=SUN_ENERGY)
    add_camera((4.5, -4.2, 2.2), looking_at((4.5, -4.2, 2.2), (-1.0, 1.0, 0.8)), 70.0)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 400
    smart_uv_lightmaps(made)
    for obj in made:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = made[0]
    per_object = evaluated_triangles(made)
    scene[PRODUCTION_PROPERTY] = {"triangles_target": int(triangles_target), "objects": len(made), "seed": int(seed)}
    return {"triangles": sum(per_object.values()), "triangles_target": int(triangles_target), "objects": len(made),
            "triangles_per_object": per_object, "seconds": time.perf_counter() - started}


def _split_by_region(vertices: np.ndarray, triangles: np.ndarray, parts: int) -> list[np.ndarray]:
    """The triangles in `parts` groups by position along the mesh's longest axis."""
    if parts <= 1:
        return [np.arange(len(triangles))]
    centres = vertices[triangles].mean(axis=1)
    axis = int(np.argmax(np.ptp(centres, axis=0)))
    order = np.argsort(centres[:, axis], kind="stable")
    return [np.sort(chunk) for chunk in np.array_split(order, parts)]


def save_production(path, triangles_target: int, objects: int = 10, seed: int = 0) -> dict:
    summary = build_production(triangles_target, objects, seed)
    save_blend(path)
    return {**summary, "path": str(path)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.production",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--triangles", type=int, required=True, metavar="N", help="about how many triangles")
    parser.add_argument("--objects", type=int, default=10, help="about how many mesh objects (1: one of them all)")
    parser.add_argument("--output", required=True, metavar="FILE.blend")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    summary = save_production(Path(args.output), args.triangles, args.objects, args.seed)
    print(f"{summary['path']}: {summary['triangles']} triangles (target {args.triangles}),"
          f" {summary['objects']} mesh objects, built in {summary['seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
