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
# what each quality sets; the values were chosen by measuring error and time on the Cornell box
# and the 4k room (docs/benchmarks.md, "Why the presets hold these values"). Tolerances per method:
# progressive, the unshot power left relative to the emitted; hemi-cube, the change per sweep
# relative to max B.
QUALITY_PRESETS = {
    "draft": {"solve": {"patch_size": 1.0, "elements": 1, "refinements": 4, "visibility_res": 256,
                        "hemicube_res": 32, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 0.5,
                        "probe_pieces": 4},
              "tolerance": {"progressive": 3e-2, "hemicube": 1e-3},
              "lightmaps": {"texel_density": 0.0, "direct_map_resolution": 256, "direct_pieces": 2,
                            "direct_subsamples": 2, "sky_directions": 0, "texel_budget": 32768}},
    "good": {"solve": {"patch_size": 1.0, "elements": 1, "refinements": 5, "visibility_res": 256,
                       "hemicube_res": 32, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 0.5,
                       "probe_pieces": 4},
             "tolerance": {"progressive": 2e-2, "hemicube": 1e-5},
             "lightmaps": {"texel_density": 0.0, "direct_map_resolution": 512, "direct_pieces": 2,
                           "direct_subsamples": 2, "sky_directions": 0, "texel_budget": 65536}},
    "final": {"solve": {"patch_size": 0.5, "elements": 4, "refinements": 5, "visibility_res": 512,
                        "hemicube_res": 24, "hemicube_elements": 1, "emitter_gap_resolution": 4.0, "refine_budget": 1.0,
                        "probe_pieces": 3},
              "tolerance": {"progressive": 1e-2, "hemicube": 1e-5},
              "lightmaps": {"texel_density": 0.0, "direct_map_resolution": 1024, "direct_pieces": 4,
                            "direct_subsamples": 2, "sky_directions": 256, "texel_budget": 131072}},
}
DEFAULT_QUALITY = "good"  # what SolveSettings() and LightmapSettings() are, and the panel's and CLI's default

PATCHES_ACROSS_SCENE = 2  # a patch is at most the scene's diameter over this: a wall is never one sample
PATCH_SIZE = QUALITY_PRESETS[DEFAULT_QUALITY]["solve"]["patch_size"]  # the panel's Custom patch size, to start with
MAX_SPLIT = 64  # patches along one side of a surface in the Patch Size mode
MIN_SKY_DIRECTIONS, MAX_SKY_DIRECTIONS = 16, 4096  # a texel's own sky: from this many directions
TEXEL_DENSITY = 64.0  # lightmap texels per scene unit (metre), 15.6 mm: the automatic density's floor
MAX_LIGHTMAP_SIZE = 1024  # texels, the largest side of a lightmap
LIGHTMAP_GUTTER = 2  # texels dilated around every chart, at every mip level
MIN_LIGHTMAP_SIZE = 8
CONTENTS = ("light", "combined")  # what a lightmap holds: the light H arriving (B = E + ρH), or B itself


def _from_preset(settings, part: str) -> None:
    """Give every field left None the value of the settings' quality preset (an unknown quality
    is left to `validate`, which names it)."""
    for name, value in QUALITY_PRESETS.get(settings.quality, {}).get(part, {}).items():
        if getattr(settings, name) is None:
            setattr(settings, name, value)


