"""The settings of a solve and of a lightmap bake, with the one set of defaults that the
command line, the Blender panel and the core share."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from .errors import SolveError

SOLVE_METHODS = ("progressive", "hemicube")  # progressive refinement, or the hemi-cube method (the original)
METHODS = ("auto",) + SOLVE_METHODS  # auto: the one the cost model predicts faster (core/method_choice.py)
SOLVERS = ("jacobi-gpu", "jacobi-cpu", "gauss-seidel")  # linear solvers of the hemi-cube method
VISIBILITY_VARIANTS = ("hemicube", "plain", "tessellated", "search", "guarded")  # visibility.hemisphere.VARIANTS
KERNELS = ("exact", "disk")
SHOOTING_POINTS = ("centroid", "centre")
QUALITIES = ("draft", "good", "final")
# what each quality sets (the dataclass defaults below are "final"'s but for the hemi-cubes, the
# finer ones the analytic tests are written for); the bench measures what each
# costs and reaches (README, "What accuracy costs": on the 4k-triangle room, draft 6.4 % in 14-20 s,
# good 5.1 % in 15-26 s, final 4.6 % in 140-197 s on the 2-core machine of 2026-12-07; on the Cornell box
# 2.5 / 2.2 / 2.1 % texel RMS, 6.6 / 5.3 / 4.9 % object-balanced, in 0.4 / 0.6 / 0.8 s, medians). The
# hemi-cubes: 32 pixels (final: 24), one per patch. They carry only the reflected light (the direct light is measured
# at 4 x 4 points a patch: hemicube/method.py), which is smooth: the emissive-ceiling sample's crate is
# within 1.5 % of Cycles at 16, 32 and 64 pixels (when the hemi-cubes carried the emitters too, 32 pixels
# left it and its light 6-9 % under), the Cornell box 2.5 % at 32 and 64 pixels, 2.9 % at 16; 128 pixels
# and 2 x 2 per patch made the box worse (3.2 %) in 21 s.
# Emitter gaps: 4 (patches facing an emitter across a narrow gap split down to a quarter of it)
# took good from 7.3 to 6.0 % on the room for +22 % time, and from 4.7 to 2.1 % on the box. For
# draft, 4 gaps need the 3e-2 tolerance: a cavity split finer holds light a 5e-2 one leaves unshot
# (the room 9.0 -> 11.9 % with 4 gaps at 5e-2; 7.9 % with 8 gaps at 3e-2; 7.4 % with both, 10 -> 12 s).
# Tolerances per method: progressive, the unshot power left relative to the emitted; hemi-cube,
# the change per sweep relative to max B.
QUALITY_PRESETS = {
    "draft": {"solve": {"patch_size": 1.0, "elements": 1, "refinements": 4, "visibility_res": 256,
                        "hemicube_res": 32, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 0.5,
                        "probe_pieces": 4},
              "tolerance": {"progressive": 3e-2, "hemicube": 1e-3},
              "lightmaps": {"direct_map_resolution": 256, "direct_pieces": 2, "direct_subsamples": 2,
                            "texel_budget": 32768}},
    "good": {"solve": {"patch_size": 1.0, "elements": 1, "refinements": 5, "visibility_res": 256,
                       "hemicube_res": 32, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 0.5,
                       "probe_pieces": 4},
             "tolerance": {"progressive": 2e-2, "hemicube": 1e-5},
             "lightmaps": {"direct_map_resolution": 512, "direct_pieces": 2, "direct_subsamples": 2,
                           "texel_budget": 65536}},
    # good's texel pass takes emitters in 2 x 2 pieces: 4 x 4 gave the 4k room 5.13 % where 2 x 2 gives 5.16 %
    # for 8.1 s of lightmaps instead of 4.4 (the Cornell box 2.2 % either way; the penumbrae alike to the eye).
    # final's texel pass takes emitters in 4 x 4 pieces: 8 x 8 gave the same error on the 4k room
    # (4.6 %) and the Cornell box (2.2 %) for 24 % more time on the room (README). Its probe (which
    # the hemi-cube method's direct light reuses) takes them in 3 x 3 since 2026-12-07: the box's
    # errors the same to the digit (2.14 %, 4.92 % balanced), the room's 4.56 -> 4.58 % and
    # 7.84 -> 7.81 %, 18 shots instead of 32 (draft and good keep 4 x 4: 3 x 3 cost the box's
    # balanced error 0.03 points)
    # final's hemi-cubes are 24 pixels and its sharp texels take 2 x 2 points (32 and 4 x 4 until
    # 2026-12-07): the Cornell box 2.29 -> 2.14 % texel RMS, 4.87 -> 4.91 % balanced, its solve and
    # lightmaps ~0.1 s faster (16 pixels: 2.42 %, 4.98 %); the 4k room (progressive: no hemi-cubes)
    # 4.56 % and 7.84 % balanced either way, its lightmaps 8.5 -> 6.6 s
    "final": {"solve": {"patch_size": 0.5, "elements": 4, "refinements": 5, "visibility_res": 512,
                        "hemicube_res": 24, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 1.0,
                        "probe_pieces": 3},
              "tolerance": {"progressive": 1e-2, "hemicube": 1e-5},
              "lightmaps": {"direct_map_resolution": 1024, "direct_pieces": 4, "direct_subsamples": 2,
                            "sky_directions": 256, "texel_budget": 131072}},
}
DEFAULT_TOLERANCE = QUALITY_PRESETS["final"]["tolerance"]

PATCH_SIZE = 0.5  # scene units (metres): faces longer than this are split into patches
MAX_SPLIT = 64  # patches along one side of a surface in the Patch Size mode
MIN_SKY_DIRECTIONS, MAX_SKY_DIRECTIONS = 16, 4096  # a texel's own sky: from this many directions
TEXEL_DENSITY = 64.0  # lightmap texels per scene unit (metre): 15.6 mm texels
MAX_LIGHTMAP_SIZE = 1024  # texels, the largest side of a lightmap
LIGHTMAP_GUTTER = 2  # texels dilated around every chart, at every mip level
MIN_LIGHTMAP_SIZE = 8
CONTENTS = ("light", "combined")  # what a lightmap holds: the light H arriving (B = E + ρH), or B itself


@dataclass
class SolveSettings:
    method: str = "progressive"  # or hemicube, or auto (what `preset` gives: the cost model picks)
    quality: str = "final"  # the preset the other fields came from (its tolerances when tolerance is None)
    subdiv: int | None = None  # N: every surface split N x N into patches; None: split by patch_size
    patch_size: float = PATCH_SIZE  # with subdiv None: longest patch side in scene units
    elements: int = 4  # S x S elements per patch (progressive), S a power of two
    hemicube_res: int = 128  # pixels across the hemi-cube's top face (the presets: 32)
    hemicube_elements: int = 2  # hemi-cube method: S x S receiving elements (hemi-cubes) per patch (final's: 1)
    solver: str = "gauss-seidel"  # fewer sweeps than Jacobi (docs/architecture.md: measured on llvmpipe)
    tolerance: float | None = None  # None: the method's default
    max_iterations: int = 100_000  # linear solvers
    max_shots: int | None = None  # progressive; None: as many as the tolerance needs
    visibility: str = "hemicube"  # progressive: hemicube (batched) | plain | tessellated | search | guarded
    kernel: str = "exact"  # progressive: exact | disk
    visibility_res: int = 512  # progressive: pixels across a visibility map (a hemi-cube's unfolded cross)
    batch_shots: int = 32  # progressive: shooters per pass at most (hemi-cube visibility)
    complete_remainder: bool = True  # progressive: the light the power unshot at the stop would deliver, added (laid out like the last shots')
    shoot_from: str = "centroid"  # progressive: visibility map from the unshot power's centroid | centre
    shooter_clusters: int = 2048  # progressive: with more patches than this, weak ones shoot in about this many clusters (0: never)
    memory_limit_bytes: int = 2 << 30  # hemi-cube form-factor matrix guard
    skip_unneeded: bool = True  # simulate only the effects the scene calls for (scene.analysis)
    refinements: int = 5  # rounds of splitting patches where the direct light changes fast, before the solve
    refine_threshold: float = 0.5  # split a patch whose light spreads more than this fraction of its mean
    emitter_gap_resolution: float = 4.0  # split patches across a narrow gap from an emitter down to this many gaps
    refine_budget: float = 1.0  # the spread rule's splits add at most this many times the patches there were
    probe_pieces: int = 8  # refinement's probe: emitters and area lamps in up to N x N pieces

    @classmethod
    def preset(cls, quality: str = "good", **given) -> "SolveSettings":
        """The settings of a quality preset, with the fields in `given` set as given."""
        if quality not in QUALITY_PRESETS:
            raise SolveError(f"unknown quality '{quality}' (choose {', '.join(QUALITIES)})")
        return cls(**(QUALITY_PRESETS[quality]["solve"] | {"method": "auto", "quality": quality} | given))

    @property
    def effective_tolerance(self) -> float:
        """The tolerance given, or the quality's for this method (an auto method is resolved first)."""
        if self.tolerance is not None:
            return self.tolerance
        return QUALITY_PRESETS[self.quality]["tolerance"]["progressive" if self.method == "auto" else self.method]

    def validate(self) -> None:
        """Refuse settings no solve can use, with a message naming the setting."""
        choices = {"method": METHODS, "quality": QUALITIES, "solver": SOLVERS, "visibility": VISIBILITY_VARIANTS,
                   "kernel": KERNELS, "shoot_from": SHOOTING_POINTS}
        for name, allowed in choices.items():
            value = getattr(self, name)
            if value not in allowed:
                raise SolveError(f"unknown {name.replace('_', ' ')} '{value}' (choose {', '.join(allowed)})")
        if self.subdiv is not None and self.subdiv < 1:
            raise SolveError("subdivision must be at least 1")
        if self.subdiv is None and not (math.isfinite(self.patch_size) and self.patch_size > 0):
            raise SolveError(f"patch size must be positive, got {self.patch_size}")
        if self.elements < 1 or self.elements & (self.elements - 1):
            raise SolveError("elements per patch must be a power of two (1, 2, 4, 8, ...)")
        if not 1 <= self.hemicube_elements <= 8:
            raise SolveError("hemi-cube elements per patch side must lie between 1 and 8")
        if self.hemicube_res < 8 or self.hemicube_res % 2:
            raise SolveError("hemi-cube resolution must be an even number of at least 8")
        if not 16 <= self.visibility_res <= 8192:
            raise SolveError("visibility map resolution must lie between 16 and 8192 pixels")
        if not 0 < self.effective_tolerance < 1:
            raise SolveError("tolerance must lie between 0 and 1")
        if not 1 <= self.batch_shots <= 64:
            raise SolveError("shooters per pass must lie between 1 and 64")
        if self.shooter_clusters < 0:
            raise SolveError("shooter clusters must not be negative (0: every patch shoots alone)")
        if not 0 <= self.refinements <= 8 or not self.refine_threshold > 0:
            raise SolveError("refinements must lie between 0 and 8, the refine threshold above 0")
        if not self.refine_budget >= 0:
            raise SolveError("the refine budget must not be negative")
        if not 1 <= self.probe_pieces <= 16:
            raise SolveError(f"probe pieces per side must be 1..16, got {self.probe_pieces}")
        if not self.emitter_gap_resolution >= 1:
            raise SolveError("the emitter gap resolution must be at least 1 (patches split down to that many gaps)")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class LightmapSettings:
    texel_density: float = TEXEL_DENSITY  # texels per scene unit; 0: automatic (`texel_budget`)
    max_size: int = MAX_LIGHTMAP_SIZE  # cap on width and height
    resolution_overrides: dict = field(default_factory=dict)  # object name -> side (or (w, h)); 0 = density
    power_of_two: bool = False  # round sizes up to powers of two
    gutter: int = LIGHTMAP_GUTTER
    content: str = "light"  # "light": H, shown as emission + albedo x lightmap; "combined": B = E + ρH
    direct_per_texel: bool = True  # lamps' and emitters' light recomputed at every texel (sharp shadows)
    direct_map_resolution: int = 1024  # pixels across the visibility maps of that direct light, at most (fewer where
    # a pixel at the scene's diameter would still be finer than a texel: lightmap.direct.matched_map_resolution)
    direct_pieces: int = 8  # emissive polygons and area lamps shoot that light in up to N x N pieces (penumbrae)
    direct_subsamples: int = 4  # where that light is sharp, a texel takes the mean of N x N points over its square (1: its centre)
    sky_directions: int = 0  # the sky's light recomputed at every texel from N directions (0: the elements' interpolated)
    # with texel_density 0, the density that spreads this many texels over the baked surfaces, and
    # never under TEXEL_DENSITY: a small scene gets as many texels as the preset's quality asks
    texel_budget: int = 65536

    @classmethod
    def preset(cls, quality: str = "good", **given) -> "LightmapSettings":
        """The lightmap settings of a quality preset, with the fields in `given` set as given."""
        if quality not in QUALITY_PRESETS:
            raise SolveError(f"unknown quality '{quality}' (choose {', '.join(QUALITIES)})")
        return cls(**(QUALITY_PRESETS[quality]["lightmaps"] | given))

    def validate(self) -> None:
        if not (math.isfinite(self.texel_density) and self.texel_density >= 0):
            raise SolveError(f"texel density must be positive (or 0: automatic), got {self.texel_density}")
        if self.texel_density == 0 and self.texel_budget < 1:
            raise SolveError(f"the automatic texel density needs a positive texel budget, got {self.texel_budget}")
        if self.content not in CONTENTS:
            raise SolveError(f"unknown lightmap content '{self.content}' (choose {', '.join(CONTENTS)})")
        if self.max_size < MIN_LIGHTMAP_SIZE:
            raise SolveError(f"the lightmap size cap must be at least {MIN_LIGHTMAP_SIZE}, got {self.max_size}")
        if not 1 <= self.direct_pieces <= 16:
            raise SolveError(f"direct light pieces per side must be 1..16, got {self.direct_pieces}")
        if not 1 <= self.direct_subsamples <= 8:
            raise SolveError(f"direct light points per texel side must be 1..8, got {self.direct_subsamples}")
        if not (self.sky_directions == 0 or MIN_SKY_DIRECTIONS <= self.sky_directions <= MAX_SKY_DIRECTIONS):
            raise SolveError(f"the sky's directions per texel must be 0 (none) or {MIN_SKY_DIRECTIONS}.."
                             f"{MAX_SKY_DIRECTIONS}, got {self.sky_directions}")
