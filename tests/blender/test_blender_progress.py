"""What the panel and the status bar say while a bake runs: one estimate, a bar that moves with time,
text that fits; and the last bake's summary wrapped to the panel's width."""

from __future__ import annotations

import math

import blender_support  # noqa: F401  (sets BLENDER_USER_RESOURCES before bpy loads)
import pytest

from radiosity_addon.blender.panel import LABEL_MARGIN, GLYPH_WIDTH, fitted
from radiosity_addon.blender.progress import SETTLING, BakeClock


def progressive_feed(total=20.0, startup=1.0, step=0.2):
    """Reports like progressive refinement's: '1 − unshot' leaps to 0.7 at once and creeps after;
    its own estimate of time left starts far too short and is right later on."""
    t = startup
    while t < total:
        done = (t - startup) / (total - startup)
        fraction = 1 - 0.3 * math.exp(-6 * done)
        eta = (total - t) * (0.1 if t < startup + 0.8 else 1.0)
        yield t, fraction, f"shot {int(100 * t)}, unshot {1 - fraction:.2e} of emitted, ~{eta:.0f} s left", eta
        t += step


def test_the_bar_moves_with_time_and_never_goes_back():
    clock = BakeClock(now=0.0)
    shown = []
    for t, fraction, message, eta in progressive_feed():
        clock.solving(fraction, message, eta, now=t)
        shown.append((t, clock.fraction(now=t), clock.seconds_left(now=t)))
    fractions = [f for _, f, _ in shown]
    assert fractions == sorted(fractions)  # never back
    assert fractions[0] == 0.0  # nothing is promised before the solve has run a while
    # after the first seconds the bar is the elapsed share of the true 20 s, within 10 points
    for t, fraction, left in shown:
        if t > 1.0 + SETTLING + 1.0:
            assert abs(fraction - t / 21.0) < 0.1, (t, fraction)
            assert abs(left - (21.0 - t)) < 2.5, (t, left)
    # between reports it keeps moving
    last = shown[-1][0]
    assert clock.fraction(now=last + 0.1) < clock.fraction(now=last + 0.5)


def test_a_solver_with_its_own_estimate_is_waited_for_not_extrapolated():
    """Progressive refinement's emitters shoot first: '1 − unshot' climbs to 0.9 in the first 30 %
    of a 20 s solve with no estimate of time left (what the real-Blender bake showed: the bar at
    52 % a quarter of the way in); after them its estimate is right."""
    clock = BakeClock(now=0.0)
    shown = []
    for k in range(5, 200):
        t = 0.1 * k
        share = t / 20.0
        fraction, eta = (3 * share, None) if share < 0.3 else (0.9 + 0.1 * (share - 0.3) / 0.7, 20.0 - t)
        clock.solving(min(fraction, 0.9), "shot", eta, now=t, own_estimate=True)
        shown.append((share, clock.fraction(now=t)))
    fractions = [f for _, f in shown]
    assert fractions == sorted(fractions)
    assert max(f for share, f in shown if share < 0.3) == 0.0  # nothing promised by the emitters' pace
    assert max(abs(f - share) for share, f in shown if share > 0.45) < 0.15, shown[::10]  # catching up


def test_a_solver_without_its_own_estimate_is_extrapolated():
    """A solver that reports a fraction only: linear in time here, 10 s in all."""
    clock = BakeClock(now=0.0)
    for k in range(1, 28):
        t = 0.5 + 0.2 * k
        clock.solving((t - 0.5) / 9.5, f"hemi-cubes {k}/50", None, now=t)
        clock.fraction(now=t)  # the panel reads it ten times a second
    assert clock.fraction(now=6.0) == pytest.approx(6.0 / 10.0, abs=0.05)
    for k in range(6, 100):
        clock.fraction(now=0.1 * k)
    clock.laying_out_lightmaps(now=10.0)
    assert clock.stage == "writing lightmaps" and clock.fraction(now=10.2) > 0.9
    # the bar says "finishing"; the stage shows that the lightmaps go on (the panel redraws on a change)
    assert clock.stage_text(now=10.5) == "writing lightmaps"
    assert clock.stage_text(now=12.2) == "writing lightmaps (2 s)" and clock.status_line(now=13.1).count("(3 s)") == 1
    clock.finished()
    assert clock.fraction() == 1.0 and clock.seconds_left() is None


def test_a_longer_estimate_slows_the_bar_down_without_stopping_or_leaping_it():
    """Another program takes the CPU: the solver's estimate of time left jumps from 5 s to 50 s."""
    clock = BakeClock(now=0.0)
    shown = []
    for k in range(10, 300):
        t = 0.1 * k
        clock.solving(0.5, "shot", 10.0 - t if t < 5 else 55.0 - t, now=t)
        shown.append(clock.fraction(now=t))
    steps = [b - a for a, b in zip(shown, shown[1:])]
    assert min(steps[20:]) > 0 and max(steps) < 0.02, (min(steps[20:]), max(steps))
    assert clock.seconds_left(now=29.9) == pytest.approx(25.1, abs=3.0)


def test_one_estimate_in_text_short_enough_for_the_panel():
    clock = BakeClock(now=0.0)
    for t, fraction, message, eta in progressive_feed():
        clock.solving(fraction, message, eta, now=t)
        if t > 3:
            break
    bar, status = clock.bar_text(now=3.0), clock.status_line(now=3.0)
    assert bar.startswith(f"{100 * clock.fraction(now=3.0):.0f}% · about ") and len(bar) <= 24, bar
    assert clock.stage.startswith("shot ") and "left" not in clock.stage  # the solver's own estimate is dropped
    assert status.count("left") == 1, status


@pytest.mark.parametrize("width", [220, 300, 480])
def test_the_summary_wraps_at_its_separators_to_the_panel_width(width):
    summary = "3 channel(s) · occlusion · interreflection · 1 emitter(s) · 1139 shots · 5.2 s"
    lines = fitted(summary, width)
    chars = int((width - LABEL_MARGIN) / GLYPH_WIDTH)
    assert all(len(line) <= chars for line in lines), lines
    assert " · ".join(lines) == summary  # broken at separators, nothing lost
    assert (len(lines) > 1) == (chars < len(summary))


def test_a_word_longer_than_the_panel_is_wrapped_not_cut():
    lines = fitted("x" * 60, 150)
    assert "".join(lines) == "x" * 60 and max(len(line) for line in lines) == int((150 - LABEL_MARGIN) / GLYPH_WIDTH)
