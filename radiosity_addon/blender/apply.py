"""Write-back: one float image per object, shown through its materials; and the way back.

Images are first made under temporary names and written (packed or EXR); only
when all of them succeeded do they replace the previous lightmaps, so a failure
leaves the .blend as it was. The shading switch adds tagged nodes and makes
their Material Output the active one: the user's nodes and links stay as they
were, and `remove_bake` deletes ours and re-activates the original output.
A material that other objects also use is copied for the baked object (an
Image Texture node can show only one object's lightmap).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import bpy
import numpy as np

from .errors import BakeError
from .materials import MaterialReader
from .shader_graph import Nodes, surface_shader, walk
from .tags import (ADDED_SLOT, COPY_OF, CREATED_UV, ENABLED_NODES, LIGHTMAP_UV, NODE_TAG, ORIGINAL_OUTPUT,
                   ORIGINAL_SLOTS, is_ours, lightmap_image_name, original_output_node, uses_nodes)

PENDING_SUFFIX = ".radiosity-pending"
NODE_NAMES = {
    "uv": "Radiosity Lightmap UV",
    "image": "Radiosity Lightmap",
    "emission": "Radiosity Lightmap Emission",
    "output": "Radiosity Lightmap Output",
}


# ---------------------------------------------------------------- images

def _new_image(name: str, rgba: np.ndarray):
    height, width = rgba.shape[:2]
    image = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
    # coverage lives in alpha; the colour must not be divided or multiplied by it
    image.alpha_mode = "CHANNEL_PACKED"
    image.pixels.foreach_set(np.ascontiguousarray(rgba, dtype=np.float32).ravel())
    image.file_format = "OPEN_EXR"
    image.use_half_precision = False
    return image


def _save_exr(image, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    image.filepath_raw = str(path)
    image.save()
    image.source = "FILE"
    if bpy.data.filepath:
        try:
            image.filepath = bpy.path.relpath(str(path))
        except ValueError:  # another drive on Windows: keep it absolute
            pass


def file_name(name: str) -> str:
    """An object name as a file name on every platform (Blender allows '/', ':' and more in names)."""
    cleaned = re.sub(r'[<>:"/\\|?*\x00-\x1f]', "_", name).strip(" .")
    return cleaned or "unnamed"


def write_images(images: dict, output: str, directory: Path | None) -> dict:
    """Make and store every lightmap; on success replace the old images and return name -> image.
    output: 'PACK' or 'EXR' (into `directory`)."""
    made = {}
    try:
        for object_name, rgba in images.items():
            final_name = lightmap_image_name(object_name)
            image = _new_image(final_name + PENDING_SUFFIX, rgba)
            made[object_name] = image
            if output == "EXR":
                _save_exr(image, Path(directory) / f"{file_name(final_name)}.exr")
            else:
                image.pack()
    except (RuntimeError, OSError) as error:
        for image in made.values():
            bpy.data.images.remove(image)
        raise BakeError(f"cannot write the lightmaps: {str(error).strip().splitlines()[-1]}") from None
    for object_name, image in made.items():
        final_name = lightmap_image_name(object_name)
        old = bpy.data.images.get(final_name)
        if old is not None:
            old.user_remap(image)
            bpy.data.images.remove(old)
        image.name = final_name
    return made


# ---------------------------------------------------------------- materials

def _users_elsewhere(material, obj) -> bool:
    """True if any object other than `obj` shows this material."""
    for other in bpy.data.objects:
        if other is obj or other.type not in {"MESH", "CURVE", "SURFACE", "FONT", "META"}:
            continue
        if any(slot.material is material for slot in other.material_slots):
            return True
    return False


def _remember_slots(obj) -> None:
    if ORIGINAL_SLOTS not in obj:
        obj[ORIGINAL_SLOTS] = [[slot.link, slot.material.name if slot.material else ""]
                               for slot in obj.material_slots]


def _own_materials(obj) -> list:
    """The object's materials, each used by this object alone (copies made where needed)."""
    if len(obj.material_slots) == 0:
        _remember_slots(obj)
        obj.data.materials.append(None)
        obj[ADDED_SLOT] = True
    materials = []
    copies = {}  # shared material -> this object's copy (two slots may show the same material)
    for slot in obj.material_slots:
        material = slot.material
        if material is not None and material.name in copies:
            slot.link = "OBJECT"
            slot.material = material = copies[material.name]
        elif material is None:
            _remember_slots(obj)
            material = bpy.data.materials.new(f"{obj.name} lightmap")
            material[COPY_OF] = ""
            slot.link = "OBJECT"
            slot.material = material
        elif _users_elsewhere(material, obj):
            _remember_slots(obj)
            copy = material.copy()
            copy.name = f"{material.name} ({obj.name} lightmap)"
            copy[COPY_OF] = material.name
            copies[material.name] = copy
            slot.link = "OBJECT"
            slot.material = copy
            material = copy
        if material not in materials:
            materials.append(material)
    return materials


def _tagged(tree, role: str, kind: str, location):
    node = tree.nodes.get(NODE_NAMES[role])
    if node is None or not is_ours(node):
        node = tree.nodes.new(kind)
        node.name = node.label = NODE_NAMES[role]
        node[NODE_TAG] = 1
    node.location = location
    return node


def _shown_colour(material, tree, texture, make, content: str, diffuse_factors: dict, reader):
    """The socket or constant the baked material emits: the lightmap itself ("combined"), or its
    emission + albedo x lightmap ("light"), albedo and emission from the material's own nodes."""
    lightmap = texture.outputs["Color"]
    if content == "combined":
        return lightmap
    fallback = reader.colours(material)
    algebra = Nodes(tree, make, diffuse_factors.get(material.name, {}), fallback)
    shader = None
    if uses_nodes(material) and not material.get(ENABLED_NODES):  # a 4.x material without nodes: its colour
        shader = surface_shader(original_output_node(material))
    albedo, emission = walk(shader, algebra) if shader is not None else fallback
    return algebra.add(emission, algebra.scale(lightmap, albedo))


