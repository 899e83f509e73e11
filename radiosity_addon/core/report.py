"""The report of a solve, typed: what was solved, how long each stage took, what the scene
analysis let it skip and what each method did. `to_dict()` gives the report file's JSON
(docs/architecture.md, Report)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from .hemicube import HemicubeDetails
from .progressive import ProgressiveDetails
from .scene import SceneEffects
from .settings import SolveSettings


@dataclass
class Counts:
    surfaces: int
    objects: int
    patches: int
    elements: int
    clusters: int = 0  # clusters of small faces the solve took as one surface each (scene.face_clusters)


@dataclass
class Report:
    method: str
    settings: SolveSettings
    counts: Counts
    timings: dict[str, float]  # seconds per stage, and "total"
    effects: SceneEffects  # what the scene analysis decided to simulate
    details: HemicubeDetails | ProgressiveDetails
    radiosity_max: float
    refined: list = field(default_factory=list)  # patches split at each refinement (their light changed fast)
    method_choice: dict | None = None  # --method auto: the method chosen, why, and both predictions

    @property
    def work(self):
        """What the method ran (hemi-cubes, shots, visibility maps, channels, ...)."""
        return self.details.work

    @property
    def shots(self) -> int | None:
        return self.details.shots

    @property
    def iterations(self) -> int | None:
        return self.details.iterations

    def to_dict(self) -> dict:
        return {"method": self.method, "settings": self.settings.as_dict(), "counts": asdict(self.counts),
                "timings": dict(self.timings), **self.details.entries(),
                "effects": {**asdict(self.effects), **self.work.entries()}, "radiosity_max": self.radiosity_max,
                "refined": list(self.refined), "method_choice": self.method_choice}

    def summary_line(self) -> str:
        """One line saying what the solve simulated and skipped (the Blender panel shows it)."""
        effects, work = self.effects, self.work
        said = [f"{work.channels_solved} channel(s)",
                "occlusion" if effects.occlusion else "no occlusion (skipped)",
                "interreflection" if effects.interreflection else "direct light only",
                f"{effects.emitters} emitter(s)"]
        if effects.back_sides or effects.back_sides_skipped:
            said += [f"{effects.back_sides} back side(s)", f"{effects.back_sides_skipped} skipped"]
        said.append(f"{self.shots} shots" if self.shots is not None else f"{work.hemicubes} hemi-cubes")
        if "total" in self.timings:
            said.append(f"{self.timings['total']:.1f} s")
        return " · ".join(said)
