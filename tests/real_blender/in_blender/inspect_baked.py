"""What a baked file holds (`blender -b BAKED.blend --python inspect_baked.py`): per mesh object
its lightmap image (size, packed, mean colour over covered texels) and what its materials show."""

import sys
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # tests/
import rig_lib as rig  # noqa: E402
from blend_inspection import image_rgba, lightmap_wiring  # noqa: E402

objects = {}
for obj in (o for o in bpy.data.objects if o.type == "MESH"):
    image = bpy.data.images.get(f"{obj.name}_lightmap")
    entry = {"shown": sorted({str((lightmap_wiring(s.material) or {}).get("image")) for s in obj.material_slots
                              if s.material}),
             "uv_maps": [uv.name for uv in obj.data.uv_layers]}
    if image is not None:
        rgba = image_rgba(image).reshape(-1, 4)
        covered = rgba[:, 3] > 0
        entry.update(size=list(image.size), packed=image.packed_file is not None, coverage=float(covered.mean()),
                     mean=[float(c) for c in rgba[covered, :3].mean(axis=0)] if covered.any() else None)
    objects[obj.name] = entry
rig.results["blender"] = bpy.app.version_string
rig.results["objects"] = objects
rig.results["last_bake"] = bpy.context.scene.radiosity.last_bake if hasattr(bpy.context.scene, "radiosity") else None
