"""Blender lamps and the world colour: what the export hands the core, and the bake against Cycles.

The scene, built here: a grey (rho = 0.8) 4 x 4 m floor and a 1 m box floating 0.25 m above it,
purely diffuse (roughness 1, specular 0), a black world except in the world test. Each lamp type
(and the world) lights it alone; the add-on's bake and Cycles' Combined bake on the same
'Lightmap' UVs must agree per object and channel within 10 %, as the Cornell test asks.
"""

from __future__ import annotations

import math

import blender_support as support
import bpy
import numpy as np
import pytest
from mathutils import Vector

from bench.blend_scenes import box, diffuse_material, mesh_object, reset
from bench.cycles import bake_object
from radiosity_addon.blender.errors import BakeError
from radiosity_addon.blender.export import check_emitters, export_scene
from radiosity_addon.blender.lights import export_lights, render_lamps
from radiosity_addon.blender.lightmap_uv import add_lightmap_uvs
from radiosity_addon.blender.tags import CREATED_UV

TOLERANCE = 0.10  # per object and channel, relative to Cycles' mean

LAMP_COLOUR = (1.0, 0.8, 0.6)


def build_scene():
    """Floor and box, quick bake settings, black world; returns the two mesh objects."""
    support.ensure_addon()
    reset()
    grey = diffuse_material("grey", (0.8, 0.8, 0.8))
    floor = mesh_object("Floor", [(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], [(0, 1, 2, 3)], [grey])
    box_object = mesh_object("Box", *box((0.0, 0.0, 0.75), (1.0, 1.0, 1.0)), [grey])
    for obj in (floor, box_object):
        obj.radiosity.lightmap_resolution = 32
    settings = bpy.context.scene.radiosity
    settings.content = "combined"  # compared with Cycles' Combined bake
    settings.method = "progressive"
    settings.patch_mode = "SIZE"
    settings.patch_size = 0.5
    settings.elements = "4"
    bpy.context.view_layer.update()
    return [floor, box_object]


def aim(obj, target) -> None:
    """Point a lamp's local -Z at `target`."""
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()


def add_lamp(kind: str, location=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0), name=None, **properties):
    light = bpy.data.lights.new(name or kind.title(), kind)
    light.color = LAMP_COLOUR
    for key, value in properties.items():
        setattr(light, key, value)
    obj = bpy.data.objects.new(name or kind.title(), light)
    obj.location = location
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.update()
    return obj


