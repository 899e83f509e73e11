"""Our lightmaps against a reference on the same texels (numpy only): the numbers the room
bench and the tests quote.

Lightmaps are {object: (H, W, 4) float}, RGB and coverage in alpha, rows bottom-up as Blender
stores them: texel (t, s) is the lightmap point u = (s + 0.5) / W, v = (t + 0.5) / H. A texel is
compared where both cover it (alpha above one half) and, optionally, where a mask allows it (for
example `inside_box` of the texels' world positions: the texels inside the room).

- texel relative RMS: sqrt(Σ |ours − ref|² / Σ |ref|²) over every compared texel of every object,
  RGB summed; each texel counts once, so objects and faces weigh by their texel count. That is not
  their area: Lightmap Pack gives thin faces several times the texels per m² of large ones (a
  floor slab's sides 4–6× its top). Weights per texel (`rasterize_texels`' areas) make it
  area-weighted.
- object-balanced RMS: the texel relative RMS of each object against its own reference, squared and
  averaged over all compared texels — sqrt(Σ_o n_o E_o / Σ_o n_o), E_o = Σ_o |ours − ref|² / Σ_o |ref|².
  The plain texel RMS weighs a texel by its brightness squared, so a scene's few brightest texels
  decide it: on the Cornell box the ceiling's texels in the 5 mm cavity over the light and the
  light itself hold 99.4 % of Σ |ref|², and every wall and block together 0.6 %. Balanced, each
  object's error counts by its texels whatever its brightness. With the reference's noise (half
  the difference of two seeds' bakes, whose squares estimate the squared noise of their mean), its
  expected share Σ_o |noise|² is taken from each object's Σ_o |ours − ref|² (at least 0 is left):
  the error of ours itself, not of the reference's noise, which on the Cornell box's walls is
  9–13 % per object after 1024 samples.
- object means: per object and channel, the mean over its compared texels, and the relative
  error of ours against the reference's, per channel and of the RGB sum; the worst object is the
  one whose RGB-sum error is largest in magnitude.
"""

from __future__ import annotations

import numpy as np

COVERED = 0.5  # alpha above which a texel counts as covered


def covered(image: np.ndarray) -> np.ndarray:
    return image[..., 3] > COVERED


def common_texels(ours: dict, reference: dict, masks: dict | None = None) -> dict:
    """{object: bool (H, W)} for the objects both have: covered by both (and inside the mask)."""
    common = {}
    for name in sorted(set(ours) & set(reference)):
        if ours[name].shape != reference[name].shape:
            raise ValueError(f"{name}: our lightmap is {ours[name].shape[:2]}, the reference"
                             f" {reference[name].shape[:2]}: bake the reference at our sizes")
        both = covered(ours[name]) & covered(reference[name])
        common[name] = both & masks[name] if masks is not None and name in masks else both
    return common


def _sum_of_squares(images: dict, texels: dict, weights: dict | None = None) -> float:
    total = 0.0
    for name, mask in texels.items():
        squares = (images[name][..., :3][mask] ** 2).sum(axis=-1)
        if weights is not None:  # a texel without a weight (NaN: rasterize_texels missed its centre) counts 0
            squares = squares * np.nan_to_num(weights[name][mask], nan=0.0)
        total += float(squares.sum())
    return total


def texel_relative_rms(ours: dict, reference: dict, texels: dict, weights: dict | None = None) -> float:
    """sqrt(Σ w |ours − ref|² / Σ w |ref|²), RGB, over the `texels` (common_texels) of all objects;
    w = 1 (each texel once) unless `weights` {object: (H, W)} are given (e.g. texel areas; NaN counts 0)."""
    difference = {name: ours[name] - reference[name] for name in texels}
    scale = _sum_of_squares(reference, texels, weights)
    return float(np.sqrt(_sum_of_squares(difference, texels, weights) / scale)) if scale > 0 else float("nan")


