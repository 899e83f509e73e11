"""Reading a bake back out of Blender's data, with no side effects: shared by the bpy-module tests
(through blender_support) and the scripts that run inside a real Blender (tests/real_blender/)."""

from __future__ import annotations

import numpy as np


def image_rgba(image) -> np.ndarray:
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(height, width, 4)


def upstream(socket):
    """Every node feeding `socket`, depth first."""
    seen, stack = [], [link.from_node for link in socket.links]
    while stack:
        node = stack.pop()
        if node not in seen:
            seen.append(node)
            stack += [link.from_node for socket in node.inputs for link in socket.links]
    return seen


def lightmap_wiring(material) -> dict | None:
    """What the active Material Output shows: None unless it is the add-on's lightmap chain (an
    Emission shader fed by the lightmap image on the Lightmap UV map, through arithmetic for a
    "light" lightmap)."""
    tree = material.node_tree
    output = next((n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial" and n.is_active_output), None)
    if output is None or not output.inputs["Surface"].is_linked:
        return None
    emission = output.inputs["Surface"].links[0].from_node
    if emission.bl_idname != "ShaderNodeEmission" or not emission.inputs["Color"].is_linked:
        return None
    texture = next((n for n in upstream(emission.inputs["Color"]) if n.bl_idname == "ShaderNodeTexImage"
                    and n.get("radiosity_baker")), None)
    if texture is None or not texture.inputs["Vector"].is_linked:
        return None
    uv = texture.inputs["Vector"].links[0].from_node
    if uv.bl_idname != "ShaderNodeUVMap":
        return None
    return {"image": texture.image.name if texture.image else None, "interpolation": texture.interpolation,
            "uv_map": uv.uv_map}
