"""rooms.py: the furnished room has the parts it promises, its detail follows the triangle
target, and it goes through the add-on's bake, the Cycles reference and compare.py."""

from __future__ import annotations

import subprocess
import sys

import blender_support as support
import bpy
import numpy as np
import pytest

from bench import blend_lightmaps, blend_reference, compare, room_layout, rooms
from radiosity_addon.blender.headless import HeadlessBake, bake_file
from radiosity_addon.blender.lights import world_colour


def meshes():
    return {obj.name: obj for obj in bpy.context.scene.objects if obj.type == "MESH"}


def edge_uses(mesh) -> np.ndarray:
    """How many faces use each edge: 2 everywhere on a closed solid, 1 along a sheet's border."""
    edges = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("edge_index", edges)
    return np.bincount(edges, minlength=len(mesh.edges))


def hit(origin, direction):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    found, location, _, _, obj, _ = bpy.context.scene.ray_cast(depsgraph, origin, direction)
    return obj.name if found else None, tuple(location)


@pytest.fixture(scope="module")
def room_4k():
    return rooms.build_room(4000)


def test_room_has_lamps_panel_modifiers_sheets_and_lightmap_uvs(room_4k):
    scene = bpy.context.scene
    assert sorted(obj.data.type for obj in scene.objects if obj.type == "LIGHT") == ["AREA", "SUN"]
    panel = meshes()["Ceiling Panel"]
    principled = panel.material_slots[0].material.node_tree.nodes["Principled BSDF"]
    assert principled.inputs["Emission Strength"].default_value > 0 and len(panel.data.polygons) == 1
    for name in ("Sofa", "Cushions"):
        assert [m.type for m in meshes()[name].modifiers] == ["BEVEL", "SUBSURF"]
        assert meshes()[name].modifiers["Subdivision"].levels >= 1
    for name in ("Floor", "Ceiling", "Wall North", "Window Wall", "Shelf", "Books 1"):
        assert (edge_uses(meshes()[name].data) == 2).all(), f"{name} is not a closed solid"
    for name in ("Curtain", "Painting", "Ceiling Panel"):
        assert (edge_uses(meshes()[name].data) == 1).any(), f"{name} is not a single sheet"
    assert all("Lightmap" in obj.data.uv_layers for obj in meshes().values())
    chairs = [obj for name, obj in meshes().items() if name.startswith("Chair")]
    assert len(chairs) >= 2 and len({obj.data.name for obj in chairs}) == 1  # linked duplicates
    world = scene.world.node_tree.nodes["Background"]
    assert world.inputs["Strength"].default_value == 0 or tuple(world.inputs["Color"].default_value)[:3] == (0, 0, 0)


def test_window_is_an_opening_and_the_walls_are_closed_around_it(room_4k):
    x0, x1, z0, z1 = room_layout.WINDOW
    through, where = hit(((x0 + x1) / 2 + 0.3, -1.0, (z0 + z1) / 2), (0, 1, 0))
    assert through != "Window Wall" and where[1] > 0  # past the wall, inside the room
    assert hit((x0 - 0.5, -1.0, (z0 + z1) / 2), (0, 1, 0))[0] == "Window Wall"


def test_lightmap_uvs_of_the_evaluated_meshes_do_not_overlap(room_4k):
    """Covered texels (each counted once) add up to the charts' total area: no chart lies on another,
    Bevel and Subdivision included."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    size = 512
    for name in ("Sofa", "Cushions", "Window Wall", "Books 1", "Curtain"):
        uv, world = blend_lightmaps.lightmap_triangles(meshes()[name], depsgraph)
        assert uv.min() >= 0 and uv.max() <= 1, name
        edges = uv[:, 1:] - uv[:, :1]
        area = 0.5 * np.abs(edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]).sum()
        covered = np.isfinite(compare.rasterize_texels(uv, world, size, size)[1]).sum()
        assert covered / size**2 == pytest.approx(area, rel=0.03), name


def test_texel_areas_add_up_to_the_surface_and_the_inside_is_the_floor_top():
    rooms.build_room(1000)
    positions, areas = blend_lightmaps.texel_geometry({"Floor": (256, 256)})
    positions, areas = positions["Floor"], areas["Floor"]
    inside = blend_lightmaps.inside_room({"Floor": positions})["Floor"]
    covered = np.isfinite(areas)
    w, d, t, slab = room_layout.WIDTH, room_layout.DEPTH, room_layout.WALL, room_layout.SLAB
    top, sides = (w + 2 * t) * (d + 2 * t), 2 * slab * (w + d + 4 * t)
    assert areas[covered].sum() == pytest.approx(2 * top + sides, rel=0.03)
    assert areas[inside].sum() == pytest.approx(w * d, rel=0.03)
    assert np.allclose(positions[inside][:, 2], 0.0)


def test_triangle_count_follows_the_target_and_its_closed_form():
    counts = {}
    for target in (1000, 4000, 16000):
        summary = rooms.build_room(target)
        counts[target] = summary["triangles"]
        assert summary["triangles"] == sum(summary["triangles_per_object"].values())
        assert summary["triangles"] == room_layout.predicted_triangles(room_layout.Detail(**summary["detail"]))
    assert counts[1000] < 1.3 * 1000
    assert 0.8 * 4000 < counts[4000] <= 4000 and 0.8 * 16000 < counts[16000] <= 16000


def test_world_colour_is_a_sky_the_addon_reads():
    rooms.build_room(1000, world_colour=(0.1, 0.2, 0.3))
    warnings = []
    assert world_colour(bpy.context.scene.world, warnings) == pytest.approx([0.1, 0.2, 0.3]) and not warnings
    rooms.build_room(1000)
    assert world_colour(bpy.context.scene.world, warnings) is None  # black: no sky


def test_command_line_saves_a_room(tmp_path):
    path = tmp_path / "room.blend"
    result = subprocess.run([sys.executable, "-m", "bench.rooms", "--triangles", "1000",
                             "--output", str(path)], capture_output=True, text=True, cwd=support.ROOT, timeout=120)
    assert result.returncode == 0, result.stderr[-2000:]
    triangles = room_layout.predicted_triangles(room_layout.detail_for(1000))
    assert path.is_file() and f"{path}: {triangles} triangles (target 1000), 23 mesh objects" in result.stdout


def test_room_bakes_with_the_addon_and_compares_with_cycles(tmp_path):
    path = tmp_path / "room.blend"
    rooms.save_room(path, 1000)
    bake_file(HeadlessBake(str(path), solve_options={"method": "hemicube", "patch_size": 1.0, "subdiv": None,
                                                     "hemicube_res": 16, "refinements": 0},
                           lightmap_options={"texel_density": 8.0, "content": "combined"}, output_dir=str(tmp_path / "maps")))
    names = list(rooms.build_room(1000)["triangles_per_object"])
    ours = blend_lightmaps.read_lightmaps(tmp_path / "maps", names)
    reference = blend_reference.cycles_lightmaps(path, blend_lightmaps.sizes_of(ours), "combined", samples=4)
    positions, areas = blend_lightmaps.texel_geometry(blend_lightmaps.sizes_of(ours))
    result = compare.compare(ours, reference["images"], blend_lightmaps.inside_room(positions), areas)
    # an emitter's own emission dominates its lightmap in both
    assert result["objects"]["Ceiling Panel"]["relative_rgb"] == pytest.approx(0, abs=0.05)
    assert 0 < result["texels_inside"] < result["texels"]
    assert np.isfinite(result["texel_rms"]) and np.isfinite(result["texel_rms_inside"])
