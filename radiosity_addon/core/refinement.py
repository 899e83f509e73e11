"""Adaptive substructuring (Cohen et al. 1986): where the light changes fast across a patch — a
shadow edge, a contact, an emitter a few millimetres from a ceiling — the patch is a poor shooter
(it sends its mean radiosity from everywhere on it) and a poor receiver, so it is split 2 x 2;
smooth regions stay coarse.

The estimate is measured, not guessed: the direct light (lamps and emitters, the few shots that
light a scene first) is shot into S x S elements per patch, and a patch whose elements' light
spreads more than `refine_threshold` of its mean (plus a floor of REFINE_FLOOR of the scene's
mean, so dim corners are not split for noise) is split — if another surface faces it from closer
than its own size, where its light, sent as if uniform, lands wrong (a patch far from everything
is a good enough shooter whatever its spread; the lightmaps recompute the direct light per
texel). That is repeated `refinements` times, then the method solves once on the refined patches.
The probe is the texel pass at the element centres (`shooting.light_at_points`), and after the
first round only at the new children's: a patch a round left alone keeps its light, so a round
costs its shots' visibility maps plus what it split, not the whole scene again.
"""

from __future__ import annotations

import numpy as np

from .scene import Patches, split_patches
from .scene.gaps import OPPOSED_COSINE, covered_centres, distance_to_outline, facing_partners
from .scene.rows import row_labels
from .shooting import MeasuredDirectLight, direct_light_at_elements, patch_scale_shots, same_shots
from .uvspace import patch_material_values

REFINE_FLOOR = 0.05
PROBE_ELEMENTS = 4  # elements per patch side the direct light is measured on
PROBE_PIECES = 8  # the probe's emitters and area lamps in up to N x N pieces (the solve's emitters in 256 in all)
GAP_RESOLUTION = 2.0  # patches facing another surface closely are split down to this many gaps
SMALLEST_PATCH = 1 / 1024  # of the scene's diameter: no split below it
REFINE_MIN_PATCHES = 2000  # the spread rule may add this many patches whatever the scene's size
RIM_GAPS = 3.0  # within this many gaps (plus its size) of a gap's opening, a patch facing across it is split
MIN_CUT = 0.1  # a patch is cut along an outline no nearer than this to its side (no slivers)
OUTLINE_PARALLEL = 0.05  # an outline edge runs along a patch's side when it strays less than this per unit


def near_an_opening(patches: Patches, scene_corners: np.ndarray, rows: np.ndarray, partners: np.ndarray,
                    gaps: np.ndarray) -> np.ndarray:
    """(len(rows),) bool: patches `rows` facing `partners` across `gaps` that lie within their own
    size plus RIM_GAPS gaps of the opening of that gap — the outline of their own surface or of the
    partner's — where the two sides are turned towards each other (not walls meeting at a corner).
    Light trapped in a gap changes fast there (it escapes), and only there."""
    size = np.sqrt(patches.area[rows])
    centre = patches.center[rows]
    own = distance_to_outline(centre, scene_corners[patches.surface[rows]])
    theirs = distance_to_outline(centre, scene_corners[patches.surface[partners]])
    opposed = np.einsum("nd,nd->n", patches.normal[rows], patches.normal[partners]) < -OPPOSED_COSINE
    return opposed & (np.minimum(own, theirs) < size + RIM_GAPS * gaps)


def outline_cuts(patches: Patches, rows: np.ndarray, outlines: np.ndarray) -> np.ndarray:
    """(len(rows), 2) the parameters (s, t) at which to cut the quads `rows` 2 x 2 so that no
    child lies astride an edge of their `outlines` (len(rows), 4, 3; an emitter's outline seen
    across a gap, say): along each direction, where an outline edge running along the other
    direction crosses the patch nearest its middle; the middle where none does or the cut would
    leave a sliver (within MIN_CUT of a side; the next round cuts the smaller child there).
    A ceiling patch astride the outline of an emitter 5 mm under it is half in the trapped light
    and half out: its mean, sent into the room from its outer half, makes the room too bright."""
    corners = patches.corners[rows]
    along_s = 0.5 * (corners[:, 1] - corners[:, 0] + corners[:, 2] - corners[:, 3])
    along_t = 0.5 * (corners[:, 3] - corners[:, 0] + corners[:, 2] - corners[:, 1])
    basis = np.stack([along_s, along_t], axis=1)  # (n, 2, 3)
    gram = np.einsum("nkd,njd->nkj", basis, basis)
    projected = np.einsum("ncd,njd->ncj", outlines - corners[:, :1], basis)  # (n, 4, 2)
    st = np.linalg.solve(gram[:, None], projected[..., None])[..., 0]  # outline corners in (s, t)
    start, delta = st, np.roll(st, -1, axis=1) - st
    cuts = np.full((len(rows), 2), 0.5)
    for axis in (0, 1):
        other = 1 - axis
        value = start[..., axis] + 0.5 * delta[..., axis]
        low = np.minimum(start[..., other], start[..., other] + delta[..., other])
        high = np.maximum(start[..., other], start[..., other] + delta[..., other])
        usable = ((np.abs(delta[..., axis]) <= OUTLINE_PARALLEL * np.abs(delta[..., other])) & (low < 1) & (high > 0)
                  & (value > MIN_CUT) & (value < 1 - MIN_CUT))
        offset = np.where(usable, np.abs(value - 0.5), np.inf)
        best = offset.argmin(axis=1)
        found = np.isfinite(offset[np.arange(len(rows)), best])
        cuts[found, axis] = value[np.arange(len(rows)), best][found]
    return cuts


