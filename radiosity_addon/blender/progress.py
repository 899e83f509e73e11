"""One estimate of when a bake ends, shown as a bar that moves with time and as time left.

bpy-free. The solver's own fraction says little about time (progressive refinement's "1 −
unshot" is at 65 % after its first shots and creeps through the last 5 %), so the bar is the
elapsed share of the estimated total instead: total = elapsed + the solver's estimate of time
left (or, without one, its fraction extrapolated linearly) + the lightmaps' share. The first
second of a solve is not trusted (progressive refinement's first shots carry most of the energy,
so its early rate promises far too much); later estimates are smoothed, a longer one taken at
once, because the bar never goes back and an estimate too short would stop it.
"""

from __future__ import annotations

import time

LIGHTMAP_SHARE = 0.05  # the lightmap layout takes about this share of the solve's time
SETTLING = 1.0  # seconds of solving before its estimates count
SMOOTHING = 0.3  # weight of a new, shorter estimate of the total against the running one
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

    def solving(self, fraction: float, message: str, eta: float | None, now: float | None = None) -> None:
        """A progress report of the solve: fraction in [0, 1], its message, its own time left."""
        now = time.monotonic() if now is None else now
        if self.solve_started is None:
            self.solve_started = now
        self.stage = message.split(",")[0]  # the progressive message ends in an estimate of its own
        solve_elapsed = now - self.solve_started
        if solve_elapsed < SETTLING:
            return
        if eta is None and fraction >= 0.02:
            eta = solve_elapsed * (1.0 - fraction) / fraction
        if eta is not None:
            self._estimate(now, eta + LIGHTMAP_SHARE * (solve_elapsed + eta))

    def laying_out_lightmaps(self, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        self.stage = "writing lightmaps"
        solve_time = now - (self.solve_started if self.solve_started is not None else self.started)
        self.total = (now - self.started) + LIGHTMAP_SHARE * solve_time  # the solve's part is known now

    def finished(self) -> None:
        self.done = True
        self.stage = "done"

    def _estimate(self, now: float, seconds_left: float) -> None:
        total = (now - self.started) + max(0.0, seconds_left)
        if self.total is None or total > self.total:
            self.total = total
        else:
            self.total += SMOOTHING * (total - self.total)

    def fraction(self, now: float | None = None) -> float:
        if self.done:
            return 1.0
        if self.total is None or self.total <= 0:
            return self.shown
        now = time.monotonic() if now is None else now
        self.shown = max(self.shown, min(MOST_SHOWN, (now - self.started) / self.total))
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
        return f"Radiosity bake {self.bar_text(now)} · {self.stage} · Esc cancels"
