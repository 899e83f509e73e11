"""Opacity textures: faces whose material lets light through where a texture says so (alpha-cut
leaves, fences, chains). Cycles lets light pass such a surface with probability 1 - alpha; the
visibility passes test alpha at the texture's own resolution instead (a point of the surface
blocks light where alpha >= ALPHA_CUTOFF), which is the same for the 0/1 masks foliage uses
and keeps shadows as sharp as the texture's cut-out.

Per texture an opacity image (float32 (H, W), alpha, row 0 at v = 0; u and v repeat every 1, as an
image texture's do), per face which texture (-1: opaque) and its corners' UVs in it.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError

ALPHA_CUTOFF = 0.5  # a surface point with alpha below this lets light through
MAX_OPACITY_SIZE = 4096  # pixels along a side of one opacity image
COVERAGE_SAMPLES = 8  # points along a side of a polygon where its coverage is sampled


@dataclass(eq=False)
class OpacityMaps:
    images: list  # float32 (H, W) alpha per texture
    index: np.ndarray  # (S,) int64: each surface's texture, -1 for opaque
    uv: np.ndarray  # (S, 4, 2) float64: its corners' UVs in that texture (triangles repeat their last)

    def __post_init__(self):
        self.index = np.asarray(self.index, dtype=np.int64)
        self.uv = np.asarray(self.uv, dtype=np.float64)

    def validate(self) -> None:
        """Refuse textures no pass can use (a scene coming in: `scene.load`, the Blender exporter)."""
        self.images = [np.asarray(image, dtype=np.float32) for image in self.images]
        if len(self.index) and self.index.max(initial=-1) >= len(self.images):
            raise SceneError("opacity: a surface names an opacity texture that is not given")
        for image in self.images:
            if image.ndim != 2 or not 1 <= min(image.shape) or max(image.shape) > MAX_OPACITY_SIZE:
                raise SceneError(f"opacity: a texture must be an image of 1 to {MAX_OPACITY_SIZE} pixels a side,"
                                 f" got the shape {image.shape}")
            if not np.all(np.isfinite(image)):
                raise SceneError("opacity: a texture has NaN or infinite values")
        if not np.all(np.isfinite(self.uv)):
            raise SceneError("opacity: a surface's texture UVs have NaN or infinite values")

    @property
    def any(self) -> bool:
        return bool((self.index >= 0).any())

    def digest(self) -> bytes:
        """A hash of the textures and of which surface wears which where (a cache key part)."""
        found = hashlib.sha1()
        for image in self.images:
            found.update(str(image.shape).encode())
            found.update(np.ascontiguousarray(image).tobytes())
        found.update(np.ascontiguousarray(self.index).tobytes())
        found.update(np.ascontiguousarray(self.uv).tobytes())
        return found.digest()

    def rows(self, rows: np.ndarray) -> "OpacityMaps":
        """The same textures for the surfaces `rows` (e.g. a scene with backs added)."""
        return OpacityMaps(self.images, self.index[rows], self.uv[rows])

    def arrays(self) -> dict:
        """For a scene's .npz (`scene.load.save_scene`)."""
        found = {"opacity_index": self.index.astype(np.int32), "opacity_uv": self.uv.astype(np.float64)}
        found.update({f"opacity_image{k}": image for k, image in enumerate(self.images)})
        return found

    @classmethod
    def from_arrays(cls, arrays: dict) -> "OpacityMaps | None":
        if "opacity_index" not in arrays:
            return None
        count = sum(1 for name in arrays if name.startswith("opacity_image"))
        maps = cls([arrays[f"opacity_image{k}"] for k in range(count)], arrays["opacity_index"], arrays["opacity_uv"])
        maps.validate()
        return maps

    def with_proxies(self, kept: np.ndarray, faces: np.ndarray, label: np.ndarray, corners: np.ndarray,
                     rectangles: np.ndarray) -> "OpacityMaps":
        """The textures of a clustered scene (`scene.face_clusters`): the surfaces `kept` as they are,
        then one rectangle (n, 4, 3) per cluster of the `faces` (with `corners` (F', 4, 3)) under
        `label`: a cluster's faces share one texture, whose UVs are affine over a flat cluster (the
        affine fit of its corners' UVs, evaluated at the rectangle's corners)."""
        count = len(rectangles)
        index = np.full(count, -1, dtype=np.int64)
        index[label] = self.index[faces]
        uv = np.zeros((count, 4, 2))
        textured = np.flatnonzero(index >= 0)
        if len(textured):
            uv[textured] = _affine_uv(corners, self.uv[faces], label, rectangles, textured)
        return OpacityMaps(self.images, np.concatenate([self.index[kept], index]),
                           np.concatenate([self.uv[kept], uv]))


