"""The baked Cornell sample agrees with Cycles baking the same file (docs/architecture.md: the units match).

Cycles bakes Combined into the same 'Lightmap' UV maps at the same resolution; both
are compared on the texels both cover. Two differences of Cycles are switched off
for the comparison: surfaces emit from their back too (the light gets a
front-only emission here), and bounces and clamping are limited by default.
"""

from __future__ import annotations

import blender_support as support
import bpy

from radiosity_addon.bench.cycles import bake_object
from radiosity_addon.blender.tags import CREATED_UV

TOLERANCE = 0.10  # per object and channel, relative to Cycles' mean


def front_only_emission(material) -> None:
    tree = material.node_tree
    principled = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    front = tree.nodes.new("ShaderNodeMath")
    front.operation = "SUBTRACT"
    front.inputs[0].default_value = 1.0
    tree.links.new(geometry.outputs["Backfacing"], front.inputs[1])
    strength = tree.nodes.new("ShaderNodeMath")
    strength.operation = "MULTIPLY"
    strength.inputs[0].default_value = principled.inputs["Emission Strength"].default_value
    tree.links.new(front.outputs[0], strength.inputs[1])
    tree.links.new(strength.outputs[0], principled.inputs["Emission Strength"])


def test_cornell_lightmaps_agree_with_cycles_within_ten_percent_per_object():
    support.open_blend(support.CORNELL, method="progressive", subdivision=4)
    objects = [obj for obj in bpy.context.scene.objects if obj.type == "MESH"]
    assert bpy.ops.radiosity.bake() == {"FINISHED"}
    ours = {obj.name: support.image_rgba(bpy.data.images[f"{obj.name}_lightmap"]) for obj in objects}

    # back to the original shading, keeping the Lightmap UV maps for Cycles
    for obj in objects:
        obj.data[CREATED_UV] = False
    assert bpy.ops.radiosity.remove_bake() == {"FINISHED"}
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = 64
    cycles.use_denoising = False
    cycles.max_bounces = cycles.diffuse_bounces = 64  # radiosity has every bounce
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    front_only_emission(bpy.data.objects["light"].material_slots[0].material)

    failures = []
    for obj in objects:
        baked = ours[obj.name]
        reference = bake_object(obj, baked.shape[1], baked.shape[0], cycles.samples)
        both = (baked[..., 3] > 0.5) & (reference[..., 3] > 0.5)
        assert both.sum() > 0.3 * (baked[..., 3] > 0.5).sum(), f"{obj.name}: coverage differs"
        mean_ours = baked[..., :3][both].mean(axis=0)
        mean_cycles = reference[..., :3][both].mean(axis=0)
        for channel in range(3):
            if mean_cycles[channel] < 0.02 * mean_cycles.max():
                continue  # e.g. blue on the red wall: too dark to compare relatively
            ratio = mean_ours[channel] / mean_cycles[channel]
            if abs(ratio - 1) > TOLERANCE:
                failures.append(f"{obj.name} channel {channel}: ours {mean_ours[channel]:.4f}"
                                f" cycles {mean_cycles[channel]:.4f} ratio {ratio:.3f}")
    assert not failures, "; ".join(failures)