def wire_material(material, image, content: str = "combined", diffuse_factors: dict | None = None,
                  reader: MaterialReader | None = None) -> None:
    """Show `image` (on the Lightmap UV map, linear filtering) as the material's surface: as the
    outgoing radiance it holds ("combined"), or as the light arriving ("light"), lit by it."""
    if not uses_nodes(material):  # Blender 4.x material shown without nodes: remember to switch back
        material[ENABLED_NODES] = True
        material.use_nodes = True
    tree = material.node_tree
    if ORIGINAL_OUTPUT not in material:
        active = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"
                       and n.is_active_output and not is_ours(n)), None)
        material[ORIGINAL_OUTPUT] = active.name if active else ""
    for node in [n for n in tree.nodes if is_ours(n) and n.name not in NODE_NAMES.values()]:
        tree.nodes.remove(node)  # the arithmetic of an earlier bake
    right = max((n.location.x for n in tree.nodes if not is_ours(n)), default=0.0)
    x, y = right + 300.0, 600.0
    uv = _tagged(tree, "uv", "ShaderNodeUVMap", (x, y))
    uv.uv_map = LIGHTMAP_UV
    texture = _tagged(tree, "image", "ShaderNodeTexImage", (x + 200, y))
    texture.image = image
    texture.interpolation = "Linear"
    texture.extension = "EXTEND"
    made = []

    def make(kind):
        node = tree.nodes.new(kind)
        node[NODE_TAG] = 1
        node.location = (x + 300 + 60 * len(made), y - 300 - 40 * len(made))
        made.append(node)
        return node

    colour = _shown_colour(material, tree, texture, make, content, diffuse_factors or {}, reader or MaterialReader())
    emission = _tagged(tree, "emission", "ShaderNodeEmission", (x + 500 + 60 * len(made), y))
    emission.inputs["Strength"].default_value = 1.0
    output = _tagged(tree, "output", "ShaderNodeOutputMaterial", (x + 700 + 60 * len(made), y))
    output.target = "ALL"
    tree.links.new(uv.outputs["UV"], texture.inputs["Vector"])
    if hasattr(colour, "node"):
        tree.links.new(colour, emission.inputs["Color"])
    else:
        emission.inputs["Color"].default_value = (*np.clip(colour, 0, None), 1.0)
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    output.is_active_output = True


def show_lightmaps(objects, images: dict, content: str = "combined", diffuse_factors: dict | None = None) -> None:
    reader = MaterialReader()
    for obj in objects:
        for material in _own_materials(obj):
            wire_material(material, images[obj.name], content, diffuse_factors, reader)


# ---------------------------------------------------------------- the way back

def unwire_material(material) -> None:
    tree = material.node_tree
    if tree is None:
        return
    for node in [n for n in tree.nodes if is_ours(n)]:
        tree.nodes.remove(node)
    original = material.get(ORIGINAL_OUTPUT)
    if original:
        node = tree.nodes.get(original)
        if node is not None:
            node.is_active_output = True
    if ORIGINAL_OUTPUT in material:
        del material[ORIGINAL_OUTPUT]
    if material.get(ENABLED_NODES):
        material.use_nodes = False
        del material[ENABLED_NODES]


def remove_bake(obj, shading_only: bool = False) -> bool:
    """Restore the object's original shading, delete its lightmap image and the UV map the bake made
    (`shading_only`: keep those two; a cancelled bake takes back its live preview so).
    Returns False if the object had no bake."""
    had_bake = False
    for slot in obj.material_slots:
        if slot.material is not None and slot.material.get(ORIGINAL_OUTPUT) is not None:
            had_bake = True
            unwire_material(slot.material)
    if ORIGINAL_SLOTS in obj:
        had_bake = True
        originals = list(obj[ORIGINAL_SLOTS])
        copies = sorted({slot.material.name for slot in obj.material_slots
                         if slot.material is not None and COPY_OF in slot.material})
        for slot, (link, name) in zip(obj.material_slots, originals):
            slot.link = "OBJECT"
            slot.material = None
            slot.link = link
            if link == "OBJECT":
                slot.material = bpy.data.materials.get(name) if name else None
        if obj.get(ADDED_SLOT):
            obj.data.materials.pop(index=len(obj.data.materials) - 1)
        for name in copies:
            copy = bpy.data.materials.get(name)
            if copy is not None and copy.users == 0:
                bpy.data.materials.remove(copy)
        for key in (ORIGINAL_SLOTS, ADDED_SLOT):
            if key in obj:
                del obj[key]
    if shading_only:
        return had_bake
    image = bpy.data.images.get(lightmap_image_name(obj.name))
    if image is not None:
        had_bake = True
        bpy.data.images.remove(image)
    mesh = obj.data
    if mesh is not None and mesh.get(CREATED_UV):
        from .lightmap_uv import remove_lightmap_uvs

        remove_lightmap_uvs([mesh])
    return had_bake


def default_exr_directory() -> Path | None:
    return Path(bpy.path.abspath("//")) if bpy.data.filepath else None


def check_output(output: str, directory) -> None:
    """Refuse before the solve, not after it: EXR output needs somewhere to write."""
    if output == "EXR" and directory is None:
        raise BakeError("save the .blend first (EXR lightmaps are written next to it), or choose Pack")
    if output == "EXR" and Path(directory).exists() and not os.access(directory, os.W_OK):
        raise BakeError(f"cannot write EXR lightmaps into '{directory}' (no permission)")
