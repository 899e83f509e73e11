"""The scene model: planar convex polygons with reflectance, emission, lightmap UVs, grouped
into objects (the surfaces of one object share a lightmap), plus lamps and a world colour.

Surfaces are stored as arrays (one row per surface) so that every stage handles a scene of
100 000 faces without a Python loop over them; `Surface` is a view of one row for callers
that handle a few. Values are outgoing radiance in Blender's emission units (see
docs/architecture.md, Units).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import geometry
from .lamps import Lamp, parse_lamps, parse_world_color


@dataclass(frozen=True)
class Surface:
    name: str
    vertices: np.ndarray  # (k, 3) float64, k in {3, 4}, counter-clockwise from the front
    reflectance: np.ndarray  # (3,) in [0, 1)
    emission: np.ndarray  # (3,) >= 0, outgoing radiance
    object: str = ""
    uv: np.ndarray | None = None  # (k, 2) lightmap UVs, or None
    two_sided: bool = False  # the back emits and receives too

    @property
    def object_name(self) -> str:
        return self.object or self.name

    @property
    def is_triangle(self) -> bool:
        return len(self.vertices) == 3

    @property
    def normal(self) -> np.ndarray:
        return geometry.unit(geometry.polygon_area_vector(self.vertices))

    @property
    def area(self) -> float:
        return float(np.linalg.norm(geometry.polygon_area_vector(self.vertices)))


@dataclass(frozen=True)
class MaterialMap:
    """An object's diffuse albedo and emission per texel of its lightmap UVs, as the renderer
    evaluates its materials (the Blender side bakes them with Cycles): float32 (H, W, 3) each,
    row 0 at v = 0, the layout of its lightmap."""
    albedo: np.ndarray
    emission: np.ndarray


def padded_corners(vertices) -> np.ndarray:
    """(4, 3) corners of a 3- or 4-vertex polygon (a triangle repeats its last vertex)."""
    v = np.asarray(vertices, dtype=np.float64)
    return np.concatenate([v, v[-1:]])[:4] if len(v) == 3 else v


class FaceNames(Sequence):
    """Surface names made on demand, `<object>#<k>` (k counting the scene's surfaces): a mesh
    exported face by face needs no string per face until one is named in a message."""

    def __init__(self, object_names: list[str], object_index: np.ndarray):
        self.object_names, self.object_index = object_names, object_index

    def __len__(self) -> int:
        return len(self.object_index)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        index = int(index)
        if index < 0:
            index += len(self)
        return f"{self.object_names[self.object_index[index]]}#{index}"


@dataclass(eq=False)
class Scene:
    names: Sequence[str]  # (S) surface names, unique (a list, or FaceNames)
    corners: np.ndarray  # (S, 4, 3) float64, counter-clockwise from the front; triangles repeat c2
    corner_count: np.ndarray  # (S,) int: 3 or 4
    reflectance: np.ndarray  # (S, 3)
    emission: np.ndarray  # (S, 3)
    object_index: np.ndarray  # (S,) int: index into object_names
    object_names: list[str]  # objects in first-seen order
    uv: np.ndarray  # (S, 4, 2) lightmap UVs of the corners (zeros where has_uv is False)
    has_uv: np.ndarray  # (S,) bool
    two_sided: np.ndarray  # (S,) bool: the back emits and receives too
    extras: dict = field(default_factory=dict)  # other top-level keys (lights, world, camera), kept on save
    material_maps: dict = field(default_factory=dict)  # object name -> MaterialMap (textured materials)
    opacity: object = None  # OpacityMaps: faces whose material lets light through where its texture says (None: none)

    @classmethod
    def from_surfaces(cls, surfaces: list[Surface], extras: dict | None = None) -> "Scene":
        object_names = list(dict.fromkeys(s.object_name for s in surfaces))
        object_of = {name: k for k, name in enumerate(object_names)}
        return cls(
            names=[s.name for s in surfaces],
            corners=np.stack([padded_corners(s.vertices) for s in surfaces]),
            corner_count=np.array([len(s.vertices) for s in surfaces], dtype=np.int64),
            reflectance=np.stack([np.asarray(s.reflectance, dtype=np.float64) for s in surfaces]),
            emission=np.stack([np.asarray(s.emission, dtype=np.float64) for s in surfaces]),
            object_index=np.array([object_of[s.object_name] for s in surfaces], dtype=np.int64),
            object_names=object_names,
            uv=np.stack([padded_corners(s.uv) if s.uv is not None else np.zeros((4, 2)) for s in surfaces]),
            has_uv=np.array([s.uv is not None for s in surfaces], dtype=bool),
            two_sided=np.array([s.two_sided for s in surfaces], dtype=bool),
            extras=dict(extras or {}),
        )

    def __len__(self) -> int:
        return len(self.names)

    def surface(self, index: int) -> Surface:
        k = int(self.corner_count[index])
        return Surface(name=self.names[index], vertices=self.corners[index, :k], reflectance=self.reflectance[index],
                       emission=self.emission[index], object=self.object_names[self.object_index[index]],
                       uv=self.uv[index, :k] if self.has_uv[index] else None, two_sided=bool(self.two_sided[index]))

    @property
    def surfaces(self) -> list[Surface]:
        """Every surface as a `Surface` (a Python object each: for callers that handle few)."""
        return [self.surface(i) for i in range(len(self))]

    @property
    def opacity_index(self) -> np.ndarray | None:
        """(S,) the opacity texture of each surface, -1 for opaque ones (None: the scene has none)."""
        return None if self.opacity is None else self.opacity.index

    @property
    def objects(self) -> list[str]:
        return list(self.object_names)

    @functools.cached_property
    def object_surfaces(self) -> dict[str, np.ndarray]:
        """Object name -> indices of its surfaces (ascending)."""
        order = np.argsort(self.object_index, kind="stable")
        starts = np.searchsorted(self.object_index[order], np.arange(len(self.object_names) + 1))
        return {name: order[starts[k]:starts[k + 1]] for k, name in enumerate(self.object_names)}

    @property
    def is_triangle(self) -> np.ndarray:
        return self.corner_count == 3

    @functools.cached_property
    def area_vector(self) -> np.ndarray:
        return geometry.area_vector(self.corners)

    @functools.cached_property
    def area(self) -> np.ndarray:
        return np.linalg.norm(self.area_vector, axis=1)

    @functools.cached_property
    def normal(self) -> np.ndarray:
        return self.area_vector / self.area[:, None]

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        points = self.corners.reshape(-1, 3)
        return points.min(axis=0), points.max(axis=0)

    @property
    def diameter(self) -> float:
        low, high = self.bounds
        return float(np.linalg.norm(high - low))

    @functools.cached_property
    def lamps(self) -> list[Lamp]:
        """The lamps (the `lights` entry) that emit anything; faults raise SceneError."""
        return parse_lamps(self.extras.get("lights"))

    @functools.cached_property
    def world_color(self) -> np.ndarray:
        """The world's uniform radiance (zeros without a world)."""
        return parse_world_color(self.extras.get("world"))

    def to_dict(self) -> dict:
        surfaces = []
        for i, name in enumerate(self.names):
            k = int(self.corner_count[i])
            entry = {"name": name, "object": self.object_names[self.object_index[i]],
                     "vertices": self.corners[i, :k].tolist(), "reflectance": self.reflectance[i].tolist(),
                     "emission": self.emission[i].tolist()}
            if self.has_uv[i]:
                entry["uv"] = self.uv[i, :k].tolist()
            if self.two_sided[i]:
                entry["two_sided"] = True
            surfaces.append(entry)
        return {**self.extras, "surfaces": surfaces}
