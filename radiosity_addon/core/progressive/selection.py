"""The next shooters: the patches of largest unshot power, read from the residual texture's mip
level log2(S) - 1 (2 x 2 texels per patch: quadrant means; level 0 when S = 1). One readback per
batch gives every patch's mean unshot radiosity, the total unshot power and where on each patch
its unshot power lies (the centroid a shooter's visibility is rendered from: a patch half hidden
under a box then shoots from its lit part)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..shooting import ElementTextures

# a batch takes the strongest shooters down to this fraction of the strongest one's power: weaker
# ones would shoot too early (and again later), stronger ones gain from sharing the pass
BATCH_POWER_FLOOR = 0.05
READBACK = ("per batch of shots: the residual's mip level log2(S) - 1 (2 x 2 texels per patch) and 16 bytes"
            " per shot of energy sums (hit and reflected fractions, fixed point)")


@dataclass
class Residuals:
    mean: np.ndarray  # (P, 3) mean unshot radiosity of each patch
    power: np.ndarray  # (P,) unshot power, summed over channels
    centroid: np.ndarray  # (P, 2) bilinear (s, t) of each patch's unshot power centroid
    unshot: np.ndarray  # (3,) total unshot power

    def strongest(self, count: int, floor: float = BATCH_POWER_FLOOR) -> np.ndarray:
        """Up to `count` patches of largest unshot power, strongest first, none under `floor` times
        the strongest's (empty when nothing is left to shoot)."""
        return strongest(self.power, count, floor)


def strongest(power: np.ndarray, count: int, floor: float = BATCH_POWER_FLOOR) -> np.ndarray:
    """Indices of up to `count` of the largest `power`, largest first, none under `floor` times the
    largest (empty when nothing is above zero)."""
    top = float(power.max()) if len(power) else 0.0
    if top <= 0 or count <= 0:
        return np.zeros(0, dtype=np.int64)
    count = min(count, len(power))
    candidates = np.argpartition(-power, count - 1)[:count]
    candidates = candidates[np.argsort(-power[candidates], kind="stable")]
    return candidates[power[candidates] >= floor * top]


class ResidualReader:
    def __init__(self, textures: ElementTextures, area: np.ndarray):
        self.textures, self.area = textures, np.asarray(area, dtype=np.float64)
        layout = textures.layout
        self.level = max(layout.level - 1, 0)
        self.quadrants = 2 if layout.level > 0 else 1  # texels per patch side at that level

    def read(self) -> Residuals:
        textures, layout, q = self.textures, self.textures.layout, self.quadrants
        w, h = (size // (layout.elements // q) for size in layout.residual_size)
        image = np.frombuffer(textures.residual.read(level=self.level), dtype=np.float32)
        image = image.reshape(h, w, textures.residual.components).astype(np.float64)
        tiles = image.reshape(h // q, q, w // q, q, -1).transpose(0, 2, 1, 3, 4).reshape(-1, q, q, image.shape[-1])
        tiles = tiles[:layout.patch_count]
        tiles = tiles[..., :3] if textures.channels == 3 else np.repeat(tiles[..., :1], 3, axis=-1)
        mean = tiles.mean(axis=(1, 2))  # the quadrants have equal texel counts: their mean is the tile's
        weight = tiles.sum(axis=-1)  # (P, q, q)
        centre = (np.arange(q) + 0.5) / q
        total = weight.sum(axis=(1, 2))
        safe = np.where(total > 0, total, 1.0)
        s = (weight * centre[None, None, :]).sum(axis=(1, 2)) / safe
        t = (weight * centre[None, :, None]).sum(axis=(1, 2)) / safe
        centroid = np.where(total[:, None] > 0, np.stack([s, t], axis=1), 0.5)
        power = self.area * mean.sum(axis=1)
        return Residuals(mean=mean, power=power, centroid=centroid, unshot=(self.area[:, None] * mean).sum(axis=0))
