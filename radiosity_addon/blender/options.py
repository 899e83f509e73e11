"""What one bake is asked to do, as a plain object: read from the panel (`scene.radiosity`) or
given by a script or the command line, and never written back into the user's file."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..core import LightmapSettings, SolveSettings

OUTPUTS = ("PACK", "EXR")


@dataclass
class BakeOptions:
    solve: SolveSettings = field(default_factory=SolveSettings)
    lightmaps: LightmapSettings = field(default_factory=LightmapSettings)
    output: str = "PACK"  # PACK: images inside the .blend; EXR: <object>_lightmap.exr beside it
    include_unselected: bool = True  # visible unselected meshes block and reflect light
    uv_margin: float = 0.1  # Lightmap Pack margin (percent) for meshes without a 'Lightmap' UV map

    def overridden(self, solve: dict | None = None, lightmaps: dict | None = None) -> "BakeOptions":
        """These options with some solve and lightmap settings replaced (a script's or the CLI's)."""
        return replace(self, solve=replace(self.solve, **(solve or {})),
                       lightmaps=replace(self.lightmaps, **(lightmaps or {})))
