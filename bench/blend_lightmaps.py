"""Lightmaps of a .blend as numpy, for compare.py: the add-on's EXRs read back, their sizes (the
sizes the Cycles reference is baked at), and where each texel lies in the world.

Images come as (H, W, 4) float32, rows bottom-up as Blender stores them, coverage in alpha.
"""

from __future__ import annotations

from pathlib import Path

import bpy
import numpy as np

from radiosity_addon.blender.apply import file_name
from radiosity_addon.blender.tags import lightmap_image_name
from .blend_reference import UV_MAP
from .compare import inside_box, rasterize_texels
from .rooms import ROOM_PROPERTY


def image_pixels(image) -> np.ndarray:
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(height, width, 4)


def read_lightmaps(directory, names) -> dict:
    """{object: (H, W, 4)} from the EXRs the add-on's bake wrote for the objects `names` into `directory`."""
    lightmaps = {}
    for name in names:
        path = Path(directory) / f"{file_name(lightmap_image_name(name))}.exr"
        if not path.is_file():
            raise FileNotFoundError(f"no lightmap of '{name}' in {directory} (looked for {path.name})")
        image = bpy.data.images.load(str(path.resolve()), check_existing=False)
        try:  # a float EXR's pixels come as stored (marking it non-colour data would convert them)
            lightmaps[name] = image_pixels(image)
        finally:
            bpy.data.images.remove(image)
    return lightmaps


def sizes_of(lightmaps: dict) -> dict:
    """{object: (width, height)}: what blend_reference bakes at to match these lightmaps."""
    return {name: (image.shape[1], image.shape[0]) for name, image in lightmaps.items()}


def lightmap_triangles(obj, depsgraph) -> tuple[np.ndarray, np.ndarray]:
    """The evaluated mesh's triangles (modifiers applied): Lightmap UVs (T, 3, 2) and world positions (T, 3, 3)."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        count = len(mesh.loop_triangles)
        loops = np.empty(count * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("loops", loops)
        corners = np.empty(len(mesh.loops), dtype=np.int64)
        mesh.loops.foreach_get("vertex_index", corners)
        positions = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
        mesh.vertices.foreach_get("co", positions)
        uv = np.empty(len(mesh.loops) * 2, dtype=np.float64)
        mesh.uv_layers[UV_MAP].data.foreach_get("uv", uv)
    finally:
        evaluated.to_mesh_clear()
    matrix = np.array(evaluated.matrix_world, dtype=np.float64)
    world = positions.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    return uv.reshape(-1, 2)[loops].reshape(count, 3, 2), world[corners[loops]].reshape(count, 3, 3)


def texel_geometry(sizes: dict) -> tuple[dict, dict]:
    """({object: (H, W, 3)} world position of each texel centre, {object: (H, W)} world area per
    texel) of the open file's objects at `sizes`; NaN where no triangle's Lightmap UVs cover the centre."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    positions, areas = {}, {}
    for name, (width, height) in sizes.items():
        uv, world = lightmap_triangles(bpy.data.objects[name], depsgraph)
        positions[name], areas[name] = rasterize_texels(uv, world, width, height)
    return positions, areas


def room_interior() -> tuple[list, list]:
    """(low, high) corners of the open room file's inside (rooms.py keeps them in the scene)."""
    room = bpy.context.scene.get(ROOM_PROPERTY)
    if room is None:
        raise ValueError(f"the open file has no '{ROOM_PROPERTY}' property: not a room from rooms.py")
    return list(room["interior_min"]), list(room["interior_max"])


def inside_room(positions: dict, margin: float = 0.01) -> dict:
    """{object: bool (H, W)}: texels at `positions` (texel_geometry) inside the open room file's
    inside, grown by `margin`. Faces in the walls' thickness (reveals, the window frame), outer
    faces and hidden faces under the walls are outside."""
    low, high = room_interior()
    return {name: inside_box(p, low, high, margin) for name, p in positions.items()}
