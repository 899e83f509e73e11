"""Lamps and the world colour of a scene (its `lights` and `world` entries) as shooters.

Units follow Cycles (measured on a ρ = 0.8 plane, see the README), in the outgoing-radiance
units of the radiosity B:

- point / spot lamp of `power` P watts: radiant intensity I = color · P / (4π) W/sr; a receiver
  gets ρ · I · cosθ / (π r²), times the spot cone's falloff. Shot from its position as one
  hemisphere (a spot of cone ≤ 180°) or two (a point lamp);
- sun of `strength` S: irradiance color · S · cosθ, a receiver gets ρ · color · S · cosθ / π;
  shot from far away along its direction with an orthographic visibility map;
- area lamp of `power` P over area A: a one-sided emitting polygon of radiance color · P / (π A),
  shot in pieces with the exact polygon kernel (it casts no shadow of its own, as in Cycles);
- world colour L: a receiver gets ρ · L · (cosine-weighted fraction of its hemisphere that sees
  no surface), measured with hemi-cubes (see `sky.py`).

Lamps are shot once each, before the patches; what receivers reflect of them becomes unshot
radiosity like any other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .patches import bilinear
from .scene import Scene, SceneError, polygon_area_vector
from .shooting import Shooter
from .visibility import frame_from_normal

LAMP_TYPES = ("point", "spot", "sun", "area")
AREA_LAMP_PIECE = 1 / 32  # longest side of an area lamp's pieces, as a fraction of the scene's size
AREA_LAMP_MAX_SPLIT = 8  # pieces per side at most


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

    @property
    def intensity(self) -> np.ndarray:
        """Radiant intensity (point, spot), W/sr per channel."""
        return self.color * self.power / (4 * math.pi)

    @property
    def area_radiance(self) -> np.ndarray:
        area = float(np.linalg.norm(polygon_area_vector(self.vertices)))
        return self.color * self.power / (math.pi * area)


def _vector(entry: dict, key: str, length: int, where: str) -> np.ndarray:
    try:
        value = np.asarray(entry[key], dtype=np.float64)
    except KeyError:
        raise SceneError(f"{where}: missing '{key}'") from None
    except (TypeError, ValueError):
        raise SceneError(f"{where}: '{key}' must be {length} numbers") from None
    if value.shape != (length,) or not np.all(np.isfinite(value)):
        raise SceneError(f"{where}: '{key}' must be {length} finite numbers, got {entry[key]!r}")
    return value


def _number(entry: dict, key: str, where: str, default=None) -> float:
    value = entry.get(key, default)
    if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise SceneError(f"{where}: '{key}' must be a non-negative number, got {value!r}")
    return float(value)


def _unit(vector: np.ndarray, where: str) -> np.ndarray:
    length = np.linalg.norm(vector)
    if length == 0:
        raise SceneError(f"{where}: 'direction' must not be zero")
    return vector / length


def lamp_from_dict(entry: dict, index: int) -> Lamp:
    if not isinstance(entry, dict):
        raise SceneError(f"light #{index}: must be an object with a 'type'")
    name = str(entry.get("name", f"light #{index}"))
    where = f"light '{name}'"
    kind = entry.get("type")
    if kind not in LAMP_TYPES:
        raise SceneError(f"{where}: 'type' must be one of {', '.join(LAMP_TYPES)}, got {kind!r}")
    color = _vector(entry, "color", 3, where)
    if np.any(color < 0):
        raise SceneError(f"{where}: 'color' must not be negative")
    if kind in ("point", "spot"):
        lamp = Lamp(name, kind, color, position=_vector(entry, "position", 3, where),
                    power=_number(entry, "power", where))
        if kind == "spot":
            size = _number(entry, "spot_size", where)
            if not 0 < size <= math.pi:
                raise SceneError(f"{where}: 'spot_size' must lie in (0, π], got {size}")
            lamp = Lamp(name, kind, color, position=lamp.position, power=lamp.power, spot_size=size,
                        spot_blend=min(_number(entry, "spot_blend", where, 0.0), 1.0),
                        direction=_unit(_vector(entry, "direction", 3, where), where))
        return lamp
    if kind == "sun":
        return Lamp(name, kind, color, direction=_unit(_vector(entry, "direction", 3, where), where),
                    strength=_number(entry, "strength", where))
    raw = entry.get("vertices")
    if not isinstance(raw, list) or len(raw) != 4:
        raise SceneError(f"{where}: an area lamp needs 4 'vertices'")
    vertices = np.stack([_vector({"v": v}, "v", 3, where) for v in raw])
    if np.linalg.norm(polygon_area_vector(vertices)) <= 0:
        raise SceneError(f"{where}: the area lamp has zero area")
    return Lamp(name, kind, color, vertices=vertices, power=_number(entry, "power", where))


def scene_lamps(scene: Scene) -> list[Lamp]:
    """The scene's lamps that emit anything (validated; faults raise SceneError)."""
    raw = scene.extras.get("lights") or []
    if not isinstance(raw, list):
        raise SceneError("scene: 'lights' must be a list")
    lamps = [lamp_from_dict(entry, k) for k, entry in enumerate(raw)]
    return [lamp for lamp in lamps if np.any(lamp.color > 0) and (lamp.power > 0 or lamp.strength > 0)]


