"""The form factors to the brightest reflectors, shot instead of rasterized.

A hemi-cube samples what its centre sees at its pixels' resolution: a small, very bright patch —
the ceiling in the 5 mm cavity over the Cornell box's light, lit by the light's back — seen
through a slit a few millimetres high covers a pixel or none, so a wall below gets its light
several times over or not at all (at 32 pixels the back wall's top row shows bright blotches). The
linear solve then carries that error everywhere. The columns of F for such patches are
recomputed the other way round: each bright patch shoots a unit radiosity with its own
visibility map (`visibility_res` pixels, at most COLUMN_VISIBILITY_RES; the exact
point-to-polygon kernel) to COLUMN_POINTS x
COLUMN_POINTS points of every receiving patch (the texel pass, each shot's factor kept apart:
`TexelReceivers(columns=...)`, a batch of up to 32 shots a pass), and the element means replace the
hemi-cube's entries — where the receiving patch's centre is far (more than FAR_SIZES times the
bright patch's size away) and the hemi-cube saw little of the patch (less than WELL_SAMPLED: at 32
pixels about 8 pixels at the top face's centre, 30 on average). The pixels the hemi-cube gave
the patch wrongly are not handed to what lies behind it, so a row's sum moves by what was aliased
(unbiased on average; it was as wrong the other way). Near,
the hemi-cube is right and the shot is not: the ceiling's patches shooting at the light's back
5 mm away left the cavity dark.

Bright: the light a patch reflects straight from the direct light, ρ D, at least BRIGHT_RATIO
times the area-weighted mean over the reflecting patches; the brightest MAX_BRIGHT_PATCHES of
them — when together they reflect at least MIN_POWER_SHARE of all the power reflected, else none:
their aliasing moves that share of the light at most. A scene lit evenly has none, and pays nothing.

What it buys, measured: docs/benchmarks.md, "Why the presets hold these values".
"""

from __future__ import annotations

import numpy as np

from ..gpu import GPU
from ..scene import Patches, Scene
from ..shooting import PatchShooters, TexelReceivers, element_areas, surface_visibility
from ..shooting.sky import element_frames

BRIGHT_RATIO = 4.0
MAX_BRIGHT_PATCHES = 96  # enough for the Cornell box's cavity: fewer left its error where it was
COLUMN_POINTS = 2
# the columns' shots' visibility at most this: their receivers are far (FAR_SIZES) and each
# element's light is an average, so a finer map costs time and changes nothing
COLUMN_VISIBILITY_RES = 128
WELL_SAMPLED = 0.01
FAR_SIZES = 8.0
MIN_POWER_SHARE = 0.2


def bright_patches(patches: Patches, reflected: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The patches among `rows` whose `reflected` (P, 3) light, summed over RGB, is at least
    BRIGHT_RATIO times the area-weighted mean over `rows`: the MAX_BRIGHT_PATCHES brightest, if
    they reflect at least MIN_POWER_SHARE of the power all `rows` reflect (else none)."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    level = reflected[rows].sum(axis=1)
    mean = float((patches.area[rows] * level).sum() / patches.area[rows].sum())
    bright = rows[level >= BRIGHT_RATIO * mean] if mean > 0 else rows[:0]
    order = np.argsort(-reflected[bright].sum(axis=1), kind="stable")
    bright = np.sort(bright[order[:MAX_BRIGHT_PATCHES]])
    power = float((patches.area[bright] * reflected[bright].sum(axis=1)).sum())
    total = float((patches.area[rows] * level).sum())
    return bright if power >= MIN_POWER_SHARE * total else bright[:0]


def shot_columns(gpu: GPU, scene: Scene, patches: Patches, columns: np.ndarray, rows: np.ndarray, elements: int,
                 points: int, visibility: str, visibility_res: int, occlusion: bool) -> np.ndarray:
    """(len(rows) · S², len(columns)) float32: the form factor from every element of the patches
    `rows` to each patch of `columns`, as the mean over its share of `points` x `points` points
    of its patch of the factor of a shot from that patch (its visibility map, the exact kernel)."""
    k = max(1, -(-points // elements))
    per_patch = (elements * k) ** 2
    frames = element_frames(patches, elements * k, rows)
    owners = np.repeat(rows, per_patch)
    result = np.zeros((len(rows) * per_patch, len(columns)), dtype=np.float64)
    if len(rows) and len(columns):
        shooters = PatchShooters(patches)
        with gpu.resources() as res:
            shots = surface_visibility(res, scene, patches, visibility_res, visibility, occlusion)
            receivers = TexelReceivers(res, frames[0], patches.normal[owners], patches.plane[owners],
                                       "exact", shots, columns=len(columns))
            receivers.shoot_all([shooters.shooter(int(p), np.ones(3)) for p in columns])
            result = receivers.read_columns()
    areas = element_areas(patches, elements * k)[rows]  # (R, S k, S k)
    blocks = result.reshape(len(rows), elements, k, elements, k, len(columns))
    weights = areas.reshape(len(rows), elements, k, elements, k)[..., None]
    means = (blocks * weights).sum(axis=(2, 4)) / weights.sum(axis=(2, 4))
    return means.reshape(len(rows) * elements * elements, len(columns)).astype(np.float32)


def shoot_bright_columns(gpu: GPU, scene: Scene, patches: Patches, element_rows: np.ndarray, rows: np.ndarray,
                         elements: int, reflected: np.ndarray, settings) -> np.ndarray:
    """Replace, in `element_rows` (len(rows) · S², P; `form_factors.element_form_factors`), the
    far, thinly sampled entries of the columns of the bright patches (`bright_patches` of
    `reflected`, ρ D (P, 3)) by their shot values; returns those patches."""
    bright = bright_patches(patches, reflected, rows)
    if len(bright) == 0:
        return bright
    shot = shot_columns(gpu, scene, patches, bright, rows, elements, COLUMN_POINTS, settings.visibility,
                        min(settings.visibility_res, COLUMN_VISIBILITY_RES), True)
    rasterized = element_rows[:, bright]
    receiver = np.repeat(patches.center[rows], elements * elements, axis=0)
    distance = np.linalg.norm(receiver[:, None] - patches.center[bright][None], axis=2)
    far = distance > FAR_SIZES * np.sqrt(patches.area[bright])[None]
    element_rows[:, bright] = np.where(far & (rasterized < WELL_SAMPLED), shot, rasterized)
    return bright