def coverage(maps: OpacityMaps, rows: np.ndarray | None = None, samples: int = COVERAGE_SAMPLES) -> np.ndarray:
    """(n,) the share of each polygon (the rows of `maps`; None: all) that blocks light: alpha at
    or over the cutoff at `samples`² points spread over its texture UVs (1 for opaque polygons).
    An alpha-cut surface reflects only there: its albedo, as Cycles bakes it (alpha times the
    colour), is the opaque part's albedo times this share."""
    index = maps.index if rows is None else maps.index[rows]
    uv = maps.uv if rows is None else maps.uv[rows]
    found = np.ones(len(index))
    steps = (np.arange(samples) + 0.5) / samples
    s, t = (grid.ravel() for grid in np.meshgrid(steps, steps))
    for texture in np.unique(index[index >= 0]):
        chosen = np.flatnonzero(index == texture)
        c = uv[chosen]  # (n, 4, 2) bilinear over the corners (a triangle repeats its last)
        points = (c[:, None, 0] * ((1 - s) * (1 - t))[None, :, None] + c[:, None, 1] * (s * (1 - t))[None, :, None]
                  + c[:, None, 2] * (s * t)[None, :, None] + c[:, None, 3] * ((1 - s) * t)[None, :, None])
        image = maps.images[texture]
        rows_, columns = image.shape
        u, v = points[..., 0] % 1.0, points[..., 1] % 1.0
        alpha = image[np.minimum((v * rows_).astype(np.int64), rows_ - 1), np.minimum((u * columns).astype(np.int64), columns - 1)]
        found[chosen] = (alpha >= ALPHA_CUTOFF).mean(axis=1)
    return found


def _affine_uv(corners: np.ndarray, uv: np.ndarray, label: np.ndarray, rectangles: np.ndarray,
               clusters: np.ndarray) -> np.ndarray:
    """(len(clusters), 4, 2): per cluster the least-squares affine map from its faces' corners to
    their UVs in the rectangle's plane, evaluated at the rectangle's corners."""
    count = len(rectangles)
    origin = rectangles[:, 0]
    x_axis, y_axis = rectangles[:, 1] - rectangles[:, 0], rectangles[:, 3] - rectangles[:, 0]
    x_axis /= np.maximum(np.einsum("nd,nd->n", x_axis, x_axis), 1e-300)[:, None]
    y_axis /= np.maximum(np.einsum("nd,nd->n", y_axis, y_axis), 1e-300)[:, None]
    own = np.repeat(label, 4)
    flat = corners.reshape(-1, 3) - origin[own]
    features = np.stack([np.einsum("nd,nd->n", flat, x_axis[own]), np.einsum("nd,nd->n", flat, y_axis[own]),
                         np.ones(len(own))], axis=1)  # (s, t, 1) on the rectangle
    targets = uv.reshape(-1, 2)
    normal = np.zeros((count, 3, 3))
    right = np.zeros((count, 3, 2))
    for i in range(3):
        for j in range(3):
            normal[:, i, j] = np.bincount(own, weights=features[:, i] * features[:, j], minlength=count)
        for k in range(2):
            right[:, i, k] = np.bincount(own, weights=features[:, i] * targets[:, k], minlength=count)
    normal += 1e-12 * np.eye(3)[None]
    coefficients = np.linalg.solve(normal[clusters], right[clusters])  # (n, 3, 2)
    st = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]])
    return np.einsum("kc,nco->nko", st, coefficients)
