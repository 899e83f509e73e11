"""The next shooter, chosen on the GPU: the patch of largest unshot power, from the residual
texture's mip level log2(S) (one texel per patch: its mean). One readback of 64 bytes
(`SELECTION_DTYPE`, the layout of select_shooter.comp's Result block) per shot."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpu import Resources, storage, texture_unit
from ..shooting import ElementTextures, PatchBuffers

SELECTION_DTYPE = np.dtype([
    ("score", "<f4"), ("patch", "<i4"), ("centroid", "<f4", 2),  # best power, its patch, power centroid (s, t)
    ("residual", "<f4", 4),  # that patch's mean unshot radiosity (RGB)
    ("unshot", "<f4", 4),  # total unshot power (RGB)
    ("last_shot", "<f4", 4),  # the previous shot's hit fraction and reflected fractions (RGB)
])
READBACK = (f"{SELECTION_DTYPE.itemsize} bytes per shot: best patch power and index, its unshot power centroid"
            " (s, t), its mean residual (RGB), total unshot power (RGB), and the previous shot's hit and"
            " reflected fractions (fixed point sums)")


@dataclass
class Selection:
    patch: int  # -1 when nothing is left to shoot
    score: float
    residual: np.ndarray  # (3,) mean unshot radiosity of that patch
    centroid: np.ndarray  # (2,) bilinear (s, t) of that patch's unshot power centroid
    unshot: np.ndarray  # (3,) total unshot power
    last_shot: np.ndarray  # (4,) previous shot: hit fraction, reflected fraction per channel


class Selector:
    def __init__(self, res: Resources, textures: ElementTextures, buffers: PatchBuffers):
        self.ctx, self.textures, self.buffers = res.ctx, textures, buffers
        layout = textures.layout
        self.program = res.gpu.compute("select_shooter.comp")
        self.uniforms = {"level": layout.level, "patch_count": layout.patch_count,
                         "tiles_per_row": layout.residual_tiles_per_row, "elements": layout.elements}
        self.result = res.buffer(reserve=SELECTION_DTYPE.itemsize)

    def select(self) -> Selection:
        for name, value in self.uniforms.items():
            self.program[name] = value
        self.buffers.bind("PATCH_NORMAL_AREA", "SHOT_ENERGY")
        self.result.bind_to_storage_buffer(storage("SELECTION"))
        self.textures.residual.use(texture_unit("RESIDUAL"))
        self.ctx.memory_barrier()
        self.program.run(1)
        self.ctx.memory_barrier()
        raw = np.frombuffer(self.result.read(), dtype=SELECTION_DTYPE)[0]
        residual, unshot = raw["residual"][:3].astype(np.float64), raw["unshot"][:3].astype(np.float64)
        if self.textures.channels == 1:  # a grey scene's one channel stands for all three
            residual, unshot = np.repeat(residual[:1], 3), np.repeat(unshot[:1], 3)
        score = float(raw["score"])
        return Selection(patch=int(raw["patch"]) if score > 0 else -1, score=score, residual=residual,
                         centroid=raw["centroid"].astype(np.float64), unshot=unshot,
                         last_shot=raw["last_shot"].astype(np.float64))
