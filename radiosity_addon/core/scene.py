"""The scene model: planar convex polygons with reflectance, emission and UVs.

This is the bpy-free input of the core (DESIGN.md, Interfaces › Scene file).
Every fault a user can make is refused with a `SceneError` whose message
names the surface and the fault.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

BUNDLED_SCENES_DIR = Path(__file__).parent / "scenes"

# Relative tolerances of the geometric checks (fractions of the polygon size).
PLANARITY_TOLERANCE = 1e-4
MIN_AREA_FRACTION = 1e-10


class SceneError(ValueError):
    """A scene the user gave cannot be solved; the message says why."""


@dataclass(frozen=True)
class Surface:
    name: str
    vertices: np.ndarray  # (k, 3) float64, k in {3, 4}, counter-clockwise from the front
    reflectance: np.ndarray  # (3,) in [0, 1)
    emission: np.ndarray  # (3,) >= 0, outgoing radiance
    object: str = ""
    uv: np.ndarray | None = None  # (k, 2) lightmap UVs, or None

    @property
    def object_name(self) -> str:
        return self.object or self.name

    @property
    def is_triangle(self) -> bool:
        return len(self.vertices) == 3

    @property
    def normal(self) -> np.ndarray:
        return polygon_normal(self.vertices)

    @property
    def area(self) -> float:
        return polygon_area(self.vertices)


@dataclass
class Scene:
    surfaces: list[Surface]
    extras: dict = field(default_factory=dict)  # unknown top-level keys, kept on save

    @property
    def objects(self) -> list[str]:
        """Object names in first-seen order; surfaces of one object share a lightmap."""
        return list(dict.fromkeys(s.object_name for s in self.surfaces))

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        points = np.concatenate([s.vertices for s in self.surfaces])
        return points.min(axis=0), points.max(axis=0)

    @property
    def diameter(self) -> float:
        low, high = self.bounds
        return float(np.linalg.norm(high - low))

    def to_dict(self) -> dict:
        surfaces = []
        for s in self.surfaces:
            entry = {
                "name": s.name,
                "object": s.object_name,
                "vertices": s.vertices.tolist(),
                "reflectance": s.reflectance.tolist(),
                "emission": s.emission.tolist(),
            }
            if s.uv is not None:
                entry["uv"] = s.uv.tolist()
            surfaces.append(entry)
        return {**self.extras, "surfaces": surfaces}


def polygon_area_vector(vertices: np.ndarray) -> np.ndarray:
    """Half the sum of fan cross products: |v| is the area, v/|v| the normal."""
    v = np.asarray(vertices, dtype=np.float64)
    origin = v[0]
    return 0.5 * np.cross(v[1:-1] - origin, v[2:] - origin).sum(axis=0)


def polygon_area(vertices: np.ndarray) -> float:
    return float(np.linalg.norm(polygon_area_vector(vertices)))


def polygon_normal(vertices: np.ndarray) -> np.ndarray:
    a = polygon_area_vector(vertices)
    return a / np.linalg.norm(a)


def _vector(value, length: int, what: str, where: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneError(f"{where}: {what} must be {length} numbers, got {value!r}") from None
    if array.shape != (length,):
        raise SceneError(f"{where}: {what} must be {length} numbers, got {value!r}")
    if not np.all(np.isfinite(array)):
        raise SceneError(f"{where}: {what} has a NaN or infinite value: {value!r}")
    return array


def _check_polygon(vertices: np.ndarray, where: str) -> None:
    size = float(np.max(np.ptp(vertices, axis=0)))
    area_vector = polygon_area_vector(vertices)
    area = float(np.linalg.norm(area_vector))
    if size == 0.0 or area <= MIN_AREA_FRACTION * size * size:
        raise SceneError(f"{where}: the polygon has zero area (collinear or repeated vertices)")
    normal = area_vector / area
    if len(vertices) == 4:
        off_plane = np.abs((vertices - vertices.mean(axis=0)) @ normal).max()
        if off_plane > PLANARITY_TOLERANCE * size:
            raise SceneError(
                f"{where}: the quad is not planar (a vertex is {off_plane:.3g} off its plane);"
                " split it into two triangles"
            )
        edges = np.roll(vertices, -1, axis=0) - vertices
        turns = np.cross(edges, np.roll(edges, -1, axis=0)) @ normal
        if np.any(turns <= 1e-12 * size * size):
            raise SceneError(
                f"{where}: the quad is not convex (or has a straight corner);"
                " split it into two triangles"
            )


def surface_from_dict(entry: dict, index: int) -> Surface:
    if not isinstance(entry, dict):
        raise SceneError(f"surface #{index}: must be an object with name, vertices, reflectance, emission")
    name = entry.get("name")
    if not isinstance(name, str) or not name:
        raise SceneError(f"surface #{index}: needs a non-empty string 'name'")
    where = f"surface '{name}'"
    for key in ("vertices", "reflectance", "emission"):
        if key not in entry:
            raise SceneError(f"{where}: missing '{key}'")
    raw_vertices = entry["vertices"]
    if not isinstance(raw_vertices, list) or not 3 <= len(raw_vertices) <= 4:
        count = len(raw_vertices) if isinstance(raw_vertices, list) else "no"
        raise SceneError(f"{where}: needs 3 or 4 vertices, got {count}")
    vertices = np.stack([_vector(v, 3, f"vertex {k}", where) for k, v in enumerate(raw_vertices)])
    _check_polygon(vertices, where)

    reflectance = _vector(entry["reflectance"], 3, "reflectance", where)
    if np.any(reflectance < 0) or np.any(reflectance >= 1):
        raise SceneError(f"{where}: reflectance must lie in [0, 1), got {reflectance.tolist()}")
    emission = _vector(entry["emission"], 3, "emission", where)
    if np.any(emission < 0):
        raise SceneError(f"{where}: emission must not be negative, got {emission.tolist()}")

    uv = None
    if entry.get("uv") is not None:
        raw_uv = entry["uv"]
        if not isinstance(raw_uv, list) or len(raw_uv) != len(vertices):
            raise SceneError(f"{where}: 'uv' needs one [u, v] per vertex ({len(vertices)})")
        uv = np.stack([_vector(t, 2, f"uv {k}", where) for k, t in enumerate(raw_uv)])

    obj = entry.get("object", name)
    if not isinstance(obj, str) or not obj:
        raise SceneError(f"{where}: 'object' must be a non-empty string")
    return Surface(name=name, vertices=vertices, reflectance=reflectance, emission=emission, object=obj, uv=uv)


def scene_from_dict(data: dict, require_emitter: bool = True) -> Scene:
    if not isinstance(data, dict) or not isinstance(data.get("surfaces"), list):
        raise SceneError("scene: expected a JSON object with a 'surfaces' list")
    if not data["surfaces"]:
        raise SceneError("scene: the 'surfaces' list is empty")
    surfaces = [surface_from_dict(entry, k) for k, entry in enumerate(data["surfaces"])]
    duplicates = sorted(name for name, count in Counter(s.name for s in surfaces).items() if count > 1)
    if duplicates:
        raise SceneError(f"surface '{duplicates[0]}': the name is used by more than one surface")
    scene = Scene(surfaces=surfaces, extras={k: v for k, v in data.items() if k != "surfaces"})
    if require_emitter:
        check_has_emitter(scene)
    return scene


def check_has_emitter(scene: Scene) -> None:
    """Refuse a scene with no emissive surface, no lamp that emits and no world colour."""
    from .effects import emitter_count  # effects reads the lamps, which build on this module

    if emitter_count(scene) == 0:
        raise SceneError(
            "scene: nothing emits light; give at least one surface a positive emission"
            " (an emissive material), a lamp or a world colour before baking"
        )


def bundled_scene_names() -> list[str]:
    return sorted(p.stem for p in BUNDLED_SCENES_DIR.glob("*.json"))


def resolve_scene_path(path_or_name: str | Path) -> Path:
    path = Path(path_or_name)
    if path.suffix == "" and not path.exists():
        bundled = BUNDLED_SCENES_DIR / f"{path_or_name}.json"
        if bundled.exists():
            return bundled
        raise SceneError(
            f"scene: '{path_or_name}' is neither a file nor a bundled scene"
            f" ({', '.join(bundled_scene_names())})"
        )
    if not path.exists():
        raise SceneError(f"scene: file '{path}' does not exist")
    return path


def load_scene(path_or_name: str | Path, require_emitter: bool = True) -> Scene:
    """Load a scene file, or a bundled scene by name (e.g. 'cornell-box')."""
    path = resolve_scene_path(path_or_name)
    try:
        data = json.loads(path.read_text(), parse_constant=lambda c: math.nan)
    except json.JSONDecodeError as error:
        raise SceneError(f"scene: '{path}' is not valid JSON ({error})") from None
    except OSError as error:
        raise SceneError(f"scene: cannot read '{path}' ({error.strerror})") from None
    return scene_from_dict(data, require_emitter=require_emitter)


def save_scene(scene: Scene, path: str | Path) -> None:
    Path(path).write_text(json.dumps(scene.to_dict(), indent=1))
