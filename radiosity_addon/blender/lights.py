"""Blender lamps and the world colour -> the scene's `extras` ("lights", "world").

The core turns these into shooters of their own (docs/architecture.md, Lamps); here they
are only read out of Blender, in world space:

- point / spot: `position`, `color`, `power` (Watts, `energy` x 2^exposure); spot adds
  `direction` (where the light travels: the lamp's local -Z), `spot_size` (full cone
  angle, radians) and `spot_blend`;
- sun: `direction`, `color`, `strength` (W/m^2);
- area: the 4 world-space corners of its rectangle, counter-clockwise seen from the
  emitting (-Z) side, `color`, `power`; a disk or ellipse becomes the rectangle of
  equal area;
- world: `color` = Background colour x Strength, left out when black.

Exposure (x 2^exposure), a blackbody temperature (x its colour) and Normalize off (x the
lamp's area: 4 pi r^2 for a point or spot of radius r, the rectangle's area, pi sin^2(angle/2)
for a sun) are converted as Cycles 5.0 applies them (measured with a bake of a plane).
What the bake cannot follow (lamp node trees, a narrowed area spread, square spots,
a textured sky, ...) is converted as closely as it can be and named in a warning.
"""

from __future__ import annotations

import math

import bpy
import numpy as np

from .materials import try_image_average

EQUAL_AREA = math.sqrt(math.pi) / 2  # a disk of diameter d has the area of a square of side d * this


def render_lamps(view_layer) -> list:
    """The lamps that light a render of this view layer: visible and not disabled in renders."""
    return [obj for obj in view_layer.objects
            if obj.type == "LIGHT" and obj.visible_get(view_layer=view_layer) and not obj.hide_render]


def as_list(values) -> list[float]:
    return [float(v) for v in values]


class LightReader:
    def __init__(self):
        self.warnings: list[str] = []

    def warn(self, obj, text: str) -> None:
        line = f"lamp '{obj.name}': {text}"
        if line not in self.warnings:
            self.warnings.append(line)

    def lights(self, depsgraph, lamps) -> list[dict]:
        result = []
        for obj in lamps:
            entry = self.light(obj, obj.evaluated_get(depsgraph) if depsgraph is not None else obj)
            if entry is not None:
                result.append(entry)
        return result

    def light(self, obj, obj_eval) -> dict | None:
        light = obj_eval.data
        if not getattr(obj, "visible_diffuse", True):
            self.warn(obj, "not visible to diffuse rays (Object > Visibility); skipped")
            return None
        if getattr(light, "use_nodes", False) and light.node_tree is not None:
            self.warn(obj, "its node tree is ignored; baked with its colour and power")
        if not getattr(light, "use_shadow", True):
            self.warn(obj, "casts no shadows in Cycles but does in the bake")
        color = np.array(light.color[:3], dtype=np.float64)
        if getattr(light, "use_temperature", False):
            color = color * np.array(light.temperature_color[:3], dtype=np.float64)
        energy = float(light.energy) * 2.0 ** float(getattr(light, "exposure", 0.0))
        matrix = np.array(obj_eval.matrix_world, dtype=np.float64)
        if not np.all(np.isfinite(matrix)):
            self.warn(obj, "its transform is not finite; skipped")
            return None
        axes, origin = matrix[:3, :3], matrix[:3, 3]
        direction = -axes[:, 2]
        if np.linalg.norm(direction) < 1e-12:
            self.warn(obj, "its transform is degenerate (zero scale); skipped")
            return None
        direction = direction / np.linalg.norm(direction)
        entry = {"name": obj.name, "type": light.type.lower(), "color": as_list(color)}
        if light.type in ("POINT", "SPOT"):
            if not getattr(light, "normalize", True) and light.shadow_soft_size > 0:
                energy *= 4 * math.pi * light.shadow_soft_size ** 2  # Cycles: power per sphere area
            entry.update(position=as_list(origin), power=energy)
            if light.type == "SPOT":
                if light.use_square:
                    self.warn(obj, "a square spot is baked as a round cone")
                scale = np.linalg.norm(axes[:, :2], axis=0)
                if not np.isclose(scale[0], scale[1], rtol=1e-3):
                    self.warn(obj, "its scale makes the cone elliptic; baked as a round cone")
                entry.update(direction=as_list(direction), spot_size=float(light.spot_size),
                             spot_blend=float(light.spot_blend))
        elif light.type == "SUN":
            if not getattr(light, "normalize", True) and light.angle > 0:
                energy *= math.pi * math.sin(light.angle / 2) ** 2  # Cycles: strength per disk of the sky
            entry.update(direction=as_list(direction), strength=energy, angle=float(light.angle))
        elif light.type == "AREA":
            corners = self.area_corners(obj, light, matrix)
            if corners is None:
                return None
            if not getattr(light, "normalize", True):
                edge_u, edge_v = corners[1] - corners[0], corners[3] - corners[0]
                energy *= float(np.linalg.norm(np.cross(edge_u, edge_v)))  # Cycles: power per unit area
            if getattr(light, "spread", math.pi) < math.pi - 1e-4:
                self.warn(obj, "its spread is narrower than 180 degrees; baked as a fully diffuse emitter")
            entry.update(vertices=[as_list(c) for c in corners], power=energy)
        else:
            self.warn(obj, f"lamp type {light.type} is not supported; skipped")
            return None
        return entry

    def area_corners(self, obj, light, matrix) -> np.ndarray | None:
        width = float(light.size)
        height = float(light.size_y) if light.shape in ("RECTANGLE", "ELLIPSE") else width
        if light.shape in ("DISK", "ELLIPSE"):
            width, height = width * EQUAL_AREA, height * EQUAL_AREA
        x, y = width / 2, height / 2
        # counter-clockwise seen from -Z: (v1 - v0) x (v2 - v0) points along -Z
        local = np.array([[-x, -y, 0.0], [-x, y, 0.0], [x, y, 0.0], [x, -y, 0.0]])
        corners = local @ matrix[:3, :3].T + matrix[:3, 3]
        normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
        if np.linalg.norm(normal) <= 1e-12 * max(1.0, float(np.ptp(corners, axis=0).max())) ** 2:
            self.warn(obj, "its rectangle has no area; skipped")
            return None
        if np.dot(normal, -matrix[:3, 2]) < 0:  # a mirroring transform: keep the front on the lit side
            corners = corners[::-1]
        return corners


