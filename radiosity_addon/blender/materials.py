"""Blender materials -> (reflectance, emission) in the core's units.

Principled BSDF: Base Color -> reflectance, Emission Color x Strength -> emission
(docs/architecture.md, Units). Diffuse BSDF and Emission shaders map the same way; Add
and Mix shaders combine their inputs. A texture on a colour input is replaced
by its average colour, anything else by a grey default: both with a warning,
since the bake then cannot match what the user sees.
"""

from __future__ import annotations

import numpy as np

from .tags import ENABLED_NODES, original_output_node, uses_nodes

DEFAULT_REFLECTANCE = np.array([0.8, 0.8, 0.8])  # Blender's default surface colour
MAX_REFLECTANCE = 0.99  # the solve needs rho < 1; a white of 1.0 is common in Blender


class MaterialReader:
    """Reads and caches each material's colours; collects one warning per material and fault."""

    def __init__(self):
        self.cache: dict = {}
        self.warnings: list[str] = []

    def warn(self, material, text: str) -> None:
        line = f"material '{material.name}': {text}"
        if line not in self.warnings:
            self.warnings.append(line)

    def colours(self, material) -> tuple[np.ndarray, np.ndarray]:
        if material is None:
            return DEFAULT_REFLECTANCE, np.zeros(3)
        key = material.name
        if key not in self.cache:
            reflectance, emission = self._read(material)
            if np.any(reflectance > MAX_REFLECTANCE):
                self.warn(material, f"reflectance capped at {MAX_REFLECTANCE} (light must lose energy at each bounce)")
                reflectance = np.minimum(reflectance, MAX_REFLECTANCE)
            if not (np.all(np.isfinite(reflectance)) and np.all(np.isfinite(emission))):
                self.warn(material, "a colour or strength is not a finite number; baked as a grey default")
                reflectance, emission = DEFAULT_REFLECTANCE, np.zeros(3)
            self.cache[key] = (np.clip(reflectance, 0.0, None), np.clip(emission, 0.0, None))
        return self.cache[key]

    def _read(self, material):
        if not uses_nodes(material) or material.get(ENABLED_NODES):  # Blender 4.x without nodes: its colour
            return np.array(material.diffuse_color[:3], dtype=np.float64), np.zeros(3)
        output = original_output_node(material)
        surface = output.inputs.get("Surface") if output else None
        if surface is None or not surface.is_linked:
            self.warn(material, "no shader on the Material Output; using a grey default")
            return DEFAULT_REFLECTANCE, np.zeros(3)
        return self._shader(material, surface.links[0].from_node, depth=0)

    def _shader(self, material, node, depth):
        kind = node.bl_idname
        if depth > 16:
            return DEFAULT_REFLECTANCE, np.zeros(3)
        if kind == "ShaderNodeBsdfPrincipled":
            emission = self._colour(material, node.inputs["Emission Color"], np.zeros(3)) \
                * self._value(material, node.inputs["Emission Strength"])
            return self._colour(material, node.inputs["Base Color"], DEFAULT_REFLECTANCE), emission
        if kind == "ShaderNodeBsdfDiffuse":
            return self._colour(material, node.inputs["Color"], DEFAULT_REFLECTANCE), np.zeros(3)
        if kind == "ShaderNodeEmission":
            emission = self._colour(material, node.inputs["Color"], np.ones(3)) \
                * self._value(material, node.inputs["Strength"])
            return np.zeros(3), emission
        if kind in ("ShaderNodeAddShader", "ShaderNodeMixShader"):
            shaders = [s for s in node.inputs if s.type == "SHADER"]
            parts = [self._shader(material, s.links[0].from_node, depth + 1) if s.is_linked
                     else (np.zeros(3), np.zeros(3)) for s in shaders]
            if kind == "ShaderNodeAddShader":
                return parts[0][0] + parts[1][0], parts[0][1] + parts[1][1]
            fac = self._value(material, node.inputs["Fac"])
            return ((1 - fac) * parts[0][0] + fac * parts[1][0], (1 - fac) * parts[0][1] + fac * parts[1][1])
        if kind == "NodeReroute" and node.inputs[0].is_linked:
            return self._shader(material, node.inputs[0].links[0].from_node, depth + 1)
        self.warn(material, f"shader '{node.name}' is not diffuse; baked as a grey default")
        return DEFAULT_REFLECTANCE, np.zeros(3)

    def _colour(self, material, socket, default) -> np.ndarray:
        if not socket.is_linked:
            return np.array(socket.default_value[:3], dtype=np.float64)
        source = socket.links[0].from_node
        if source.bl_idname == "ShaderNodeTexImage" and source.image is not None:
            average = try_image_average(source.image)
            if average is not None:
                self.warn(material, f"texture '{source.image.name}' on '{socket.name}' baked as its average colour")
                return average
        self.warn(material, f"'{socket.name}' is driven by '{source.name}'; baked with its unlinked value")
        return np.array(socket.default_value[:3], dtype=np.float64) if len(socket.default_value) >= 3 else default

    def _value(self, material, socket) -> float:
        if socket.is_linked:
            self.warn(material, f"'{socket.name}' is driven by a node; baked with its unlinked value")
        return float(socket.default_value)


def srgb_to_linear(values: np.ndarray) -> np.ndarray:
    return np.where(values <= 0.04045, values / 12.92, ((values + 0.055) / 1.055) ** 2.4)


def image_average(image) -> np.ndarray:
    width, height = image.size
    pixels = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(-1, image.channels)[:, :3].astype(np.float64)
    if rgb.size == 0:
        return DEFAULT_REFLECTANCE
    mean = rgb.mean(axis=0)
    if not image.is_float and image.colorspace_settings.name.lower().startswith("srgb"):
        mean = srgb_to_linear(rgb).mean(axis=0)
    return mean


def try_image_average(image):
    """Average of an image whose pixels are not loaded yet (e.g. a file image); None if unreadable."""
    try:
        if image.size[0] * image.size[1] == 0:
            return None
        return image_average(image)
    except (RuntimeError, ValueError):
        return None
