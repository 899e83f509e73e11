"""The baked Cornell sample agrees with Cycles baking the same, unmodified file (the units match:
docs/architecture.md).

Cycles bakes Combined into the same 'Lightmap' UV maps at the same resolution; both are compared
on the texels both cover. Only the render settings change (more bounces, no clamping: radiosity
has every bounce and no clamp); the file's materials, lamps and backs are baked as they are.
"""

from __future__ import annotations

import blender_support as support
import bpy
import pytest

from bench.cycles import bake_object
from radiosity_addon.blender.tags import CREATED_UV

# per object and channel, relative to Cycles' mean: measured -0.7 ... +2.9 % against Cycles at
# 512 samples x 2 once the gap between the light and the ceiling was resolved (it was +4 ... +11 %);
# `final` by progressive refinement (its floor +2 %; the hemi-cube method's is +5 %: README)
TOLERANCE = 0.05


@pytest.mark.slow
def test_cornell_lightmaps_agree_with_cycles_within_five_percent_per_object():
    support.open_blend(support.CORNELL, method="progressive", quality="final")
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
