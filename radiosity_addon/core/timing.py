"""Wall time per stage and progress callbacks, shared by every stage."""

from __future__ import annotations

import contextlib
import time
from typing import Callable

# progress(fraction_done, message, details) — fraction in [0, 1]
ProgressCallback = Callable[[float, str, dict], None]


class StageTimer:
    """Wall time per named stage, in seconds, for the report's `timings`."""

    def __init__(self):
        self.timings: dict[str, float] = {}

    @contextlib.contextmanager
    def stage(self, name: str):
        start = time.perf_counter()
        try:
            yield
        finally:
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start


def scaled_progress(progress: ProgressCallback | None, start: float, end: float) -> ProgressCallback | None:
    """A progress callback mapping [0, 1] of one stage onto [start, end] of the whole."""
    if progress is None:
        return None
    return lambda fraction, message, details: progress(start + (end - start) * fraction, message, details)
