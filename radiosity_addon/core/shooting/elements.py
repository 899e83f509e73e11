"""Receivers: substructured element textures (docs/architecture.md, Progressive).

Each patch owns an S x S grid of elements (receivers); element [j, i] sits at
bilinear parameters s = (i + 0.5)/S, t = (j + 0.5)/S of its patch. Two float32
RGBA textures hold them as tiles, one tile per patch, row-major in an atlas:

- **light**: the light H gathered so far (radiosity B = E + ρH): tiles padded with
  a gutter of GUTTER texels. The shooting pass writes each gutter texel with the
  value of the element it continues (clamp to edge), so filtered reads at tile
  edges stay inside the patch; the result equals `imaging.pad_tiles(elements,
  GUTTER)` (tested). H rather than B, so surfaces that reflect nothing (ρ = 0) still
  know the light they receive — what a "light" lightmap holds.
- **residual** (unshot radiosity): unpadded S x S tiles on multiples of S, so
  mip level log2(S) holds one texel per patch, the tile mean. Texels store the
  residual times the element's area weight a_e S^2 / A, so the mean is the
  patch's unshot power per unit area even where elements differ in area
  (triangles, trapezoids).
"""

from __future__ import annotations

import math

import numpy as np

from ..gpu import Resources
from ..scene import Patches
from ..scene.geometry import bilinear

GUTTER = 1
MAX_TEXTURE_SIZE = 16384


def element_parameters(elements: int) -> tuple[np.ndarray, np.ndarray]:
    """(s, t) of the element centres, each (S, S) indexed [j (t row), i (s column)]."""
    centre = (np.arange(elements) + 0.5) / elements
    t, s = np.meshgrid(centre, centre, indexing="ij")
    return s, t


def element_centers(patches: Patches, elements: int) -> np.ndarray:
    """(P, S, S, 3) element centre points."""
    s, t = element_parameters(elements)
    return bilinear(patches.corners, s, t)


def element_areas(patches: Patches, elements: int) -> np.ndarray:
    """(P, S, S) element areas: |dp/ds x dp/dt| at the centre / S^2, exact for planar bilinear
    patches (the Jacobian is bilinear in s, t), so each patch's elements sum to its area."""
    s, t = element_parameters(elements)
    c = patches.corners[:, None, None]  # (P, 1, 1, 4, 3)
    s, t = s[None, :, :, None], t[None, :, :, None]
    ds = (c[..., 1, :] - c[..., 0, :]) * (1 - t) + (c[..., 2, :] - c[..., 3, :]) * t
    dt = (c[..., 3, :] - c[..., 0, :]) * (1 - s) + (c[..., 2, :] - c[..., 1, :]) * s
    return np.linalg.norm(np.cross(ds, dt), axis=-1) / elements ** 2


