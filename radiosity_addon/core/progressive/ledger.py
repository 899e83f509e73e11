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


def ambient_term(patches: Patches):
    """Cohen et al. 1988: Ambient = R Σ A ΔB / Σ A, R = 1/(1 − ρ̄), as a function of the unshot
    power Σ A ΔB (RGB). For previews only: a preview shows B + ρ · Ambient; the result never
    includes it."""
    area = patches.area
    mean_reflectance = (area[:, None] * patches.reflectance).sum(axis=0) / area.sum()
    scale = 1.0 / (area.sum() * np.maximum(1.0 - mean_reflectance, 1e-6))
    return lambda unshot_power: np.asarray(unshot_power) * scale


def time_left(history, tolerance: float):
    """Seconds to reach the tolerance, from the rate of decrease of log(unshot) over the last half
    of the time solved so far. The rate falls as the solve goes (the first shots carry most of the
    energy), so a window of the last few shots, early on all of them fast, promises far too little:
    measured on the Cornell box it said a third of the real total at a fifth of the way, where the
    last half's rate is within 10 % from a fifth of the way on."""
    if len(history) < 4:
        return None
    t1, u1 = history[-1]
    halfway = bisect.bisect_right(history, 0.5 * t1, key=lambda entry: entry[0])  # times increase
    t0, u0 = history[max(halfway - 1, 0)]
    if t1 <= t0 or u1 <= 0 or u0 <= u1:
        return None
    rate = (math.log(u0) - math.log(u1)) / (t1 - t0)
    return max(0.0, (math.log(u1) - math.log(tolerance)) / rate)