def world_color(scene: Scene) -> np.ndarray:
    """The world's uniform radiance (zeros without a world)."""
    world = scene.extras.get("world")
    if not world:
        return np.zeros(3)
    if not isinstance(world, dict):
        raise SceneError("scene: 'world' must be an object with a 'color'")
    color = _vector(world, "color", 3, "world")
    if np.any(color < 0):
        raise SceneError("world: 'color' must not be negative")
    return color


def spot_falloff(cos_angle: np.ndarray, lamp: Lamp) -> np.ndarray:
    """Cycles' spot cone: smoothstep over the blend band inside the cone's edge."""
    cos_half = math.cos(lamp.spot_size / 2)
    smooth = (1 - cos_half) * lamp.spot_blend
    t = np.clip((cos_angle - cos_half) / smooth, 0, 1) if smooth > 0 else (cos_angle > cos_half).astype(float)
    return t * t * (3 - 2 * t)


def lamp_shooters(lamp: Lamp, scene_centre: np.ndarray, scene_diameter: float) -> list[Shooter]:
    """The shots of one lamp: a point lamp two hemispheres, a spot of cone <= 180° one,
    a sun one orthographic view from outside the scene, an area lamp its polygon."""
    if lamp.type in ("point", "spot"):
        cone = lamp.type == "spot"
        cos_half = math.cos(lamp.spot_size / 2) if cone else -2.0
        axis = lamp.direction if cone else np.array([0.0, 0.0, 1.0])
        poles = [axis] if cone and lamp.spot_size <= math.pi else [axis, -axis]
        return [Shooter(position=lamp.position, axes=(*frame_from_normal(pole), pole), polygon=np.zeros((4, 3)),
                        area=0.0, radiosity=lamp.intensity, kind=1, light_direction=tuple(axis),
                        spot_cos_half=cos_half, spot_smooth=(1 - cos_half) * lamp.spot_blend if cone else 0.0)
                for pole in poles]
    if lamp.type == "sun":
        eye = scene_centre - lamp.direction * scene_diameter
        return [Shooter(position=eye, axes=(*frame_from_normal(lamp.direction), lamp.direction),
                        polygon=np.zeros((4, 3)), area=0.0, radiosity=lamp.color * lamp.strength, kind=2,
                        light_direction=tuple(lamp.direction), ortho_extent=scene_diameter / 2)]
    # An area lamp is split into sub-lamps, each with its own visibility map, so shadows keep
    # their penumbra (one map from the centre turns a nearby object's penumbra into umbra).
    normal = polygon_area_vector(lamp.vertices)
    normal = normal / np.linalg.norm(normal)
    sides = np.linalg.norm(np.roll(lamp.vertices, -1, axis=0) - lamp.vertices, axis=1)
    split = int(np.clip(np.ceil(sides.max() / (scene_diameter * AREA_LAMP_PIECE)), 1, AREA_LAMP_MAX_SPLIT))
    grid = np.arange(split + 1) / split
    s0, t0 = np.meshgrid(grid[:-1], grid[:-1])
    offsets = np.array([[0, 0], [1, 0], [1, 1], [0, 1]]) / split
    corners = bilinear(lamp.vertices[None], s0.ravel()[:, None] + offsets[:, 0], t0.ravel()[:, None] + offsets[:, 1])[0]
    radiance = lamp.area_radiance
    x_axis = frame_from_normal(normal, lamp.vertices[1] - lamp.vertices[0])
    return [Shooter(position=piece.mean(axis=0), axes=(*x_axis, normal), polygon=piece,
                    area=float(np.linalg.norm(polygon_area_vector(piece))), radiosity=radiance, kind=0)
            for piece in corners]
