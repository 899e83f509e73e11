"""Shared set-up of the tests that drive the add-on through the `bpy` module.

Import this before bpy: it points Blender's user directory at a temporary one so
the tests never read or write the developer's Blender configuration.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="radiosity-blender-user-")

import bpy  # noqa: E402

from blend_inspection import image_rgba, lightmap_wiring  # noqa: E402,F401  (the tests use them from here)

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "sample_blends"
CORNELL = SAMPLES / "cornell_box.blend"
ROOM = SAMPLES / "room.blend"
SAMPLES_MADE = SAMPLES / ".made"  # `make samples` and ensure_samples() touch it
SAMPLE_SOURCES = (ROOT / "tools/make_sample_blends.py", ROOT / "bench/blend_scenes.py",
                  ROOT / "bench/shapes.py")


def ensure_samples() -> None:
    """sample_blends/ is made on demand (each Blender opens the files it made; 4.x cannot open 5.x
    files): made here when missing or older than their generator."""
    made = SAMPLES_MADE.stat().st_mtime if SAMPLES_MADE.exists() else 0.0
    if made > max(source.stat().st_mtime for source in SAMPLE_SOURCES):
        return
    result = subprocess.run([sys.executable, str(SAMPLE_SOURCES[0])], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    SAMPLES_MADE.touch()


ensure_samples()


def ensure_addon() -> None:
    """Register the add-on from the source tree (once per process)."""
    if not hasattr(bpy.types, "RADIOSITY_OT_bake"):
        from radiosity_addon import blender

        blender.register()


def open_blend(path: Path, method: str = "hemicube", subdivision: int = 2, content: str = "combined",
               quality: str = "CUSTOM"):
    """Open a file and choose quick solver settings, or a quality preset (and what the lightmaps
    hold: these tests read B off them unless they ask for the light); returns bpy.context."""
    ensure_addon()
    bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    settings = bpy.context.scene.radiosity
    settings.content = content
    settings.quality = quality
    settings.method = method
    settings.patch_mode = "SUBDIVISION"
    settings.subdivision = subdivision
    settings.hemicube_resolution = 32
    settings.texel_density = 32.0
    return bpy.context


def select_only(objects) -> None:
    bpy.context.view_layer.update()  # objects linked just now join the view layer on update
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj in objects)
    if objects:
        bpy.context.view_layer.objects.active = objects[0]


def node_tree_state(tree) -> dict:
    if tree is None:
        return {}
    nodes = {}
    for node in tree.nodes:
        inputs = {}
        for socket in node.inputs:
            value = getattr(socket, "default_value", None)
            if value is not None and not isinstance(value, (str, bpy.types.ID)):
                value = tuple(value) if hasattr(value, "__len__") else value
            inputs[socket.identifier] = value if not isinstance(value, bpy.types.ID) else value.name
        nodes[node.name] = {
            "type": node.bl_idname,
            "location": tuple(round(c, 3) for c in node.location),
            "active_output": getattr(node, "is_active_output", None),
            "target": getattr(node, "target", None),
            "image": node.image.name if getattr(node, "image", None) else None,
            "inputs": inputs,
            "properties": sorted(node.keys()),
        }
    links = sorted((link.from_node.name, link.from_socket.identifier, link.to_node.name, link.to_socket.identifier)
                   for link in tree.links)
    return {"nodes": nodes, "links": links}


def blend_state() -> dict:
    """Everything a bake may touch, as plain data: equal states mean an unchanged file."""
    return {
        "scenes": sorted(scene.name for scene in bpy.data.scenes),
        "images": sorted(image.name for image in bpy.data.images),
        "materials": {m.name: {"tree": node_tree_state(m.node_tree), "properties": sorted(m.keys())}
                      for m in bpy.data.materials},
        "meshes": {mesh.name: {"uv": [(uv.name, uv.active, uv.active_render) for uv in mesh.uv_layers],
                               "materials": [m.name if m else None for m in mesh.materials],
                               "properties": sorted(mesh.keys()),
                               "polygons": len(mesh.polygons)}
                   for mesh in bpy.data.meshes},
        "objects": {obj.name: {"slots": [(s.link, s.material.name if s.material else None)
                                         for s in obj.material_slots],
                               "properties": sorted(k for k in obj.keys() if k != "radiosity"),
                               "selected": obj.select_get()}
                    for obj in bpy.data.objects},
    }


def gone_within(condition, seconds: float) -> bool:
    """Whether `condition()` holds within `seconds` (a finished bake's solver process is reaped and
    its folder removed on a thread: `BakeWorker.discard(wait=False)`)."""
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def inject_into_solver(monkeypatch, code: str) -> None:
    """Run `code` in the solver process before its main: how the tests give it faults (it is a
    process of its own, so patching this one changes nothing there)."""
    from radiosity_addon.blender import worker

    main = "from radiosity_addon.solver_process.child import main"
    assert main in worker.BOOTSTRAP
    monkeypatch.setattr(worker, "BOOTSTRAP", worker.BOOTSTRAP.replace(main, f"exec({code!r}); {main}"))