def world_colour(world, warnings: list[str]) -> list[float] | None:
    """Background colour x Strength of a plain world; None when black or absent."""
    if world is None:
        return None
    visibility = getattr(world, "cycles_visibility", None)
    if visibility is not None and not getattr(visibility, "diffuse", True):
        warnings.append(f"world '{world.name}': not visible to diffuse rays; not baked")
        return None
    tree = world.node_tree
    if tree is None or (bpy.app.version < (5, 0, 0) and not world.use_nodes):  # 5.x worlds always use nodes
        colour = np.array(world.color[:3], dtype=np.float64)
    else:
        colour = _world_nodes(world, tree, warnings)
    if colour is None or not np.all(np.isfinite(colour)) or not np.any(colour > 0):
        return None
    return as_list(np.clip(colour, 0.0, None))


def _world_nodes(world, tree, warnings):
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    output = (next((n for n in outputs if n.is_active_output and n.target in ("ALL", "CYCLES")), None)
              or next((n for n in outputs if n.is_active_output), None)
              or (outputs[0] if outputs else None))
    if output is None or not output.inputs["Surface"].is_linked:
        return None
    node = output.inputs["Surface"].links[0].from_node
    while node.bl_idname == "NodeReroute" and node.inputs[0].is_linked:
        node = node.inputs[0].links[0].from_node
    if node.bl_idname != "ShaderNodeBackground":
        warnings.append(f"world '{world.name}': shader '{node.name}' is not a Background; the sky is not baked")
        return None
    colour_socket, strength_socket = node.inputs["Color"], node.inputs["Strength"]
    colour = np.array(colour_socket.default_value[:3], dtype=np.float64)
    if colour_socket.is_linked:
        source = colour_socket.links[0].from_node
        average = None
        if source.bl_idname in ("ShaderNodeTexEnvironment", "ShaderNodeTexImage") and source.image is not None:
            average = try_image_average(source.image)
        if average is not None:
            colour = np.asarray(average, dtype=np.float64)[:3]
            warnings.append(f"world '{world.name}': texture '{source.image.name}' baked as a uniform sky"
                            " of its average colour")
        else:
            warnings.append(f"world '{world.name}': the Background colour is driven by '{source.name}';"
                            " baked as a uniform sky of its unlinked colour")
    if strength_socket.is_linked:
        warnings.append(f"world '{world.name}': the Background strength is driven by a node;"
                        " baked with its unlinked value")
    return colour * float(strength_socket.default_value)


def export_lights(depsgraph, lamps, world) -> tuple[dict, list[str]]:
    """The scene extras for `lamps` (light objects) and `world`, and the warnings on what was simplified."""
    reader = LightReader()
    extras = {}
    lights = reader.lights(depsgraph, lamps)
    if lights:
        extras["lights"] = lights
    warnings = list(reader.warnings)
    colour = world_colour(world, warnings)
    if colour is not None:
        extras["world"] = {"color": colour}
    return extras, warnings