def channel_means(images: dict, texels: dict) -> dict:
    """{object: mean RGB (3,)} over each object's `texels` (objects with at least one)."""
    return {name: images[name][..., :3][mask].mean(axis=0) for name, mask in texels.items() if mask.any()}


def object_errors(ours: dict, reference: dict, texels: dict) -> dict:
    """{object: {"ours", "reference" (mean RGB), "relative" (per channel, NaN where the reference's
    mean is 0), "relative_rgb" (of the RGB sums), "rms" (the object's own texel relative RMS), "texels"}}."""
    mine, theirs = channel_means(ours, texels), channel_means(reference, texels)
    errors = {}
    for name in theirs:
        difference = mine[name] - theirs[name]
        relative = np.divide(difference, theirs[name], out=np.full(3, np.nan), where=theirs[name] > 0)
        total = theirs[name].sum()
        errors[name] = {"ours": mine[name], "reference": theirs[name], "relative": relative,
                        "relative_rgb": float(difference.sum() / total) if total > 0 else float("nan"),
                        "rms": texel_relative_rms(ours, reference, {name: texels[name]}),
                        "texels": int(texels[name].sum())}
    return errors


def worst_object(errors: dict) -> tuple[str, float]:
    """(object, relative RGB error) of the object whose mean is off the most."""
    finite = {name: e["relative_rgb"] for name, e in errors.items() if np.isfinite(e["relative_rgb"])}
    name = max(finite, key=lambda n: abs(finite[n]))
    return name, finite[name]


def object_balanced_rms(ours: dict, reference: dict, texels: dict, noise: dict | None = None) -> float:
    """sqrt(Σ_o n_o E_o / Σ_o n_o) over the objects with `texels` (n_o of them) and a reference not
    all black: E_o = Σ |ours − ref|² / Σ |ref|² over the object's texels, RGB; with `noise` (the
    reference's, `reference_with_noise`), E_o = max(Σ |ours − ref|² − Σ |noise|², 0) / Σ |ref|²."""
    total = count = 0.0
    for name, mask in texels.items():
        scale = _sum_of_squares(reference, {name: mask})
        if not mask.any() or scale <= 0:
            continue
        squares = _sum_of_squares({name: ours[name] - reference[name]}, {name: mask})
        if noise is not None:
            squares = max(squares - _sum_of_squares(noise, {name: mask}), 0.0)
        total += int(mask.sum()) * squares / scale
        count += int(mask.sum())
    return float(np.sqrt(total / count)) if count else float("nan")


def relative_noise(noise: dict, reference: dict, texels: dict) -> float:
    """The reference's own noise (half the difference of two seeds' bakes) as a texel relative RMS,
    sqrt(Σ |noise|² / Σ |ref|²): the floor under which no error against it can be measured."""
    return float(np.sqrt(_sum_of_squares(noise, texels) / _sum_of_squares(reference, texels)))


def compare(ours: dict, reference: dict, inside: dict | None = None, weights: dict | None = None,
            noise: dict | None = None) -> dict:
    """The bench's comparison: texel RMS over all common texels and over those `inside`, the
    object-balanced RMS over all (and, given the reference's `noise`, with its noise taken out:
    "balanced_bias"), each object's means and errors, and the worst object (over all common
    texels). With `weights` (texel areas, say) the texel RMS weigh texels by them instead of
    counting each once."""
    everywhere = common_texels(ours, reference)
    errors = object_errors(ours, reference, everywhere)
    result = {"texel_rms": texel_relative_rms(ours, reference, everywhere, weights), "objects": errors,
              "balanced_rms": object_balanced_rms(ours, reference, everywhere),
              "worst_object": worst_object(errors), "texels": int(sum(m.sum() for m in everywhere.values())),
              "weighting": "texel count" if weights is None else "given weights"}
    if noise is not None:
        result["balanced_bias"] = object_balanced_rms(ours, reference, everywhere, noise)
    if inside is not None:
        within = common_texels(ours, reference, inside)
        result["texel_rms_inside"] = texel_relative_rms(ours, reference, within, weights)
        result["texels_inside"] = int(sum(m.sum() for m in within.values()))
    return result