@dataclass
class SolveSettings:
    """A solve's settings. Built as a quality preset: `SolveSettings()` is the default preset
    (DEFAULT_QUALITY), `SolveSettings(quality="draft")` the whole draft preset, and any field given
    overrides the preset's value (the fields marked "preset" are None until then)."""
    method: str = "auto"  # progressive | hemicube | auto: the one the cost model predicts faster
    quality: str = DEFAULT_QUALITY  # the preset the fields left None come from (its tolerances when tolerance is None)
    subdiv: int | None = None  # N: every surface split N x N into patches; None: split by patch_size
    patch_size: float | None = None  # preset; with subdiv None: longest patch side in scene units (solve caps
    # it at the scene's diameter / PATCHES_ACROSS_SCENE)
    elements: int | None = None  # preset; S x S elements per patch (progressive), S a power of two
    hemicube_res: int | None = None  # preset; pixels across the hemi-cube's top face
    hemicube_elements: int | None = None  # preset; hemi-cube method: S x S receiving hemi-cubes per patch
    solver: str = "gauss-seidel"  # fewer sweeps than Jacobi (docs/architecture.md: measured on llvmpipe)
    tolerance: float | None = None  # None: the method's default
    max_iterations: int = 100_000  # linear solvers
    max_shots: int | None = None  # progressive; None: as many as the tolerance needs
    visibility: str = "hemicube"  # progressive: hemicube (batched) | plain | tessellated | search | guarded
    kernel: str = "exact"  # progressive: exact | disk
    visibility_res: int | None = None  # preset; pixels across a visibility map (a hemi-cube's unfolded cross)
    batch_shots: int = 32  # progressive: shooters per pass at most (hemi-cube visibility)
    complete_remainder: bool = True  # progressive: the light the power unshot at the stop would deliver, added (laid out like the last shots')
    shoot_from: str = "centroid"  # progressive: visibility map from the unshot power's centroid | centre
    shooter_clusters: int = 2048  # progressive: with more patches than this, weak ones shoot in about this many clusters (0: never)
    memory_limit_bytes: int = 2 << 30  # hemi-cube form-factor matrix guard
    skip_unneeded: bool = True  # simulate only the effects the scene calls for (scene.analysis)
    refinements: int | None = None  # preset; rounds of splitting patches where the direct light changes fast
    refine_threshold: float = 0.5  # split a patch whose light spreads more than this fraction of its mean
    emitter_gap_resolution: float | None = None  # preset; split patches facing an emitter across a narrow gap to this many gaps
    refine_budget: float | None = None  # preset; the spread rule's splits add at most this many times the patches
    probe_pieces: int | None = None  # preset; refinement's probe: emitters and area lamps in up to N x N pieces

    def __post_init__(self) -> None:
        _from_preset(self, "solve")

    @classmethod
    def preset(cls, quality: str = DEFAULT_QUALITY, **given) -> "SolveSettings":
        """The settings of a quality preset, with the fields in `given` set as given; an unknown
        quality is refused at once."""
        if quality not in QUALITY_PRESETS:
            raise SolveError(f"unknown quality '{quality}' (choose {', '.join(QUALITIES)})")
        return cls(quality=quality, **given)

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
    """A lightmap bake's settings, built as SolveSettings are: `LightmapSettings()` is the default
    preset's, `quality=` another preset's, and the fields given override the preset's."""
    quality: str = DEFAULT_QUALITY  # the preset the fields left None come from
    texel_density: float | None = None  # preset (0: automatic, `texel_budget`); texels per scene unit
    max_size: int = MAX_LIGHTMAP_SIZE  # cap on width and height
    resolution_overrides: dict = field(default_factory=dict)  # object name -> side (or (w, h)); 0 = density
    power_of_two: bool = False  # round sizes up to powers of two
    gutter: int = LIGHTMAP_GUTTER
    content: str = "light"  # "light": H, shown as emission + albedo x lightmap; "combined": B = E + ρH
    direct_per_texel: bool = True  # lamps' and emitters' light recomputed at every texel (sharp shadows)
    direct_map_resolution: int | None = None  # preset; pixels across the visibility maps of that direct light, at most (fewer where
    # a pixel at the scene's diameter would still be finer than a texel: lightmap.direct.matched_map_resolution)
    direct_pieces: int | None = None  # preset; emissive polygons and area lamps shoot that light in up to N x N pieces (penumbrae)
    direct_subsamples: int | None = None  # preset; where that light is sharp, a texel takes the mean of N x N points over its square (1: its centre)
    sky_directions: int | None = None  # preset; the sky's light recomputed at every texel from N directions (0: the elements' interpolated)
    # with texel_density 0, the density that spreads this many texels over the baked surfaces, and
    # never under TEXEL_DENSITY: a small scene gets as many texels as the preset's quality asks
    texel_budget: int | None = None  # preset

    def __post_init__(self) -> None:
        _from_preset(self, "lightmaps")

    @classmethod
    def preset(cls, quality: str = DEFAULT_QUALITY, **given) -> "LightmapSettings":
        """The lightmap settings of a quality preset, with the fields in `given` set as given; an
        unknown quality is refused at once."""
        if quality not in QUALITY_PRESETS:
            raise SolveError(f"unknown quality '{quality}' (choose {', '.join(QUALITIES)})")
        return cls(quality=quality, **given)

    def validate(self) -> None:
        if self.quality not in QUALITY_PRESETS:
            raise SolveError(f"unknown quality '{self.quality}' (choose {', '.join(QUALITIES)})")
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
