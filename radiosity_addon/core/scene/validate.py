"""Checks shared by every way a scene comes in (scene files, the Blender exporter): values
read from user data, and the polygon checks, vectorized over all surfaces."""

from __future__ import annotations

import math

import numpy as np

from ..errors import SceneError
from .geometry import area_vector

PLANARITY_TOLERANCE = 1e-4  # off-plane distance, relative to the polygon's size
MIN_AREA_FRACTION = 1e-10  # area, relative to the squared size
STRAIGHT_CORNER = 1e-12  # turn at a corner, relative to the squared size
MAX_REFLECTANCE = 0.99  # the solve needs ρ < 1 (light must lose energy at each bounce); white 1.0 is common


def vector(value, length: int, what: str, where: str) -> np.ndarray:
    """`value` as `length` finite float64 numbers, or a SceneError naming `what` and `where`."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise SceneError(f"{where}: {what} must be {length} numbers, got {value!r}") from None
    if array.shape != (length,):
        raise SceneError(f"{where}: {what} must be {length} numbers, got {value!r}")
    if not np.all(np.isfinite(array)):
        raise SceneError(f"{where}: {what} has a NaN or infinite value: {value!r}")
    return array


def number(value, what: str, where: str) -> float:
    """A finite non-negative number, or a SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise SceneError(f"{where}: '{what}' must be a non-negative number, got {value!r}")
    return float(value)


def polygon_faults(corners: np.ndarray, corner_count: np.ndarray) -> dict[str, np.ndarray]:
    """Per polygon (corners (S, 4, 3), triangles repeating their last corner): masks of the faults
    no solve accepts — `zero_area`, `not_planar` (a quad off its plane by more than
    PLANARITY_TOLERANCE of its size), `not_convex` (a quad with a reflex or straight corner) —
    and `off_plane`, the largest distance of a quad's corner from its plane."""
    corners = np.asarray(corners, dtype=np.float64)
    quad = np.asarray(corner_count) == 4
    size = np.ptp(corners, axis=1).max(axis=1)
    vector_area = area_vector(corners)
    area = np.linalg.norm(vector_area, axis=1)
    zero_area = (size == 0.0) | (area <= MIN_AREA_FRACTION * size * size)
    normal = vector_area / np.where(area > 0, area, 1.0)[:, None]
    off_plane = np.abs(np.einsum("svc,sc->sv", corners - corners.mean(axis=1, keepdims=True), normal)).max(axis=1)
    edges = np.roll(corners, -1, axis=1) - corners
    turns = np.einsum("svc,sc->sv", np.cross(edges, np.roll(edges, -1, axis=1)), normal)
    not_planar = quad & ~zero_area & (off_plane > PLANARITY_TOLERANCE * size)
    not_convex = quad & ~zero_area & ~not_planar & np.any(turns <= STRAIGHT_CORNER * size[:, None] ** 2, axis=1)
    return {"zero_area": zero_area, "not_planar": not_planar, "not_convex": not_convex,
            "off_plane": np.where(quad, off_plane, 0.0)}


def check_polygons(corners: np.ndarray, corner_count: np.ndarray, names) -> None:
    """Raise a SceneError naming the first surface with a polygon fault."""
    faults = polygon_faults(corners, corner_count)
    bad = faults["zero_area"] | faults["not_planar"] | faults["not_convex"]
    if not bad.any():
        return
    index = int(np.flatnonzero(bad)[0])
    where = f"surface '{names[index]}'"
    if faults["zero_area"][index]:
        raise SceneError(f"{where}: the polygon has zero area (collinear or repeated vertices)")
    if faults["not_planar"][index]:
        raise SceneError(f"{where}: the quad is not planar (a vertex is {faults['off_plane'][index]:.3g} off its"
                         " plane); split it into two triangles")
    raise SceneError(f"{where}: the quad is not convex (or has a straight corner); split it into two triangles")


def check_values(names, reflectance: np.ndarray, emission: np.ndarray) -> None:
    """Reflectance in [0, 1) and emission >= 0 for every surface."""
    bad = np.flatnonzero(np.any((reflectance < 0) | (reflectance >= 1), axis=1))
    if len(bad):
        raise SceneError(f"surface '{names[bad[0]]}': reflectance must lie in [0, 1), got {reflectance[bad[0]].tolist()}")
    bad = np.flatnonzero(np.any(emission < 0, axis=1))
    if len(bad):
        raise SceneError(f"surface '{names[bad[0]]}': emission must not be negative, got {emission[bad[0]].tolist()}")
