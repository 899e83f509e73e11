"""Lightmap sizes: from a texel density, a per-object override and a cap. Natural sizes round
up to multiples of 8 so at least the first three mip levels have OpenGL's sizes too (powers of
two, optionally: all do)."""

from __future__ import annotations

import numbers

from ..errors import SolveError
from ..settings import MIN_LIGHTMAP_SIZE as MIN_SIZE

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
