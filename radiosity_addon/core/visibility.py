"""Visibility maps from a point: hemispherical item buffers (DESIGN.md, Method 2).

From an eye with an orthonormal frame (x, y, pole z), every patch is drawn
projected as (x/|p|, y/|p|) with depth |p|, into an integer item buffer of
patch id + 1 (0: nothing, or the back of a patch). The shooting pass then
looks receivers up in it. Variants (see `VARIANTS`):

- plain: each patch drawn as two straight triangles (Coombe et al. 2004);
- tessellated: each patch split into up to TESSELLATION^2 quads (fewer when it looks
  small from the eye) in a geometry shader
  (dissertation Algorithm 7), so the straight edges follow the curved image;
- search: tessellated, and a receiver also accepts its id in the texels
  around its own (dissertation Algorithm 8).

A map knows nothing of shooters: a patch shooter renders it from its centre
with its normal as pole; a point light could render one (or two) from its
position.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import gl
from .patches import Patches

TESSELLATION = 32  # most segments per patch side
GEOMETRY_INVOCATIONS = 16  # geometry shader instances per patch, each drawing every 16th row
SEGMENT_ANGLE = 0.1  # radians seen from the eye per segment, at most (when TESSELLATION allows)


@dataclass(frozen=True)
class Variant:
    tessellation: int
    search_radius: int


VARIANTS = {
    "plain": Variant(tessellation=1, search_radius=0),
    "tessellated": Variant(tessellation=TESSELLATION, search_radius=0),
    "search": Variant(tessellation=TESSELLATION, search_radius=1),
}


def frame_from_normal(normal: np.ndarray, hint: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes completing `normal` to a right-handed frame (x, y, normal)."""
    normal = np.asarray(normal, dtype=np.float64)
    if hint is None or np.linalg.norm(np.cross(hint, normal)) < 1e-6:
        hint = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = hint - np.dot(hint, normal) * normal
    x /= np.linalg.norm(x)
    return x, np.cross(normal, x)


def project(points: np.ndarray, eye: np.ndarray, axes: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """Hemispherical projection (x/|p|, y/|p|, z/|p|) of points (..., 3) in the eye's frame."""
    d = np.asarray(points) - eye
    q = np.stack([d @ axes[0], d @ axes[1], d @ axes[2]], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


class VisibilityMap:
    """A resolution x resolution item buffer of all patches, seen from a point."""

    def __init__(self, ctx, patches: Patches, resolution: int, variant: str, scene_diameter: float):
        if variant not in VARIANTS:
            raise ValueError(f"unknown visibility variant '{variant}' (choose {', '.join(VARIANTS)})")
        self.ctx = ctx
        self.resolution = resolution
        self.variant = VARIANTS[variant]
        n = self.variant.tessellation
        self.program = gl.program(
            ctx, "hemisphere_item_buffer.vert", "hemisphere_item_buffer.frag", "hemisphere_item_buffer.geom",
            defines={"TESSELLATION": n, "INVOCATIONS": min(n, GEOMETRY_INVOCATIONS),
                     "MAX_VERTICES": 2 * (n + 1) * -(-n // min(n, GEOMETRY_INVOCATIONS)),
                     "SEGMENT_ANGLE": SEGMENT_ANGLE if n > 1 else 1e9},
        )
        self.program["near"] = 0.0
        self.program["far"] = 2.0 * scene_diameter
        vertices = np.empty(len(patches) * 4, dtype=[("p", "f4", 3), ("id", "u4")])
        vertices["p"] = patches.corners.reshape(-1, 3)
        vertices["id"] = np.repeat(np.arange(len(patches), dtype=np.uint32), 4)
        self.vertex_buffer = ctx.buffer(vertices.tobytes())
        self.vao = ctx.vertex_array(self.program, [(self.vertex_buffer, "3f 1u", "in_position", "in_patch")])
        self.items = ctx.texture((resolution, resolution), 1, dtype="u4")
        self.items.filter = (ctx.NEAREST, ctx.NEAREST)
        self.depth = ctx.depth_renderbuffer((resolution, resolution))
        self.framebuffer = ctx.framebuffer([self.items], self.depth)

    def render(self, eye, axes, skip_patch: int = -1) -> None:
        """Draw the item buffer from `eye`, axes = (x, y, pole); `skip_patch` is left out."""
        ctx = self.ctx
        self.program["eye"] = tuple(map(float, eye))
        for name, axis in zip(("axis_x", "axis_y", "axis_z"), axes):
            self.program[name] = tuple(map(float, axis))
        self.program["skip_patch"] = int(skip_patch)
        self.framebuffer.use()
        self.framebuffer.clear(0, 0, 0, 0, depth=1.0)
        ctx.enable_only(ctx.DEPTH_TEST)
        self.vao.render(mode=ctx.LINES_ADJACENCY)

    def image(self) -> np.ndarray:
        """(R, R) uint32 item buffer [y, x]: patch id + 1, 0 = nothing (tests and debugging)."""
        r = self.resolution
        return np.frombuffer(self.items.read(), dtype=np.uint32).reshape(r, r)

    def release(self) -> None:
        for obj in (self.vao, self.vertex_buffer, self.framebuffer, self.items, self.depth, self.program):
            obj.release()
