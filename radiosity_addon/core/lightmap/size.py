"""Lightmap sizes: from a texel density, a per-object override and a cap. Natural sizes round
up to multiples of 8 so at least the first three mip levels have OpenGL's sizes too (powers of
two, optionally: all do). And the UVs an object brings, checked before they are used."""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import SceneError, SolveError
from ..scene import Scene
from ..settings import MIN_LIGHTMAP_SIZE as MIN_SIZE
from ..settings import TEXEL_DENSITY, LightmapSettings

UV_TOLERANCE = 1e-3  # how far given UVs may stray outside [0, 1]
SIZE_MULTIPLE = 8  # sizes round up to this so levels 1-3 halve exactly, as GL's floor(w / 2) does


def resolve_size(natural: tuple[int, int], override, max_size: int, power_of_two: bool,
                 object_name: str) -> tuple[int, int]:
    """Final (width, height): the override or the natural size, rounded and capped."""
    if override is not None:
        try:
            size = (override, override) if isinstance(override, numbers.Real) else tuple(override)
            valid = len(size) == 2 and all(int(n) == n >= MIN_SIZE for n in size)
        except (TypeError, ValueError):
            valid = False
        if not valid:
            raise SolveError(f"object '{object_name}': lightmap resolution {override!r} must be an integer"
                             f" (or width, height) of at least {MIN_SIZE}")
        size = tuple(int(n) for n in size)
    else:
        size = tuple(max(MIN_SIZE, -(-int(n) // SIZE_MULTIPLE) * SIZE_MULTIPLE) for n in natural)
    if power_of_two:
        size = tuple(1 << (n - 1).bit_length() for n in size)
        cap = 1 << (max_size.bit_length() - 1)
    else:
        cap = max_size
    return tuple(min(n, cap) for n in size)


def uv_polygon_area(uv: np.ndarray) -> np.ndarray:
    """(n,) areas of UV polygons (n, 4, 2) (shoelace; a repeated corner adds nothing)."""
    x, y = uv[..., 0], uv[..., 1]
    return 0.5 * np.abs((x * np.roll(y, -1, axis=-1) - y * np.roll(x, -1, axis=-1)).sum(axis=-1))


def given_uvs(scene: Scene, name: str, indices: np.ndarray) -> bool:
    """True if the object's surfaces all carry UVs, False if none do; mixed or out-of-range is an error."""
    with_uv = scene.has_uv[indices]
    if not with_uv.any():
        return False
    if not with_uv.all():
        missing = scene.names[indices[np.flatnonzero(~with_uv)[0]]]
        raise SceneError(f"object '{name}': surface '{missing}' has no lightmap 'uv' but others of the"
                         " object do; give every surface of an object UVs, or none")
    uv = scene.uv[indices]
    outside = np.flatnonzero((uv.min(axis=(1, 2)) < -UV_TOLERANCE) | (uv.max(axis=(1, 2)) > 1 + UV_TOLERANCE))
    if len(outside):
        raise SceneError(f"surface '{scene.names[indices[outside[0]]]}': lightmap UVs leave the [0, 1] square")
    if uv_polygon_area(uv).sum() <= 0:
        raise SceneError(f"object '{name}': its lightmap UVs have zero area")
    return True


def chosen_texel_density(scene: Scene, settings: LightmapSettings, objects=None) -> float:
    """The settings' texel density, or where it is 0 (automatic) the one that spreads the settings'
    `texel_budget` texels over the surfaces of `objects` (default: all), at least TEXEL_DENSITY."""
    if settings.texel_density > 0:
        return float(settings.texel_density)
    chosen = set(scene.object_names if objects is None else objects)
    baked = np.isin(np.asarray(scene.object_names)[scene.object_index], list(chosen))
    area = float(scene.area[baked].sum())
    return max(TEXEL_DENSITY, math.sqrt(settings.texel_budget / area)) if area > 0 else TEXEL_DENSITY