def patch_means(areas: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """(P, 3) area-weighted means of element values (P, S, S, 3) with element areas (P, S, S)."""
    return (areas[..., None] * elements).sum(axis=(1, 2)) / areas.sum(axis=(1, 2))[:, None]


class ElementLayout:
    """Where each patch's tile lives in the two atlases."""

    def __init__(self, patch_count: int, elements: int, gutter: int = GUTTER):
        self.patch_count = patch_count
        self.elements = elements
        self.gutter = gutter
        self.padded = elements + 2 * gutter
        self.level = int(math.log2(elements))  # mip level with one texel per residual tile
        self.residual_tiles_per_row, self.residual_size = self._atlas(elements)
        self.padded_tiles_per_row, self.light_size = self._atlas(self.padded)

    def _atlas(self, tile: int) -> tuple[int, tuple[int, int]]:
        per_row = max(1, min(math.ceil(math.sqrt(self.patch_count)), MAX_TEXTURE_SIZE // tile))
        rows = -(-self.patch_count // per_row)
        if rows * tile > MAX_TEXTURE_SIZE:
            raise ValueError(f"{self.patch_count} patches of {tile}x{tile} texels do not fit one texture")
        return per_row, (per_row * tile, rows * tile)

    def tiles(self, image: np.ndarray, padded: bool) -> np.ndarray:
        """Atlas image (H, W, C) -> (P, T, T, C) tiles."""
        tile = self.padded if padded else self.elements
        per_row = self.padded_tiles_per_row if padded else self.residual_tiles_per_row
        h, w, c = image.shape
        rows = h // tile
        grid = image.reshape(rows, tile, per_row, tile, c).transpose(0, 2, 1, 3, 4)
        return grid.reshape(rows * per_row, tile, tile, c)[: self.patch_count]

    def atlas(self, tiles: np.ndarray, padded: bool) -> np.ndarray:
        """(P, T, T, C) tiles -> atlas image (H, W, C), unused tiles zero."""
        tile = self.padded if padded else self.elements
        per_row = self.padded_tiles_per_row if padded else self.residual_tiles_per_row
        w, h = self.light_size if padded else self.residual_size
        rows = h // tile
        c = tiles.shape[-1]
        full = np.zeros((rows * per_row, tile, tile, c), dtype=tiles.dtype)
        full[: self.patch_count] = tiles
        return full.reshape(rows, per_row, tile, tile, c).transpose(0, 2, 1, 3, 4).reshape(h, w, c)


class ElementTextures:
    """The light and residual textures of one solve: no light gathered yet, the emission unshot
    (or, with `unshot_emission` False, nothing: the caller shoots the emitters' own emission itself).
    `channels` 3: RGBA32F texels; 1 (a grey scene): R32F texels holding the one channel
    (the shaders' vec4 math then carries zeros in g, b, a)."""

    def __init__(self, res: Resources, patches: Patches, elements: int, gutter: int = GUTTER, channels: int = 3,
                 unshot_emission: bool = True):
        ctx = res.ctx
        self.ctx = ctx
        self.channels = channels
        self.emission = np.asarray(patches.emission, dtype=np.float64)
        self.reflectance = np.asarray(patches.reflectance, dtype=np.float64)
        self.layout = layout = ElementLayout(len(patches), elements, gutter)
        self.areas = element_areas(patches, elements)  # (P, S, S) float64
        self.weights = self.areas * elements ** 2 / patches.area[:, None, None]  # a_e S^2 / A
        emission = np.broadcast_to(self.emission[:, None, None, :] * float(unshot_emission),
                                   (len(patches), elements, elements, 3))
        components = 4 if channels == 3 else 1
        texels = lambda a: (np.concatenate([a, np.zeros(a.shape[:-1] + (1,))], axis=-1)  # noqa: E731
                            if components == 4 else a[..., :1])

        self.light = res.texture(layout.light_size, components, dtype="f4")
        self.light.write(np.zeros(layout.light_size[::-1] + (components,), dtype=np.float32).tobytes())
        residual = layout.atlas(texels(emission * self.weights[..., None]), padded=False)
        self.residual = res.texture(layout.residual_size, components, residual.astype(np.float32).tobytes(),
                                    dtype="f4")
        self.build_mipmaps()

    @property
    def image_format(self) -> str:
        """The GLSL image format of both textures."""
        return "rgba32f" if self.channels == 3 else "r32f"

    def _rgb(self, tiles: np.ndarray) -> np.ndarray:
        """Tiles of the textures' components as RGB (a grey scene's one channel repeated)."""
        return tiles[..., :3] if self.channels == 3 else np.repeat(tiles[..., :1], 3, axis=-1)

    def build_mipmaps(self) -> None:
        """Mip levels 1..log2(S) of the residual (level log2(S): tile means)."""
        if self.layout.level > 0:
            self.residual.build_mipmaps(0, self.layout.level)
            self.residual.filter = (self.ctx.NEAREST_MIPMAP_NEAREST, self.ctx.NEAREST)
        else:  # S = 1: level 0 already holds one texel per patch (no mip levels: keep it complete)
            self.residual.filter = (self.ctx.NEAREST, self.ctx.NEAREST)

    def _padded_tiles(self) -> np.ndarray:
        """(P, S+2g, S+2g, C) float32 view of the light texture's tiles."""
        w, h = self.layout.light_size
        image = np.frombuffer(self.light.read(), dtype=np.float32).reshape(h, w, self.light.components)
        return self.layout.tiles(image, padded=True)

    def read_padded_light(self) -> np.ndarray:
        """(P, S+2g, S+2g, 3) float64: the padded light tiles."""
        return self._rgb(self._padded_tiles()).astype(np.float64)

    def read_light(self) -> np.ndarray:
        """(P, S, S, 3) float64 light H gathered by each element (the gutters cut off before the
        copy: with one element per patch they are 8 of every 9 texels read)."""
        g, s = self.layout.gutter, self.layout.elements
        return self._rgb(self._padded_tiles()[:, g:g + s, g:g + s]).astype(np.float64)

    def radiosity(self, light: np.ndarray) -> np.ndarray:
        """(P, S, S, 3) element radiosity B = E + ρH of element light `light`."""
        return self.emission[:, None, None, :] + self.reflectance[:, None, None, :] * light

    def read_radiosity(self) -> np.ndarray:
        """(P, S, S, 3) float64 element radiosity."""
        return self.radiosity(self.read_light())

    def read_residual(self) -> np.ndarray:
        """(P, S, S, 3) float64 unshot radiosity per element (the area weight divided out)."""
        w, h = self.layout.residual_size
        image = np.frombuffer(self.residual.read(level=0), dtype=np.float32).reshape(h, w, self.residual.components)
        return self._rgb(self.layout.tiles(image, padded=False)).astype(np.float64) / self.weights[..., None]
