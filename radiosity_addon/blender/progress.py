"""One estimate of when a bake ends, shown as a bar that moves with time and as time left.

bpy-free. The solver's own fraction says little about time (progressive refinement's "1 −
unshot" leaps with its first shots and creeps through the last few per cent), so the bar shows the
elapsed share of the estimated total instead: total = elapsed + the solver process's estimate of
the job's time left (every stage of the solve and the lightmaps: core.timing.StagePlan; without
one, its fraction extrapolated linearly), smoothed over a few seconds. The first second of a solve
is not trusted (a prediction made before the solve has measured this machine). What the bake does
before its solver starts (the export, Cycles' material bakes) is shown as its stage.

The estimate changes as the solve goes (and as other programs take the CPU), and a bar set to
elapsed / total would then stop or leap. So the bar moves at the speed that reaches the end when
the estimate says, and catches up within a couple of seconds when it is behind elapsed / total:
it never stops, never leaps and never goes back.
"""

from __future__ import annotations

import math
import time

SETTLING = 1.0  # seconds of solving before its estimates count
SMOOTHING = 3.0  # seconds over which the estimate of the total follows the solver's
CATCH_UP = 2.0  # seconds in which a bar behind elapsed / total closes the distance
MOST_SHOWN = 0.99  # the bar stops short of 100 % until the result is in


def time_left_text(seconds: float) -> str:
    if seconds < 1.5:
        return "finishing"
    if seconds < 100:
        return f"about {seconds:.0f} s left"
    return f"about {seconds / 60:.0f} min left"


class BakeClock:
    """Fed with the solver's progress; read by the panel, the status bar and scripts."""

    def __init__(self, now: float | None = None):
        self.started = time.monotonic() if now is None else now
        self.stage = "starting the solver"
        self.total: float | None = None  # estimated seconds from start to end
        self.solve_started: float | None = None
        self.shown = 0.0
        self.done = False
        self._estimated_at: float | None = None
        self._shown_at: float | None = None
        self._lightmaps_started: float | None = None

    def solving(self, fraction: float, message: str, eta: float | None, now: float | None = None,
                own_estimate: bool = False) -> None:
        """A progress report of the solver process: fraction in [0, 1], its message, the job's time
        left. A solver with `own_estimate` is waited for while its `eta` is None: its fraction is
        never extrapolated (progressive refinement's emitters take it to ~0.9 in a share of the time
        that depends on the scene)."""
        now = time.monotonic() if now is None else now
        if self.solve_started is None:
            self.solve_started = now
        self.stage = message.split(",")[0]  # the progressive message ends in an estimate of its own
        solve_elapsed = now - self.solve_started
        if solve_elapsed < SETTLING:
            return
        if eta is None and not own_estimate and fraction >= 0.02:
            eta = solve_elapsed * (1.0 - fraction) / fraction
        if eta is not None:
            self._estimate(now, eta)

    def preparing(self, stage: str) -> None:
        """What the bake does before its solver runs (exporting, Cycles' material bakes)."""
        self.stage = stage

    def laying_out_lightmaps(self, now: float | None = None) -> None:
        """The solve is over; the lightmaps are made (the solver goes on reporting their time left)."""
        now = time.monotonic() if now is None else now
        self.stage = "writing lightmaps"
        self._lightmaps_started = now

    def stage_text(self, now: float | None = None) -> str:
        """The stage, with the seconds the lightmaps have taken so far: their time is predicted, and a
        bar at "finishing" must still show that the bake goes on."""
        if self._lightmaps_started is None or self.done:
            return self.stage
        now = time.monotonic() if now is None else now
        seconds = now - self._lightmaps_started
        return self.stage if seconds < 1.0 else f"{self.stage} ({seconds:.0f} s)"

    def finished(self) -> None:
        self.done = True
        self.stage = "done"

    def _estimate(self, now: float, seconds_left: float) -> None:
        total = (now - self.started) + max(0.0, seconds_left)
        if self.total is None:
            self.total = total
        else:
            weight = 1.0 - math.exp(-max(0.0, now - self._estimated_at) / SMOOTHING)
            self.total += weight * (total - self.total)
        self._estimated_at = now

    def fraction(self, now: float | None = None) -> float:
        if self.done:
            return 1.0
        now = time.monotonic() if now is None else now
        step = 0.0 if self._shown_at is None else max(0.0, now - self._shown_at)
        self._shown_at = now
        if self.total is None or self.total <= 0:
            return self.shown
        elapsed = now - self.started
        speed = (MOST_SHOWN - self.shown) / max(self.total - elapsed, 0.5)  # at the end when it says
        behind = min(MOST_SHOWN, elapsed / self.total) - self.shown
        if behind > 0:
            speed = max(speed, behind / CATCH_UP)
        self.shown = min(MOST_SHOWN, self.shown + speed * step)
        return self.shown

    def seconds_left(self, now: float | None = None) -> float | None:
        if self.total is None or self.done:
            return None
        now = time.monotonic() if now is None else now
        return max(0.0, self.total - (now - self.started))

    def bar_text(self, now: float | None = None) -> str:
        """Short enough for the panel at its default width: '42% · about 8 s left'."""
        fraction, left = self.fraction(now), self.seconds_left(now)
        return f"{100 * fraction:.0f}%" + (f" · {time_left_text(left)}" if left is not None else "")

    def status_line(self, now: float | None = None) -> str:
        return f"Radiosity bake {self.bar_text(now)} · {self.stage_text(now)} · Esc cancels"
