"""Materials that let light through where a texture says (alpha-cut leaves, chains, fences): which
they are, their opacity as Cycles evaluates it, and the UV map it is read in.

Cycles treats a surface's alpha as transparency: light passes with probability 1 - alpha. A
material lets light through when its surface reaches a Transparent BSDF, or a Principled BSDF
whose Alpha is linked or under 1. Its opacity texture is baked by Cycles itself, on a probe plane
whose UVs span the texture once: the material's copy (the user's is never touched) has every shader
replaced by an Emission of its transparency — a Transparent BSDF emits its colour, a Principled BSDF
1 - Alpha, any other shader nothing — which Mix and Add shaders combine exactly as Cycles combines
the closures, so the Emit pass is the transparency at every texel, whatever nodes make the alpha
(an image's alpha channel, a math node's cut-off, a procedural mask on UVs). The texture is baked
at the size of the largest image in the material (at most OPACITY_SIZE), so a leaf card keeps its
cut-out. The core tests alpha against its cutoff in every visibility pass (core/scene/opacity.py).

Not followed: alpha that depends on anything but the texture UVs (object or generated
coordinates, vertex colours), transparency inside node groups (the group is taken as opaque), and
the light glass and translucent shaders let through (they are opaque here).
"""

from __future__ import annotations

import bpy
import numpy as np

from .tags import original_output_node, uses_nodes

OPACITY_SIZE = 2048  # pixels along a side of a baked opacity texture, at most
PROCEDURAL_SIZE = 256  # for an alpha made without images
TRANSPARENT = "ShaderNodeBsdfTransparent"
PRINCIPLED = "ShaderNodeBsdfPrincipled"
COMBINING = {"ShaderNodeMixShader", "ShaderNodeAddShader", "NodeReroute"}


def _surface_nodes(material) -> list:
    """The nodes the surface of `material`'s output reaches through shader sockets."""
    output = original_output_node(material) if material is not None and material.node_tree is not None else None
    surface = output.inputs.get("Surface") if output is not None else None
    pending = [surface.links[0].from_node] if surface is not None and surface.is_linked else []
    found, seen = [], set()
    while pending:
        node = pending.pop()
        if node.name in seen:
            continue
        seen.add(node.name)
        found.append(node)
        if node.bl_idname in COMBINING:
            pending += [socket.links[0].from_node for socket in node.inputs
                        if socket.is_linked and (socket.type == "SHADER" or node.bl_idname == "NodeReroute")]
    return found


def lets_light_through(material) -> bool:
    """Does Cycles let light pass some of `material`'s surface (module doc)?"""
    if material is None or not uses_nodes(material):
        return False
    for node in _surface_nodes(material):
        if node.mute:
            continue
        if node.bl_idname == TRANSPARENT:
            return True
        if node.bl_idname == PRINCIPLED:
            alpha = node.inputs.get("Alpha")
            if alpha is not None and (alpha.is_linked or alpha.default_value < 1.0):
                return True
    return False


def texture_size(material) -> tuple[int, int]:
    """(width, height) to bake the opacity at: the material's largest image, at most OPACITY_SIZE."""
    sizes = [tuple(node.image.size) for node in material.node_tree.nodes
             if node.bl_idname == "ShaderNodeTexImage" and node.image is not None and min(node.image.size) > 0]
    if not sizes:
        return PROCEDURAL_SIZE, PROCEDURAL_SIZE
    width, height = max(sizes, key=lambda size: size[0] * size[1])
    scale = min(1.0, OPACITY_SIZE / max(width, height))
    return max(1, round(width * scale)), max(1, round(height * scale))


def uv_layer_name(material, mesh) -> str | None:
    """The mesh's UV map the material's textures read: a UV Map node's, else the active render one."""
    named = [node.uv_map for node in material.node_tree.nodes if node.bl_idname == "ShaderNodeUVMap" and node.uv_map]
    for name in named:
        if name in mesh.uv_layers:
            return name
    for layer in mesh.uv_layers:
        if layer.active_render:
            return layer.name
    return mesh.uv_layers[0].name if len(mesh.uv_layers) else None


def _uv_names(material) -> set:
    return {node.uv_map for node in material.node_tree.nodes if node.bl_idname == "ShaderNodeUVMap" and node.uv_map}


def _emitting(tree, node, colour=None, strength: float = 1.0):
    """An Emission node standing where `node` stood: `colour` a socket to link, or RGB."""
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.location = node.location
    emission.inputs["Strength"].default_value = strength
    if hasattr(colour, "node"):
        tree.links.new(colour, emission.inputs["Color"])
    elif colour is not None:
        emission.inputs["Color"].default_value = (*colour, 1.0)
    for link in list(node.outputs[0].links):
        tree.links.new(emission.outputs[0], link.to_socket)
    return emission


def transparency_copy(material):
    """A copy of `material` whose surface emits its transparency (module doc)."""
    copy = material.copy()
    tree = copy.node_tree
    for node in _surface_nodes(copy):
        kind = node.bl_idname
        if kind in COMBINING:
            continue
        if kind == TRANSPARENT:
            colour = node.inputs["Color"]
            _emitting(tree, node, colour.links[0].from_socket if colour.is_linked else tuple(colour.default_value[:3]))
        elif kind == PRINCIPLED and not node.mute:
            alpha = node.inputs["Alpha"]
            if alpha.is_linked:
                clear = tree.nodes.new("ShaderNodeMath")
                clear.operation = "SUBTRACT"
                clear.inputs[0].default_value = 1.0
                tree.links.new(alpha.links[0].from_socket, clear.inputs[1])
                _emitting(tree, node, clear.outputs[0])
            else:
                _emitting(tree, node, (1.0 - alpha.default_value,) * 3)
        else:
            _emitting(tree, node, (0.0, 0.0, 0.0), strength=0.0)
        tree.nodes.remove(node)
    return copy


def bake_opacity(materials) -> dict:
    """{material name: float32 (H, W) alpha, row 0 at v = 0} for `materials` (those that let light
    through), baked by Cycles on probe planes in a scene of their own, all in one bake."""
    from .material_bake import _bake_probes, bake_targets, _pixels, _probe_plane, _probe_scene

    materials = list({material.name: material for material in materials}.values())
    if not materials:
        return {}
    copies = [transparency_copy(material) for material in materials]
    found = {}
    with _probe_scene() as scene:
        probes = [_probe_plane(scene, f"Radiosity opacity probe {k}", copy, float(k)) for k, copy in enumerate(copies)]
        for (obj, mesh), material in zip(probes, materials):
            for name in _uv_names(material) - set(mesh.uv_layers.keys()):
                layer = mesh.uv_layers.new(name=name)
                layer.data.foreach_set("uv", np.array([0, 0, 1, 0, 1, 1, 0, 1], dtype=np.float32))
        objects = [obj for obj, _ in probes]
        images = {obj.name: bpy.data.images.new(f"{obj.name} bake", *texture_size(material), alpha=False,
                                                float_buffer=True) for obj, material in zip(objects, materials)}
        try:
            with bake_targets(objects, images):
                _bake_probes(scene, objects, "EMIT", set())
            for obj, material in zip(objects, materials):
                transparency = _pixels(images[obj.name]).mean(axis=2)
                found[material.name] = np.clip(1.0 - transparency, 0.0, 1.0).astype(np.float32)
        finally:
            for image in images.values():
                bpy.data.images.remove(image)
            for obj, mesh in probes:
                bpy.data.objects.remove(obj)
                bpy.data.meshes.remove(mesh)
            for copy in copies:
                bpy.data.materials.remove(copy)
    return found
