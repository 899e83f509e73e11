"""Wall time per stage and progress callbacks, shared by every stage."""

from __future__ import annotations

import contextlib
import contextvars
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


SPEED_LIMITS = (0.25, 4.0)  # how far the stages done may scale the prediction of those ahead
SPEED_EVIDENCE = 0.5  # predicted seconds of stages done before their speed scales those ahead
PULSE_INTERVAL = 0.5  # seconds between the reports `pulse` makes at most
PULSE_SHARE = 0.95  # of a stage's predicted time, the most a pulse says is done

_pulse = contextvars.ContextVar("radiosity_pulse", default=None)


def pulse() -> None:
    """Called by loops that may run long (the texel pass's batches, the hemi-cube batches, the
    lightmaps' objects): the running stage of a `StagePlan` reports its progress by the time gone,
    at most every PULSE_INTERVAL seconds, so the bar and the estimate move within every stage."""
    beat = _pulse.get()
    if beat is not None:
        beat()


class StagePlan:
    """Progress over stages whose cost is predicted before they run (`predicted`: name -> seconds),
    so the bar moves with time from the first stage on and the time left covers them all: the
    fraction reported is the predicted share done (the stages done, and the running one's own
    fraction of its share), the time left the predicted rest, scaled by how long the stages done
    took against their predictions (this machine, now). A stage that estimates its own time left
    (progressive refinement's shots) gives that instead of its share's rest. A prediction may be
    set again once a stage knows better (`predict`); stages not named run unreported."""

    def __init__(self, progress: ProgressCallback | None, predicted: dict[str, float]):
        self.progress = progress
        self.predicted = {name: max(float(seconds), 1e-3) for name, seconds in predicted.items()}
        self.done: dict[str, float] = {}
        self.current: str | None = None
        self.current_started = 0.0
        self.last_report = 0.0
        self.last_message = ""
        self.shown = 0.0  # the fraction reported last: never less after (a prediction set again may lower it)
        self.waiting = False  # the running stage estimates itself and has not yet

    def predict(self, name: str, seconds: float) -> None:
        if name not in self.done:
            self.predicted[name] = max(float(seconds), 1e-3)

    @property
    def speed(self) -> float:
        """Seconds taken per second predicted, by the stages done (1 before any)."""
        taken = sum(self.done.values())
        expected = sum(self.predicted[name] for name in self.done)
        # stages predicted in milliseconds take what a call costs whatever their size: no evidence
        if expected < SPEED_EVIDENCE or taken <= 0:
            return 1.0
        return min(max(taken / expected, SPEED_LIMITS[0]), SPEED_LIMITS[1])

    @contextlib.contextmanager
    def stage(self, name: str, message: str, estimates_itself: bool = False):
        """A stage that `estimates_itself` (progressive refinement's shots) reports no time left until
        it gives its own: its prediction is a cost model's, and a bar set by it would mislead."""
        self.current, self.current_started = name, time.perf_counter()
        self.waiting = estimates_itself
        self.report(0.0, message)
        token = _pulse.set(self._beat)
        try:
            yield
        finally:
            _pulse.reset(token)
            self.done[name] = self.done.get(name, 0.0) + time.perf_counter() - self.current_started
            self.current = None

    def _beat(self) -> None:
        now = time.perf_counter()
        if self.current is None or now - self.last_report < PULSE_INTERVAL:
            return
        expected = self.predicted.get(self.current, 0.0) * self.speed
        gone = (now - self.current_started) / expected if expected > 0 else 0.0
        self.report(min(gone, PULSE_SHARE), self.last_message)

    def report(self, fraction: float, message: str, details: dict | None = None) -> None:
        """The running stage at `fraction` of itself; `details` "eta": its own seconds left. The
        callback gets the whole's fraction and time left ("eta"), and the stage's own as
        "stage_fraction" and "stage_eta" (None where the stage has no estimate), and its "stage"."""
        if self.progress is None:
            return
        self.last_report, self.last_message = time.perf_counter(), message
        details = dict(details or {})
        details["stage_fraction"], details["stage_eta"] = float(fraction), details.get("eta")  # the stage's own
        total = sum(self.predicted.values())
        done = sum(self.predicted[name] for name in self.done if name != self.current)
        mine = self.predicted.get(self.current, 0.0)
        ahead = sum(seconds for name, seconds in self.predicted.items()
                    if name not in self.done and name != self.current)
        fraction = min(max(float(fraction), 0.0), 1.0)
        own = details.get("eta")
        self.waiting = self.waiting and own is None
        if self.waiting:
            details["eta"], details["stage"] = None, self.current
            self.progress(self.shown, message, details)
            return
        if own is None:
            elapsed = time.perf_counter() - self.current_started
            own = max(mine * self.speed - elapsed, (1.0 - fraction) * mine * self.speed)
        details["eta"] = own + ahead * self.speed
        details["stage"] = self.current
        self.shown = max(self.shown, min((done + fraction * mine) / total, 1.0) if total > 0 else fraction)
        self.progress(self.shown, message, details)

    def within(self, start: float = 0.0, end: float = 1.0) -> ProgressCallback:
        """A callback for a part [start, end] of the running stage (a method's own progress)."""
        return lambda fraction, message, details=None: self.report(start + (end - start) * fraction, message, details)