# ---------------------------------------------------------------- where the texels are

def rasterize_texels(uv: np.ndarray, world: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Where each texel centre that a triangle covers lies, and how much surface it stands for:
    (positions (H, W, 3) interpolated from the triangle's corners, areas (H, W) in world units²:
    the triangle's world area over its UV area, per texel), NaN where no triangle covers the
    centre. `uv` (T, 3, 2) lightmap UVs, `world` (T, 3, 3) world corners."""
    uv = np.asarray(uv, dtype=np.float64)
    world = np.asarray(world, dtype=np.float64)
    pixel = uv * np.array([width, height]) - 0.5  # texel centres at integers
    low = np.clip(np.ceil(pixel.min(axis=1)), 0, [width - 1, height - 1]).astype(np.int64)
    high = np.clip(np.floor(pixel.max(axis=1)), -1, [width - 1, height - 1]).astype(np.int64)
    spans = np.maximum(high - low + 1, 0)  # (T, 2) texel columns and rows of each bounding box
    counts = spans[:, 0] * spans[:, 1]
    triangle = np.repeat(np.arange(len(uv)), counts)
    offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    columns = low[triangle, 0] + offset % spans[triangle, 0]
    rows = low[triangle, 1] + offset // spans[triangle, 0]
    a, b, c = (pixel[triangle, k] for k in range(3))
    point = np.stack([columns, rows], axis=1).astype(np.float64)

    def cross(p, q, r):  # twice the signed area of p, q, r
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    area = cross(a, b, c)  # in texels, doubled
    with np.errstate(divide="ignore", invalid="ignore"):
        weights = np.stack([cross(b, c, point), cross(c, a, point), cross(a, b, point)], axis=1) / area[:, None]
        edges = world[:, 1:] - world[:, :1]
        per_texel = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)[triangle] / np.abs(area)
    inside = (np.abs(area) > 0) & np.all(weights >= -1e-9, axis=1)
    positions = np.full((height, width, 3), np.nan)
    positions[rows[inside], columns[inside]] = np.einsum("ik,ikj->ij", weights[inside], world[triangle[inside]])
    areas = np.full((height, width), np.nan)
    areas[rows[inside], columns[inside]] = per_texel[inside]
    return positions, areas


def inside_box(positions: np.ndarray, low, high, margin: float = 0.01) -> np.ndarray:
    """Texels whose position lies in the box [low, high] grown by `margin` (NaN positions: outside)."""
    low = np.asarray(low, dtype=np.float64) - margin
    high = np.asarray(high, dtype=np.float64) + margin
    with np.errstate(invalid="ignore"):
        return np.all((positions >= low) & (positions <= high), axis=-1)


def without_reference_noise(error: float, noise: float) -> float:
    """A texel RMS against a converged reference, estimated from one against a noisy reference: the
    reference's own relative noise `noise` (`relative_noise`), whose square is its expected share
    of the squared error, taken out (at least 0 is left)."""
    return float(np.sqrt(max(error * error - noise * noise, 0.0)))


def cycles_to_reach(error: float, rows: list[tuple[int, float, float]]) -> dict | None:
    """What Cycles needs for `error`, from its rows (samples, seconds, error) of one run: the
    samples between the two rows whose errors bracket it, interpolated as a power law (error ∝
    samples^−a between them, a straight line in log–log), and the seconds at those samples,
    linear in the samples between the same rows (a bake's time is a fixed part plus one per
    sample). {"samples", "seconds", "between": (n0, n1)}, or None when no two rows bracket it."""
    rows = sorted(rows)
    for (n0, t0, e0), (n1, t1, e1) in zip(rows, rows[1:]):
        if e1 < e0 and e1 <= error <= e0:
            samples = n0 * (n1 / n0) ** (np.log(e0 / error) / np.log(e0 / e1))
            seconds = t0 + (samples - n0) / (n1 - n0) * (t1 - t0)
            return {"samples": float(samples), "seconds": float(seconds), "between": (n0, n1)}
    return None
