"""Blender materials -> (reflectance, emission) in the core's units, read off the shader graph.

For geometry whose materials cannot be baked by Cycles (instances, occluders without a
'Lightmap' UV map; baked objects get `material_bake`): `shader_graph.walk` with numbers — a
texture on a colour input becomes its average colour, a Principled BSDF its diffuse part
(about (1 − metallic)(1 − transmission)(1 − 0.075 x specular level), close to Cycles' at
roughness ≥ 0.5), anything else a grey default, each with a warning.
"""

from __future__ import annotations

import numpy as np

from ..core import MAX_REFLECTANCE
from .shader_graph import surface_shader, walk
from .tags import ENABLED_NODES, original_output_node, uses_nodes

# Blender's default surface (no material): a Principled BSDF, base 0.8, roughness 0.5, specular
# 0.5, whose diffuse albedo Cycles' Diffuse Color pass measures at 0.770
DEFAULT_REFLECTANCE = np.array([0.770, 0.770, 0.770])


class Values:
    """`shader_graph` algebra of numbers, with the reader's warnings."""

    def __init__(self, reader, material):
        self.reader, self.material = reader, material

    def constant(self, rgb):
        return np.asarray(rgb, dtype=np.float64)

    def colour(self, socket):
        if not socket.is_linked:
            return np.array(socket.default_value[:3], dtype=np.float64)
        source = socket.links[0].from_node
        if source.bl_idname == "ShaderNodeTexImage" and source.image is not None:
            average = try_image_average(source.image)
            if average is not None:
                self.reader.warn_read(self.material, f"texture '{source.image.name}' on '{socket.name}' baked as"
                                                     " its average colour")
                return average
        self.reader.warn_read(self.material, f"'{socket.name}' is driven by '{source.name}'; baked with its"
                                             " unlinked value")
        return np.array(socket.default_value[:3], dtype=np.float64)

    def scalar(self, socket):
        if socket.is_linked:
            self.reader.warn_read(self.material, f"'{socket.name}' is driven by a node; baked with its unlinked value")
        return float(socket.default_value)

    def diffuse_factor(self, node):
        value = lambda name: float(node.inputs[name].default_value) if name in node.inputs else 0.0  # noqa: E731
        metallic, transmission = value("Metallic"), value("Transmission Weight") or value("Transmission")
        specular = value("Specular IOR Level") if "Specular IOR Level" in node.inputs else value("Specular")
        if metallic > 0 or transmission > 0:
            self.reader.warn(self.material, f"metallic {metallic:g} / transmission {transmission:g} have no diffuse"
                                            " radiosity; baked as the diffuse part")
        return (1 - metallic) * (1 - transmission) * (1 - 0.075 * specular)

    def unknown(self, node):
        name = node.name if node is not None else "nothing"
        self.reader.warn(self.material, f"shader '{name}' is not diffuse; baked as a grey default")
        return DEFAULT_REFLECTANCE, np.zeros(3)

    def scale(self, colour, factor):
        return colour * factor

    def add(self, a, b):
        return a + b

    def mix(self, fac, a, b):
        return (1 - fac) * a + fac * b


class MaterialReader:
    """Reads and caches each material's colours; collects one warning per material and fault."""

    def __init__(self, cycles_bakes_inputs: bool = False):
        self.cache: dict = {}
        self.warnings: list[str] = []
        # the objects read are baked by Cycles (material_bake): what this reading guesses about
        # linked inputs is replaced by Cycles' own values, so saying it would mislead
        self.cycles_bakes_inputs = cycles_bakes_inputs

    def warn_read(self, material, text: str) -> None:
        """A warning about an input this reading could only guess."""
        if not self.cycles_bakes_inputs:
            self.warn(material, text)

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
        shader = surface_shader(original_output_node(material))
        if shader is None:
            self.warn(material, "no shader on the Material Output; using a grey default")
            return DEFAULT_REFLECTANCE, np.zeros(3)
        return walk(shader, Values(self, material))


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
