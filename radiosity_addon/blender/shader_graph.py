"""A material's diffuse albedo and emission read off its shader graph, in one walk for two uses:

- `Values`: numbers (averages of textures, unlinked values) for geometry whose materials cannot be
  baked (instances, occluders without a 'Lightmap' UV map): `materials.MaterialReader`;
- `Nodes`: node sockets built into the material itself, so the baked look of a "light" lightmap
  is emission + albedo x lightmap with the material's own textures at full resolution.

The walk follows the surface from the Material Output through Mix and Add shaders and reroutes
to Principled BSDFs (albedo: Base Color x its diffuse factor; emission: Emission Color x
Strength), Diffuse BSDFs (Color) and Emission shaders (Color x Strength). Anything else is
`algebra.unknown(node)`.
"""

from __future__ import annotations

import numpy as np

MAX_DEPTH = 16


def walk(node, algebra, depth: int = 0):
    """(albedo, emission) of the shader `node` in the algebra's values."""
    kind = node.bl_idname if node is not None else None
    if node is None or depth > MAX_DEPTH:
        return algebra.unknown(node)
    if kind == "ShaderNodeBsdfPrincipled":
        albedo = algebra.scale(algebra.colour(node.inputs["Base Color"]), algebra.diffuse_factor(node))
        emission = algebra.scale(algebra.colour(node.inputs["Emission Color"]),
                                 algebra.scalar(node.inputs["Emission Strength"]))
        return albedo, emission
    if kind == "ShaderNodeBsdfDiffuse":
        return algebra.colour(node.inputs["Color"]), algebra.constant(np.zeros(3))
    if kind == "ShaderNodeEmission":
        return algebra.constant(np.zeros(3)), algebra.scale(algebra.colour(node.inputs["Color"]),
                                                            algebra.scalar(node.inputs["Strength"]))
    if kind in ("ShaderNodeAddShader", "ShaderNodeMixShader"):
        shaders = [socket for socket in node.inputs if socket.type == "SHADER"]
        parts = [walk(s.links[0].from_node, algebra, depth + 1) if s.is_linked
                 else (algebra.constant(np.zeros(3)), algebra.constant(np.zeros(3))) for s in shaders]
        if kind == "ShaderNodeAddShader":
            return algebra.add(parts[0][0], parts[1][0]), algebra.add(parts[0][1], parts[1][1])
        fac = algebra.scalar(node.inputs["Fac"])
        return algebra.mix(fac, parts[0][0], parts[1][0]), algebra.mix(fac, parts[0][1], parts[1][1])
    if kind == "NodeReroute" and node.inputs[0].is_linked:
        return walk(node.inputs[0].links[0].from_node, algebra, depth + 1)
    return algebra.unknown(node)


def surface_shader(output):
    """The shader node feeding a Material Output's Surface, or None."""
    surface = output.inputs.get("Surface") if output is not None else None
    return surface.links[0].from_node if surface is not None and surface.is_linked else None


class Nodes:
    """Values are output sockets or constants (numpy RGB / float) in the material's node tree;
    every node made is tagged by `make(kind)`, so removing the bake removes them."""

    def __init__(self, tree, make, diffuse_factors: dict, fallback):
        self.tree, self.make = tree, make
        self.diffuse_factors = diffuse_factors  # Principled node name -> RGB factor (baked by Cycles)
        self.fallback = fallback  # (albedo, emission) constants for shaders the walk cannot read

    def constant(self, rgb):
        return np.asarray(rgb, dtype=np.float64)

    def colour(self, socket):
        if socket.is_linked:
            return socket.links[0].from_socket
        return np.array(socket.default_value[:3], dtype=np.float64)

    def scalar(self, socket):
        return socket.links[0].from_socket if socket.is_linked else float(socket.default_value)

    def diffuse_factor(self, node):
        return np.asarray(self.diffuse_factors.get(node.name, np.ones(3)), dtype=np.float64)

    def unknown(self, node):
        return tuple(np.asarray(v, dtype=np.float64) for v in self.fallback)

    def _math(self, operation, a, b):
        if not hasattr(a, "node") and not hasattr(b, "node"):  # both constant
            values = {"MULTIPLY": a * b, "ADD": a + b, "SUBTRACT": a - b}[operation]
            return np.broadcast_to(values, (3,)).astype(np.float64)
        node = self.make("ShaderNodeVectorMath")
        node.operation = operation
        for socket, value in zip(node.inputs[:2], (a, b)):
            if hasattr(value, "node"):
                self.tree.links.new(value, socket)
            else:
                socket.default_value = tuple(np.broadcast_to(value, (3,)))
        return node.outputs["Vector"]

    def scale(self, colour, factor):
        return self._math("MULTIPLY", colour, factor)

    def add(self, a, b):
        return self._math("ADD", a, b)

    def mix(self, fac, a, b):
        return self.add(a, self.scale(self._math("SUBTRACT", b, a), fac))
