"""Lamps and the world colour of a scene (its `lights` and `world` entries), as data.

Units follow Cycles (measured on a ρ = 0.8 plane; docs/architecture.md, Lamps):
point / spot `power` P W: intensity color · P / (4π) W/sr; sun `strength` S: irradiance
color · S W/m²; area lamp `power` P over area A: a one-sided polygon of radiance
color · P / (πA); world colour L: uniform sky radiance. How they are shot is `shooting.lamps`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from .geometry import polygon_area_vector
from .validate import number, vector

LAMP_TYPES = ("point", "spot", "sun", "area")


@dataclass(frozen=True)
class Lamp:
    name: str
    type: str
    color: np.ndarray  # (3,)
    position: np.ndarray | None = None  # point, spot
    direction: np.ndarray | None = None  # spot axis, sun travel direction (unit)
    power: float = 0.0  # watts: point, spot, area
    strength: float = 0.0  # sun, W/m²
    spot_size: float = math.pi  # full cone angle
    spot_blend: float = 0.0
    vertices: np.ndarray | None = None  # area: (4, 3), front along the emission
    angle: float = 0.0  # sun: the angular diameter of its disc (radians; Blender's Angle)

    @property
    def intensity(self) -> np.ndarray:
        """Radiant intensity (point, spot), W/sr per channel."""
        return self.color * self.power / (4 * math.pi)

    @property
    def area_radiance(self) -> np.ndarray:
        area = float(np.linalg.norm(polygon_area_vector(self.vertices)))
        return self.color * self.power / (math.pi * area)


def _field(entry: dict, key: str, length: int, where: str) -> np.ndarray:
    if key not in entry:
        raise SceneError(f"{where}: missing '{key}'")
    return vector(entry[key], length, f"'{key}'", where)


def _direction(entry: dict, where: str) -> np.ndarray:
    direction = _field(entry, "direction", 3, where)
    length = np.linalg.norm(direction)
    if length == 0:
        raise SceneError(f"{where}: 'direction' must not be zero")
    return direction / length


def lamp_from_dict(entry: dict, index: int) -> Lamp:
    if not isinstance(entry, dict):
        raise SceneError(f"light #{index}: must be an object with a 'type'")
    name = str(entry.get("name", f"light #{index}"))
    where = f"light '{name}'"
    kind = entry.get("type")
    if kind not in LAMP_TYPES:
        raise SceneError(f"{where}: 'type' must be one of {', '.join(LAMP_TYPES)}, got {kind!r}")
    color = _field(entry, "color", 3, where)
    if np.any(color < 0):
        raise SceneError(f"{where}: 'color' must not be negative")
    if kind == "point":
        return Lamp(name, kind, color, position=_field(entry, "position", 3, where),
                    power=number(entry.get("power"), "power", where))
    if kind == "spot":
        size = number(entry.get("spot_size"), "spot_size", where)
        if not 0 < size <= math.pi:
            raise SceneError(f"{where}: 'spot_size' must lie in (0, π], got {size}")
        return Lamp(name, kind, color, position=_field(entry, "position", 3, where),
                    power=number(entry.get("power"), "power", where), spot_size=size,
                    spot_blend=min(number(entry.get("spot_blend", 0.0), "spot_blend", where), 1.0),
                    direction=_direction(entry, where))
    if kind == "sun":
        angle = number(entry.get("angle", 0.0), "angle", where)
        if not 0 <= angle < math.pi:
            raise SceneError(f"{where}: 'angle' must lie in [0, π), got {angle}")
        return Lamp(name, kind, color, direction=_direction(entry, where),
                    strength=number(entry.get("strength"), "strength", where), angle=angle)
    raw = entry.get("vertices")
    if not isinstance(raw, list) or len(raw) != 4:
        raise SceneError(f"{where}: an area lamp needs 4 'vertices'")
    vertices = np.stack([vector(v, 3, f"vertex {k}", where) for k, v in enumerate(raw)])
    if np.linalg.norm(polygon_area_vector(vertices)) <= 0:
        raise SceneError(f"{where}: the area lamp has zero area")
    return Lamp(name, kind, color, vertices=vertices, power=number(entry.get("power"), "power", where))


def parse_lamps(raw) -> list[Lamp]:
    """The lamps of a `lights` entry that emit anything (validated; faults raise SceneError)."""
    if not raw:
        return []
    if not isinstance(raw, list):
        raise SceneError("scene: 'lights' must be a list")
    lamps = [lamp_from_dict(entry, k) for k, entry in enumerate(raw)]
    return [lamp for lamp in lamps if np.any(lamp.color > 0) and (lamp.power > 0 or lamp.strength > 0)]


def parse_world_color(world) -> np.ndarray:
    """The world's uniform radiance from a `world` entry (zeros without one)."""
    if not world:
        return np.zeros(3)
    if not isinstance(world, dict):
        raise SceneError("scene: 'world' must be an object with a 'color'")
    color = _field(world, "color", 3, "world")
    if np.any(color < 0):
        raise SceneError("world: 'color' must not be negative")
    return color