def set_world(colour, strength) -> None:
    background = next(n for n in bpy.context.scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (*colour, 1.0)
    background.inputs["Strength"].default_value = strength


def exported_extras() -> tuple[dict, list[str]]:
    context = bpy.context
    return export_lights(context.evaluated_depsgraph_get(), render_lamps(context.view_layer), context.scene.world)


# --- the export -----------------------------------------------------------------------------------

def test_point_lamp_exports_position_colour_and_power():
    build_scene()
    add_lamp("POINT", (0.5, -1.0, 2.0), energy=40.0, exposure=1.0)  # exposure 1 doubles the power
    extras, warnings = exported_extras()
    (light,) = extras["lights"]
    assert light["type"] == "point" and light["name"] == "Point"
    assert np.allclose(light["position"], [0.5, -1.0, 2.0])
    assert np.allclose(light["color"], LAMP_COLOUR) and np.isclose(light["power"], 80.0)
    assert "world" not in extras and not warnings


def test_spot_lamp_direction_is_its_local_minus_z():
    build_scene()
    add_lamp("SPOT", (0.0, 0.0, 3.0), name="Down", energy=100.0, spot_size=1.2, spot_blend=0.15)
    add_lamp("SPOT", (0.0, -3.0, 1.0), (math.radians(90), 0.0, 0.0), name="Along Y", energy=100.0)
    lights = {light["name"]: light for light in exported_extras()[0]["lights"]}
    assert np.allclose(lights["Down"]["direction"], [0, 0, -1])
    assert np.allclose(lights["Along Y"]["direction"], [0, 1, 0], atol=1e-6)  # Rx(90) takes -Z to +Y
    assert np.isclose(lights["Down"]["spot_size"], 1.2) and np.isclose(lights["Down"]["spot_blend"], 0.15)
    assert np.allclose(lights["Down"]["position"], [0, 0, 3]) and np.isclose(lights["Down"]["power"], 100.0)


def test_sun_exports_direction_and_strength():
    build_scene()
    sun = add_lamp("SUN", (5.0, 5.0, 5.0), energy=3.0)
    aim(sun, (0.0, 0.0, 0.0))
    bpy.context.view_layer.update()
    (light,) = exported_extras()[0]["lights"]
    assert light["type"] == "sun" and np.isclose(light["strength"], 3.0) and "position" not in light
    assert np.allclose(light["direction"], -np.ones(3) / math.sqrt(3), atol=1e-6)


@pytest.mark.parametrize("shape, size, size_y, area", [
    ("SQUARE", 0.5, 9.0, 0.25),
    ("RECTANGLE", 0.5, 2.0, 1.0),
    ("DISK", 1.0, 9.0, math.pi / 4),
    ("ELLIPSE", 1.0, 2.0, math.pi / 2),
])
def test_area_lamp_corners_face_along_its_minus_z_with_the_lamp_area(shape, size, size_y, area):
    build_scene()
    lamp = add_lamp("AREA", (0.2, 0.3, 2.0), (math.radians(30), 0.0, math.radians(45)),
                    energy=50.0, shape=shape, size=size, size_y=size_y)
    (light,) = exported_extras()[0]["lights"]
    corners = np.array(light["vertices"])
    assert light["type"] == "area" and corners.shape == (4, 3) and np.isclose(light["power"], 50.0)
    assert np.allclose(corners.mean(axis=0), lamp.location)
    front = 0.5 * np.cross(corners[2] - corners[0], corners[3] - corners[1])  # area vector, by the winding
    minus_z = -np.array(lamp.matrix_world.to_3x3().col[2])
    assert np.isclose(np.linalg.norm(front), area)
    assert np.allclose(front / np.linalg.norm(front), minus_z, atol=1e-6)
    for i in range(4):  # a rectangle, counter-clockwise: each turn points along the front
        a, b, c = corners[i], corners[(i + 1) % 4], corners[(i + 2) % 4]
        assert np.isclose(np.dot(b - a, c - b), 0, atol=1e-6)
        assert np.dot(np.cross(b - a, c - b), minus_z) > 0


def test_normalize_off_temperature_and_exposure_convert_as_in_cycles():
    """Factors measured on Cycles 5.0 (a plane under each lamp, Normalize on vs off)."""
    build_scene()
    add_lamp("POINT", (0, 0, 2), name="Point", energy=10.0, shadow_soft_size=0.25, normalize=False)
    add_lamp("SUN", (0, 0, 2), name="Sun", energy=1.0, angle=0.2, normalize=False)
    add_lamp("AREA", (0, 0, 2), name="Area", energy=10.0, size=0.5, normalize=False)
    add_lamp("SPOT", (0, 0, 2), name="Warm", energy=10.0, use_temperature=True, temperature=3000, exposure=-1)
    lights = {light["name"]: light for light in exported_extras()[0]["lights"]}
    assert np.isclose(lights["Point"]["power"], 10.0 * 4 * math.pi * 0.25 ** 2)
    assert np.isclose(lights["Sun"]["strength"], math.pi * math.sin(0.1) ** 2)
    assert np.isclose(lights["Area"]["power"], 10.0 * 0.25)
    warm = bpy.data.lights["Warm"]
    assert np.isclose(lights["Warm"]["power"], 5.0)
    assert np.allclose(lights["Warm"]["color"], np.array(LAMP_COLOUR) * np.array(warm.temperature_color))


def test_hidden_and_disabled_lamps_are_skipped():
    build_scene()
    add_lamp("POINT", (0, 0, 2), name="Shown")
    add_lamp("POINT", (0, 0, 2), name="Hidden").hide_set(True)
    add_lamp("POINT", (0, 0, 2), name="Viewport Off").hide_viewport = True
    add_lamp("POINT", (0, 0, 2), name="Render Off").hide_render = True
    excluded = bpy.data.collections.new("Excluded")
    bpy.context.scene.collection.children.link(excluded)
    in_excluded = add_lamp("POINT", (0, 0, 2), name="In Excluded")
    bpy.context.scene.collection.objects.unlink(in_excluded)
    excluded.objects.link(in_excluded)
    bpy.context.view_layer.layer_collection.children["Excluded"].exclude = True
    bpy.context.view_layer.update()
    assert [light["name"] for light in exported_extras()[0]["lights"]] == ["Shown"]


def test_world_colour_is_background_times_strength_and_black_is_left_out():
    build_scene()
    assert exported_extras()[0] == {}
    set_world((0.2, 0.3, 0.5), 2.0)
    extras, warnings = exported_extras()
    assert np.allclose(extras["world"]["color"], [0.4, 0.6, 1.0]) and not warnings
    bpy.context.scene.world = None
    assert exported_extras()[0] == {}


def test_textured_world_warns_and_uses_its_unlinked_colour():
    build_scene()
    set_world((0.1, 0.1, 0.1), 1.0)
    tree = bpy.context.scene.world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    tree.links.new(sky.outputs["Color"], tree.nodes["Background"].inputs["Color"])
    extras, warnings = exported_extras()
    assert np.allclose(extras["world"]["color"], [0.1, 0.1, 0.1])
    assert any("world" in line and "driven by" in line for line in warnings)


def test_lamp_or_world_alone_lights_the_exported_scene_and_nothing_is_refused():
    objects = build_scene()
    add_lightmap_uvs(bpy.context, objects, 0.1)
    context = bpy.context
    with pytest.raises(BakeError, match="nothing emits light"):
        check_emitters(export_scene(context.evaluated_depsgraph_get(), objects, [], lamps=[],
                                    world=context.scene.world).scene)
    set_world((0.2, 0.3, 0.5), 1.0)
    scene = export_scene(context.evaluated_depsgraph_get(), objects, [], world=context.scene.world).scene
    assert "world" in scene.extras and "world" in scene.to_dict() and "lights" not in scene.extras
    lamp = add_lamp("POINT", (0, 0, 2))
    scene = export_scene(context.evaluated_depsgraph_get(), objects, [], lamps=[lamp]).scene
    assert [light["name"] for light in scene.to_dict()["lights"]] == ["Point"]


# --- against Cycles -------------------------------------------------------------------------------

def bake_both(objects, samples: int = 32) -> dict:
    """Our bake, then Cycles' Combined bake on the same UVs; per object, the mean RGB of each on the
    texels both cover."""
    support.select_only(objects)
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    ours = {obj.name: support.image_rgba(bpy.data.images[f"{obj.name}_lightmap"]) for obj in objects}
    for obj in objects:
        obj.data[CREATED_UV] = False  # keep the Lightmap UV maps for Cycles
    assert bpy.ops.radiosity.remove_bake() == {"FINISHED"}
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_denoising = False
    cycles.max_bounces = cycles.diffuse_bounces = 64
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    means = {}
    for obj in objects:
        baked = ours[obj.name]
        reference = bake_object(obj, baked.shape[1], baked.shape[0], samples)
        both = (baked[..., 3] > 0.5) & (reference[..., 3] > 0.5)
        assert both.sum() > 0.3 * (baked[..., 3] > 0.5).sum(), f"{obj.name}: coverage differs"
        means[obj.name] = (baked[..., :3][both].mean(axis=0), reference[..., :3][both].mean(axis=0))
    return means


def assert_within_tolerance(means: dict) -> None:
    failures, lines = [], []
    for name, (ours, cycles) in means.items():
        ratio = ours / np.maximum(cycles, 1e-30)
        lines.append(f"{name}: ours {np.round(ours, 4)} cycles {np.round(cycles, 4)} ratio {np.round(ratio, 3)}")
        for channel in range(3):
            if cycles[channel] >= 0.02 * cycles.max() and abs(ratio[channel] - 1) > TOLERANCE:
                failures.append(f"{name} channel {channel}")
    print("\n".join(lines))
    assert cycles_lit(means), "Cycles saw no light: the set-up is wrong"
    assert not failures, f"{', '.join(failures)} off by more than {TOLERANCE:.0%}: " + "; ".join(lines)


def cycles_lit(means: dict) -> bool:
    return all(cycles.max() > 1e-3 for _, cycles in means.values())


def set_up_point():
    add_lamp("POINT", (0.8, -1.2, 2.2), energy=150.0, shadow_soft_size=0.0)


def set_up_spot():
    lamp = add_lamp("SPOT", (0.6, -1.4, 2.6), energy=400.0, shadow_soft_size=0.0,
                    spot_size=math.radians(50), spot_blend=0.3)
    aim(lamp, (0.0, 0.0, 0.5))  # the cone's edge crosses the floor


def set_up_sun():
    lamp = add_lamp("SUN", (0.0, 0.0, 3.0), energy=2.0)
    aim(lamp, (-0.6, 0.8, -2.0))


def set_up_area():
    lamp = add_lamp("AREA", (-0.4, 0.6, 2.0), energy=120.0, shape="RECTANGLE", size=1.0, size_y=0.5)
    aim(lamp, (0.2, -0.3, 0.0))


def set_up_world():
    set_world((0.2, 0.3, 0.5), 1.5)


@pytest.mark.parametrize("method", ["progressive", "hemicube"])
@pytest.mark.parametrize("set_up", [set_up_point, set_up_spot, set_up_sun, set_up_area, set_up_world],
                         ids=["point", "spot", "sun", "area", "world"])
def test_lit_scene_agrees_with_cycles_within_ten_percent_per_object(set_up, method):
    objects = build_scene()
    settings = bpy.context.scene.radiosity
    settings.method = method
    if method == "hemicube":  # receivers as fine as progressive's 4 x 4 elements in 0.5 m patches
        settings.patch_size = 0.125  # (0.5 m patches read the spot's cone edge 11 % low)
    set_up()
    bpy.context.view_layer.update()
    assert_within_tolerance(bake_both(objects))


def test_area_lamp_close_above_an_occluder_keeps_its_penumbra():
    """The lamp is split into pieces with their own visibility maps; shot from its centre alone,
    the floor's penumbra turned into umbra (measured 21 % dark)."""
    objects = build_scene()
    add_lamp("AREA", (0.0, 0.0, 2.0), energy=120.0, shape="RECTANGLE", size=1.0, size_y=0.5)
    assert_within_tolerance(bake_both(objects))
