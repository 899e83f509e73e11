"""Energy accounts of progressive refinement (float64, on the CPU), the ambient term for
previews, and the estimate of the time left."""

from __future__ import annotations

import bisect
import math

import numpy as np

from ..scene import Patches


class EnergyLedger:
    """Power accounts in float64 (RGB): emitted + surplus = absorbed + escaped + unshot.

    A shot's hit fraction is the shooter's form-factor row sum over all elements. In a closed
    scene it should be 1; point-sampled factors make it a little more (near corners) or less
    (along shared edges). The shortfall is booked as escaped, the excess as `surplus`
    (energy the discretization created), so the accounts balance exactly either way.
    """

    def __init__(self, emitted: np.ndarray):
        self.emitted = np.asarray(emitted, dtype=np.float64)
        self.shot = np.zeros(3)
        self.absorbed = np.zeros(3)
        self.reflected = np.zeros(3)
        self.escaped = np.zeros(3)
        self.surplus = np.zeros(3)
        self.pending = None  # power of the shot whose fractions are not yet read back
        self.pending_bounce = False  # whether those shots send reflected light (not emitters' own)
        self.bounce_shot = np.zeros(3)  # what reflected-light shots sent, and of it what hit and was reflected
        self.bounce_hit = np.zeros(3)
        self.bounce_reflected = np.zeros(3)

    def settle(self, fractions: np.ndarray) -> None:
        """Book the pending shots ((K, 3) powers) with their (K, 4) (hit, reflected RGB) fractions."""
        if self.pending is None:
            return
        power, self.pending = np.atleast_2d(self.pending), None
        fractions = np.atleast_2d(fractions)
        hit = fractions[:, :1]
        reflected = np.minimum(fractions[:, 1:4], hit)
        self.shot += power.sum(axis=0)
        self.reflected += (reflected * power).sum(axis=0)
        self.absorbed += ((hit - reflected) * power).sum(axis=0)
        self.escaped += (np.maximum(1.0 - hit, 0.0) * power).sum(axis=0)
        self.surplus += (np.maximum(hit - 1.0, 0.0) * power).sum(axis=0)
        if self.pending_bounce:
            self.bounce_shot += power.sum(axis=0)
            self.bounce_hit += (np.minimum(hit, 1.0) * power).sum(axis=0)
            self.bounce_reflected += (reflected * power).sum(axis=0)

    @property
    def unshot(self) -> np.ndarray:
        return self.emitted + self.reflected - self.shot

    def as_dict(self) -> dict:
        total = lambda v: float(np.sum(v))  # noqa: E731
        return {
            "emitted": total(self.emitted), "absorbed": total(self.absorbed), "escaped": total(self.escaped),
            "surplus": total(self.surplus),
            "unshot": total(self.unshot), "shot": total(self.shot), "reflected": total(self.reflected),
            "rgb": {k: v.tolist() for k, v in (("emitted", self.emitted), ("absorbed", self.absorbed),
                                                 ("escaped", self.escaped), ("unshot", self.unshot))},
        }


def mean_reflectance(patches: Patches) -> np.ndarray:
    """(3,) area-weighted mean reflectance ρ̄."""
    return (patches.area[:, None] * patches.reflectance).sum(axis=0) / patches.area.sum()


def ambient_term(patches: Patches):
    """Cohen et al. 1988: Ambient = R Σ A ΔB / Σ A, R = 1/(1 − ρ̄), as a function of the unshot
    power Σ A ΔB (RGB). For previews only: a preview shows B + ρ · Ambient; the result never
    includes it."""
    scale = 1.0 / (patches.area.sum() * np.maximum(1.0 - mean_reflectance(patches), 1e-6))
    return lambda unshot_power: np.asarray(unshot_power) * scale


def remainder_power(ledger: EnergyLedger, patches: Patches, unshot_power: np.ndarray) -> np.ndarray:
    """(3,) power the power still unshot would deliver to the surfaces, it and all it gives rise
    to: of power U shot, a fraction h lands on surfaces and a fraction r of U is reflected, to be
    shot in turn, so U h / (1 − r) in all, with h and r measured by the reflected-light shots so
    far (Cohen et al. 1988's ambient term is the closed-scene case h = 1, r = ρ̄, its fallback)."""
    unshot_power = np.maximum(np.asarray(unshot_power, dtype=np.float64), 0.0)
    measured = ledger.bounce_shot > 0
    shot = np.where(measured, ledger.bounce_shot, 1.0)
    hit = np.where(measured, ledger.bounce_hit / shot, 1.0)
    reflected = np.where(measured, ledger.bounce_reflected / shot, mean_reflectance(patches))
    return unshot_power * hit / np.maximum(1.0 - reflected, 1e-3)


def remainder_light(power: np.ndarray, recent_light: np.ndarray, element_areas: np.ndarray) -> np.ndarray:
    """(P, S, S, 3) light H that delivers `power` (3,) laid out like `recent_light`, the light the
    last shots gathered: later bounces land where the recent ones did, only more evenly (an even
    ambient term would light what the recent bounces never reach, like a block's side turned to the
    open front). The result is the solve's extrapolation to convergence, not resolved anew in space."""
    recent = np.maximum(recent_light, 0.0)
    delivered = np.einsum("pij,pijc->c", element_areas, recent)
    scale = np.where(delivered > 0, power / np.where(delivered > 0, delivered, 1.0), 0.0)
    return recent * scale


SLOWEST = 0.7  # the most the rate is let fall per doubling of the time (a slow stretch must not blow up the estimate)


def log_rate(history, start: float, end: float) -> float | None:
    """The rate of decrease of log(unshot) between the entries at times `start` and `end`."""
    at = lambda t: history[max(bisect.bisect_right(history, t, key=lambda entry: entry[0]) - 1, 0)]  # noqa: E731
    (t0, u0), (t1, u1) = at(start), at(end)  # times increase: a bisection, not a pass over the history
    if t1 <= t0 or u1 <= 0 or u0 <= u1:
        return None
    return (math.log(u0) - math.log(u1)) / (t1 - t0)


def time_left(history, tolerance: float):
    """Seconds to reach the tolerance from the history of (elapsed, unshot fraction). The rate of
    decrease of log(unshot) falls as the solve goes (the first shots carry most of the energy):
    measured over the last half of the time, and over the quarter before, it gives how much it
    falls per doubling of the time, and the estimate lets it go on falling so (by at most SLOWEST
    per doubling): it errs long rather than short, as a progress bar that never goes back must."""
    if len(history) < 4:
        return None
    now, unshot = history[-1]
    recent = log_rate(history, 0.5 * now, now)
    if recent is None or unshot <= 0:
        return None
    earlier = log_rate(history, 0.25 * now, 0.5 * now)
    slowing = 1.0 if earlier is None else min(1.0, max(SLOWEST, recent / earlier))
    needed = math.log(unshot / tolerance)
    left, span, rate = 0.0, now, recent * slowing
    for _ in range(60):  # doublings of the time: the rate falls by `slowing` in each
        if needed <= 0:
            break
        if rate * span >= needed:
            return left + needed / rate
        needed -= rate * span
        left, span, rate = left + span, 2 * span, rate * slowing
    return max(0.0, left)
