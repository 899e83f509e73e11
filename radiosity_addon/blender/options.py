"""What one bake is asked to do, as a plain object: read from the panel (`scene.radiosity`) or
given by a script or the command line, and never written back into the user's file."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..core import LightmapSettings, SolveSettings

OUTPUTS = ("PACK", "EXR")


@dataclass
class BakeOptions:
    solve: SolveSettings = field(default_factory=SolveSettings.preset)  # auto, good: what the panel starts with
    lightmaps: LightmapSettings = field(default_factory=LightmapSettings)
    output: str = "PACK"  # PACK: images inside the .blend; EXR: <object>_lightmap.exr beside it
    include_unselected: bool = True  # visible unselected meshes block and reflect light
    uv_margin: float = 0.1  # Lightmap Pack margin (percent) for meshes without a 'Lightmap' UV map

    def overridden(self, solve: dict | None = None, lightmaps: dict | None = None) -> "BakeOptions":
        """These options with some solve and lightmap settings replaced (a script's or the CLI's);
        a "quality" among them first resets every knob to that preset's (the method kept)."""
        solve, base = dict(solve or {}), self
        if "quality" in solve:
            quality = solve.pop("quality")
            kept = self.lightmaps
            base = replace(self, solve=SolveSettings.preset(quality, method=self.solve.method),
                           lightmaps=LightmapSettings.preset(
                               quality, texel_density=kept.texel_density, max_size=kept.max_size,
                               resolution_overrides=kept.resolution_overrides, content=kept.content))
        return replace(base, solve=replace(base.solve, **solve), lightmaps=replace(base.lightmaps, **(lightmaps or {})))
