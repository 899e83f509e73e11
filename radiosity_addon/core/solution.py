"""Settings in, solution out: the types every solver and every caller share."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np

from .patches import Patches

METHODS = ("progressive", "hemicube")
SOLVERS = ("jacobi-gpu", "jacobi-cpu", "gauss-seidel")
DEFAULT_TOLERANCE = {"progressive": 1e-3, "hemicube": 1e-5}


class SolveError(RuntimeError):
    """A solve that cannot proceed; the message says what to do."""


class SolveCancelled(RuntimeError):
    """The user cancelled the solve."""


@dataclass
class SolveSettings:
    method: str = "progressive"
    subdiv: int = 4  # each surface split subdiv x subdiv into patches
    elements: int = 4  # S x S elements per patch (progressive), S a power of two
    hemicube_res: int = 128  # pixels across the hemi-cube's top face
    solver: str = "jacobi-gpu"
    tolerance: float | None = None  # None: the method's default
    max_iterations: int = 100_000  # linear solvers
    max_shots: int | None = None  # progressive; None: as many as the tolerance needs
    visibility: str = "search"  # progressive: plain | tessellated | search
    kernel: str = "exact"  # progressive: exact | disk
    memory_limit_bytes: int = 2 << 30  # hemi-cube form-factor matrix guard
    skip_unneeded: bool = True  # simulate only the effects the scene calls for (core/effects.py)

    @property
    def effective_tolerance(self) -> float:
        return self.tolerance if self.tolerance is not None else DEFAULT_TOLERANCE[self.method]

    def validate(self) -> None:
        if self.method not in METHODS:
            raise SolveError(f"unknown method '{self.method}' (choose {', '.join(METHODS)})")
        if self.solver not in SOLVERS:
            raise SolveError(f"unknown solver '{self.solver}' (choose {', '.join(SOLVERS)})")
        if self.subdiv < 1:
            raise SolveError("subdivision must be at least 1")
        if self.elements < 1 or self.elements & (self.elements - 1):
            raise SolveError("elements per patch must be a power of two (1, 2, 4, 8, ...)")
        if self.hemicube_res < 8 or self.hemicube_res % 2:
            raise SolveError("hemi-cube resolution must be an even number of at least 8")
        if not 0 < self.effective_tolerance < 1:
            raise SolveError("tolerance must lie between 0 and 1")

    def as_dict(self) -> dict:
        return asdict(self)


# progress(fraction_done, message, details) — fraction in [0, 1]
ProgressCallback = Callable[[float, str, dict], None]


@dataclass
class Solution:
    patches: Patches
    patch_radiosity: np.ndarray  # (P, 3) float64
    element_radiosity: np.ndarray | None = None  # (P, S, S, 3): [patch, t row, s column]
    report: dict = field(default_factory=dict)

    def npz_arrays(self) -> dict:
        arrays = {
            "patch_radiosity": self.patch_radiosity.astype(np.float32),
            "patch_area": self.patches.area.astype(np.float32),
            "patch_center": self.patches.center.astype(np.float32),
            "patch_normal": self.patches.normal.astype(np.float32),
            "patch_surface": self.patches.surface.astype(np.int32),
            "patch_corners": self.patches.corners.astype(np.float32),
        }
        if self.element_radiosity is not None:
            arrays["element_radiosity"] = self.element_radiosity.astype(np.float32)
        return arrays


class StageTimer:
    """Wall time per named stage, in seconds, for the report's `timings`."""

    def __init__(self):
        self.timings: dict[str, float] = {}

    def stage(self, name: str):
        timer = self

        class _Stage:
            def __enter__(self):
                self.start = time.perf_counter()

            def __exit__(self, *exc):
                timer.timings[name] = timer.timings.get(name, 0.0) + time.perf_counter() - self.start

        return _Stage()
