"""Opacity textures on the GPU: every item buffer that draws an alpha-cut surface (a leaf card, a
fence) drops its fragments where the texture's alpha is under the cutoff (`scene.opacity`), so
light passes the cut-out in every visibility pass at the texture's own resolution.

The textures are packed side by side into one 8-bit atlas (shelves, tallest first); a polygon's
vertices carry its texture UVs and the texture's rectangle in the atlas (x, y, width, height in
texels; width 0: opaque), and the fragment shader wraps the UVs into the rectangle (image textures
repeat) and reads the nearest texel.
"""

from __future__ import annotations

import numpy as np

from ..scene.opacity import ALPHA_CUTOFF, OpacityMaps

ATLAS_SIDE = 16384  # texels along the atlas's sides at most (OpenGL 4.1 guarantees 16384)


def pack(images: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(atlas uint8 (H, W): alpha * 255, rectangles (k, 4) int32: x, y, width, height per image),
    halving every image until the shelves fit ATLAS_SIDE."""
    images = [np.asarray(image, dtype=np.float32) for image in images]
    while True:
        width = max(max(image.shape[1] for image in images), int(np.ceil(np.sqrt(sum(i.size for i in images)))))
        width = min(width, ATLAS_SIDE)
        order = sorted(range(len(images)), key=lambda k: -images[k].shape[0])
        rects = np.zeros((len(images), 4), dtype=np.int32)
        x = y = shelf = 0
        for k in order:
            h, w = images[k].shape
            if x + w > width:
                x, y, shelf = 0, y + shelf, 0
            rects[k] = (x, y, w, h)
            x, shelf = x + w, max(shelf, h)
        height = y + shelf
        if height <= ATLAS_SIDE and width >= max(image.shape[1] for image in images):
            break
        images = [image[::2, ::2] if min(image.shape) > 1 else image for image in images]
    atlas = np.zeros((height, width), dtype=np.uint8)
    for image, (x, y, w, h) in zip(images, rects):
        atlas[y:y + h, x:x + w] = np.rint(np.clip(image, 0.0, 1.0) * 255).astype(np.uint8)
    return atlas, rects


class OpacityAtlas:
    """One scope's atlas texture of a set of opacity textures, and per polygon what its vertices
    carry (`vertex_rects`)."""

    def __init__(self, res, maps: OpacityMaps):
        atlas, self.rects = pack(maps.images)
        self.texture = res.texture((atlas.shape[1], atlas.shape[0]), 1, atlas.tobytes(), dtype="f1")
        self.texture.filter = (res.ctx.NEAREST, res.ctx.NEAREST)

    def vertex_rects(self, index: np.ndarray) -> np.ndarray:
        """(n, 4) int32 rectangles for polygons with textures `index` (n,) (zeros: opaque)."""
        rects = np.zeros((len(index), 4), dtype=np.int32)
        textured = index >= 0
        rects[textured] = self.rects[index[textured]]
        return rects

    def bind(self, unit: int) -> None:
        self.texture.use(unit)


def defines(textured: bool) -> dict:
    """The item-buffer shaders' defines for opacity: the test compiled in only where it is needed."""
    return {"OPACITY": int(textured), "ALPHA_CUTOFF": ALPHA_CUTOFF}