def patches_to_refine(patches: Patches, element_light: np.ndarray, threshold: float, min_size: float,
                      scene_corners: np.ndarray | None = None,
                      emitter_gap_resolution: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """(P,) float priority of each patch's split (0: not split; the gap rule's splits first, then
    the largest patches) and (P, 2) where to cut each (`split_patches`' `at`: the middle, or
    along the outline across an emitter's gap, `outline_cuts`): patches that another surface faces from closer than their size (they are split
    until they are GAP_RESOLUTION times the gap: a patch sends its light as if uniform, and across a
    gap that light lands within a gap's width), that are still larger than `min_size`, and either
    - whose elements' light spreads more than `threshold` of their mean (plus the floor), or
    - (given the surfaces' corners) that face an emitter across the gap or emit into it and lie
      near its opening (`near_an_opening`), down to `emitter_gap_resolution` times the gap: light
      trapped between an emitter's back and a ceiling a few millimetres above bounces between
      them many times, so the fall of the light towards the opening, where it escapes, must be
      resolved on both sides even where no direct light changes (the emitter's back gets none).
      Unresolved, the Cornell box as Blender exports it (its light 5 mm under the ceiling) bakes
      too bright everywhere: the cavity's gain is overestimated and the whole room gets it."""
    light = np.asarray(element_light, dtype=np.float64).sum(axis=-1)  # (P, S, S)
    mean = light.mean(axis=(1, 2))
    area = patches.area
    floor = REFINE_FLOOR * float((area * mean).sum() / area.sum())
    spread = light.max(axis=(1, 2)) - light.min(axis=(1, 2))
    size = np.sqrt(area)
    uneven = spread > threshold * (mean + floor)
    emits = np.any(patches.emission > 0, axis=1)
    lit = (mean > floor) | emits
    candidates = np.flatnonzero((size > min_size) & (uneven | (lit if scene_corners is not None else False)))
    gaps, partners = facing_partners(patches, candidates)
    close = size[candidates] > GAP_RESOLUTION * gaps
    priority = np.zeros(len(patches))
    cuts = np.full((len(patches), 2), 0.5)
    spread_rule = candidates[close & uneven[candidates]]
    priority[spread_rule] = area[spread_rule]
    if scene_corners is not None:
        # a patch whose centre a small surface close above hides gathers that shadow as its whole light
        large = np.flatnonzero(size > min_size)
        surface_size = np.linalg.norm(scene_corners - scene_corners.mean(axis=1, keepdims=True), axis=2).max(axis=1)
        hidden = large[covered_centres(patches, large, surface_size)]
        priority[hidden] = np.maximum(priority[hidden], area[hidden])
        cavity = (size[candidates] > emitter_gap_resolution * gaps) & (emits[candidates] | emits[np.maximum(partners, 0)])
        rows = candidates[cavity]
        opening = near_an_opening(patches, scene_corners, rows, partners[cavity], gaps[cavity])
        priority[rows[opening]] = np.inf
        quads = opening & ~patches.is_triangle[rows]
        cuts[rows[quads]] = outline_cuts(patches, rows[quads],
                                         scene_corners[patches.surface[partners[cavity][quads]]])
    return priority, cuts


def added_by_splitting(patches: Patches, rows: np.ndarray) -> np.ndarray:
    """Patches each split of `rows` adds: three, six when the patch's back is simulated too (a
    back is split with its front)."""
    paired = (patches.twin[rows] >= 0) | (patches.back_of[rows] >= 0)
    return np.where(paired, 6, 3)


def within_budget(patches: Patches, priority: np.ndarray, budget: int | None) -> np.ndarray:
    """(P,) bool: the patches of positive `priority` to split, highest first, so that the patches
    number at most `budget` once split."""
    chosen = np.flatnonzero(priority > 0)
    split = np.zeros(len(patches), dtype=bool)
    if budget is None:
        split[chosen] = True
        return split
    order = np.argsort(-priority[chosen], kind="stable")
    fits = np.cumsum(added_by_splitting(patches, chosen[order])) <= budget - len(patches)
    split[chosen[order[fits]]] = True
    return split


def probe_shooters(scene, patches: Patches, effects, pieces: int = PROBE_PIECES) -> list:
    """The direct light's shots the probe takes (`shooting.patch_scale_shots`)."""
    return patch_scale_shots(scene, patches, effects.occlusion, pieces)


def probe_direct(gpu, scene, patches: Patches, rows: np.ndarray, shooters: list, settings, effects,
                 elements: int) -> tuple[np.ndarray, np.ndarray]:
    """(len(rows), S, S, 3) direct light H at the S x S element centres of the patches `rows` from
    `shooters` (`probe_shooters`) each with its own visibility, and (the same shape) from the sky."""
    with gpu.resources() as res:
        return direct_light_at_elements(res, scene, patches, rows, shooters, settings.visibility,
                                        settings.visibility_res, effects.occlusion, elements,
                                        capacity=settings.batch_shots)



def unchanged_patches(before: Patches, after: Patches) -> np.ndarray:
    """(len(after),) the patch of `before` each patch of `after` is (same surface, side and
    corners), -1 for the new ones (children of a split, backs made anew)."""
    def keys(patches):
        return np.concatenate([patches.corners.reshape(len(patches), -1), patches.surface[:, None],
                               patches.is_back[:, None]], axis=1)

    code = row_labels(np.concatenate([keys(before), keys(after)]))
    of_code = np.full(code.max() + 1, -1, dtype=np.int64)
    of_code[code[:len(before)]] = np.arange(len(before))
    return of_code[code[len(before):]]


def refine(gpu, scene, patches: Patches, backs, settings, effects, timer,
           budget: int | None = None, progress=None) -> tuple[Patches, list[int], MeasuredDirectLight | None]:
    """`patches` split where the direct light changes fast, how many were split per round, and the
    direct light the last round measured, on the patches it left alone (None without rounds);
    never more than `budget` patches in all (the hemi-cube method's matrices must fit). The splits
    of the spread rule add at most `settings.refine_budget` times the patches there were (at least
    REFINE_MIN_PATCHES), largest first, so refinement grows linearly with the scene; the gap rule's
    splits (at emitters) come first and are not counted. Each round probes only the patches the
    last one made (`unchanged_patches`), unless the emitters' shots changed (a textured emitter
    split). `progress(fraction, message)` after each round."""
    elements = max(settings.elements, PROBE_ELEMENTS)
    spread_room = max(int(settings.refine_budget * len(patches)), REFINE_MIN_PATCHES)
    refined = []
    shots_light = sky_light = shooters = light_of = None
    for level in range(settings.refinements):
        with timer.stage("refine"):
            now_shooting = probe_shooters(scene, patches, effects, settings.probe_pieces)
            if shots_light is None or not same_shots(shooters, now_shooting):
                shots_light, sky_light = probe_direct(gpu, scene, patches, np.arange(len(patches)), now_shooting,
                                                      settings, effects, elements)
            else:
                fresh = np.flatnonzero(light_of < 0)
                shots_light, sky_light = (kept(values, light_of) for values in (shots_light, sky_light))
                shots_light[fresh], sky_light[fresh] = probe_direct(gpu, scene, patches, fresh, now_shooting, settings,
                                                                    effects, elements)
            shooters, light_of = now_shooting, None
            light = shots_light + sky_light
            min_size = SMALLEST_PATCH * scene.diameter
            priority, cuts = patches_to_refine(patches, light, settings.refine_threshold, min_size, scene.corners,
                                         settings.emitter_gap_resolution)
            gap_rule = np.isinf(priority)
            spread = within_budget(patches, np.where(gap_rule, 0.0, priority), len(patches) + spread_room)
            spread_room -= int(added_by_splitting(patches, np.flatnonzero(spread)).sum())
            split = within_budget(patches, np.where(gap_rule | spread, priority, 0.0), budget)
            if not split.any():
                break
            refined.append(int(split.sum()))
            before, patches = patches, split_patches(patches, split, backs, cuts)
            if progress is not None:
                progress((level + 1) / settings.refinements, f"refinement round {level + 1}: {len(patches)} patches")
            light_of = unchanged_patches(before, patches)
            if scene.material_maps:
                patches.reflectance, patches.emission = patch_material_values(gpu, scene, patches)
    if shots_light is None:
        return patches, refined, None
    known = np.ones(len(patches), dtype=bool) if light_of is None else light_of >= 0
    if light_of is not None:
        shots_light, sky_light = (kept(values, light_of) for values in (shots_light, sky_light))
    return patches, refined, MeasuredDirectLight(shots_light, sky_light, known, shooters, elements)


def kept(values: np.ndarray, light_of: np.ndarray) -> np.ndarray:
    """`values` of the patches before a split, taken over by those it left alone (`unchanged_patches`);
    zeros for the new ones."""
    return np.where((light_of >= 0)[:, None, None, None], values[np.maximum(light_of, 0)], 0.0)
