"""Marks the add-on leaves in the .blend, so re-bakes replace and restore undoes.

Every node the bake adds carries the custom property NODE_TAG; a material whose
active output was switched remembers the original output's name; an object whose
material slots were redirected to per-object copies remembers the originals.
"""

from __future__ import annotations

NODE_TAG = "radiosity_baker"
ORIGINAL_OUTPUT = "radiosity_baker_original_output"  # material: name of the output active before the bake
ORIGINAL_SLOTS = "radiosity_baker_original_slots"  # object: [[link, material name], ...] per slot
ADDED_SLOT = "radiosity_baker_added_slot"  # object: the bake appended an empty slot to its mesh
COPY_OF = "radiosity_baker_copy_of"  # material: made by the bake for one object from this material
CREATED_UV = "radiosity_baker_created_uv"  # mesh: the bake made its 'Lightmap' UV map
ENABLED_NODES = "radiosity_baker_enabled_nodes"  # material: the bake switched on use_nodes (Blender 4.x)
LIGHTMAP_UV = "Lightmap"
IMAGE_SUFFIX = "_lightmap"


def lightmap_image_name(object_name: str) -> str:
    return f"{object_name}{IMAGE_SUFFIX}"


def is_ours(node) -> bool:
    return bool(node.get(NODE_TAG))


def uses_nodes(material) -> bool:
    """Blender 4.x materials may render without their node tree; from 5.0 every material uses nodes
    (and reading `use_nodes` only warns that it is deprecated)."""
    import bpy

    return material.node_tree is not None and (bpy.app.version >= (5, 0, 0) or material.use_nodes)


def original_output_node(material):
    """The Material Output the user's shading goes through, even while the baked output is active."""
    tree = material.node_tree
    if tree is None:
        return None
    recorded = material.get(ORIGINAL_OUTPUT)
    if recorded is not None:
        return tree.nodes.get(recorded)
    for target in ("EEVEE", "ALL"):
        node = tree.get_output_node(target)
        if node is not None and not is_ours(node):
            return node
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and not is_ours(n)]
    return outputs[0] if outputs else None
