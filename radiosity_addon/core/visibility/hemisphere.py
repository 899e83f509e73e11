"""Visibility maps from a point: hemispherical item buffers (docs/architecture.md, Progressive).

From an eye with an orthonormal frame (x, y, pole z), every patch is drawn
projected as (x/|p|, y/|p|) with depth |p|, into an integer item buffer of
patch id + 1 (0: nothing, or the back of a patch). The shooting pass then
looks receivers up in it. Variants (see `VARIANTS`):

- plain: each patch drawn as two straight triangles (Coombe et al. 2004);
- tessellated: each patch split into up to TESSELLATION^2 quads (fewer when it looks
  small from the eye) in a geometry shader
  (dissertation Algorithm 7), so the straight edges follow the curved image;
- search: tessellated, and a receiver also accepts its id in the texels
  around its own (dissertation Algorithm 8);
- guarded: search, but not past a texel that shows something clearly nearer
  (a distance map is drawn with the items);
- hemicube: not this map but five perspective faces per shooter (`hemicube.HemicubeAtlas`),
  with the search; many shooters share one atlas and one draw call.

A map knows nothing of shooters: a patch renders it from a point of its own with its
normal as pole, a point lamp one or two from its position, a sun one orthographic map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpu import Resources, render, texture_unit
from ..scene import Patches
from .opacity import OpacityAtlas
from .opacity import defines as opacity_defines

TESSELLATION = 32  # most segments per patch side
# Geometry shader instances per patch (each draws every k-th row of the grid): fewer is faster on
# llvmpipe but needs more output per instance than the GL minimum (1024 components); the first count
# that links is used.
GEOMETRY_INVOCATIONS = (4, 8, 16, 32)
SEGMENT_ANGLE = 0.15  # radians seen from the eye per segment, at most (when TESSELLATION allows)


@dataclass(frozen=True)
class Variant:
    tessellation: int
    search_radius: int
    occluder_margin: float = -1.0  # < 0: search even when the own texel shows something nearer
    hemicube: bool = False  # shots look receivers up in hemi-cubes (HemicubeAtlas), many per pass


VARIANTS = {
    # hemi-cubes: straight edges stay straight on each face (no tessellation), and a whole batch
    # of shooters is drawn by one instanced call; a sun still uses one orthographic map
    "hemicube": Variant(tessellation=1, search_radius=1, hemicube=True),
    "plain": Variant(tessellation=1, search_radius=0),
    "tessellated": Variant(tessellation=TESSELLATION, search_radius=0),
    "search": Variant(tessellation=TESSELLATION, search_radius=1),
    # search only when the receiver's own texel shows nothing nearer than 0.98 of its distance:
    # 3x fewer light leaks past occluder edges, more misses where silhouettes overlap
    "guarded": Variant(tessellation=TESSELLATION, search_radius=1, occluder_margin=0.02),
}


class VisibilityMap:
    """A resolution x resolution item buffer of all patches, seen from a point."""

    def __init__(self, res: Resources, patches: Patches, resolution: int, variant: str, scene_diameter: float):
        if variant not in VARIANTS:
            raise ValueError(f"unknown visibility variant '{variant}' (choose {', '.join(VARIANTS)})")
        ctx = res.ctx
        self.ctx = ctx
        self.resolution = resolution
        self.variant = VARIANTS[variant]  # "hemicube": the map of a sun (orthographic: no tessellation)
        self.scene_diameter = scene_diameter
        count = patches.front_count  # a back is drawn as its front seen from behind (its twin id)
        corners, ids = patches.corners[:count], np.arange(count)
        maps = patches.opacity
        opacity_index = maps.index[:count] if maps is not None else np.full(count, -1)
        opacity_uv = maps.uv[:count] if maps is not None else np.zeros((count, 4, 2))
        textured = maps is not None and bool((opacity_index >= 0).any())
        self.program = self._link(res.gpu, self.variant.tessellation, textured)
        vertices = np.empty(len(ids) * 4, dtype=[("p", "f4", 3), ("id", "u4"), ("twin", "i4"),
                                                 ("opacity_uv", "f4", 2), ("opacity_rect", "i4", 4)])
        vertices["p"] = corners.reshape(-1, 3)
        vertices["id"] = np.repeat(ids.astype(np.uint32), 4)
        vertices["twin"] = np.repeat(patches.twin[ids].astype(np.int32), 4)
        vertices["opacity_uv"] = opacity_uv.reshape(-1, 2)
        vertices["opacity_rect"] = 0
        self.opacity = None
        if textured:
            self.opacity = OpacityAtlas(res, maps)
            vertices["opacity_rect"] = np.repeat(self.opacity.vertex_rects(opacity_index), 4, axis=0)
        self.vertex_buffer = res.buffer(vertices.tobytes())
        fields = "3f 1u 1i " + ("2f 4i" if textured else "24x")
        names = ["in_position", "in_patch", "in_twin"] + (["in_opacity_uv", "in_opacity_rect"] if textured else [])
        self.vao = res.vertex_array(self.program, [(self.vertex_buffer, fields, *names)])
        self.items = res.scratch_texture((resolution, resolution), 1, dtype="u4")  # `render` clears them
        self.distances = res.scratch_texture((resolution, resolution), 1, dtype="f4")
        self.depth = res.scratch_depth((resolution, resolution))
        self.framebuffer = res.framebuffer([self.items, self.distances], self.depth)
        self.drawn_view = None  # (eye, axes, skip, ortho extent) the map shows now

    @staticmethod
    def _link(gpu, n: int, textured: bool = False):
        error = None
        for invocations in GEOMETRY_INVOCATIONS:
            invocations = min(n, invocations)
            try:
                return gpu.program(
                    "hemisphere_item_buffer.vert", "hemisphere_item_buffer.frag", "hemisphere_item_buffer.geom",
                    defines={"TESSELLATION": n, "INVOCATIONS": invocations,
                             "MAX_VERTICES": 2 * (n + 1) * -(-n // invocations),
                             "SEGMENT_ANGLE": SEGMENT_ANGLE if n > 1 else 1e9, **opacity_defines(textured)},
                )
            except Exception as failure:  # moderngl raises plain Errors on compile/link failure
                error = failure
        raise error

    def render(self, eye, axes, skip_patch: int = -1, ortho_extent: float = 0.0) -> None:
        """Draw the item buffer from `eye`, axes = (x, y, pole); the front patch `skip_patch` (and
        with it its back) is left out.
        With `ortho_extent` > 0 the projection is orthographic along the pole (a sun)."""
        ctx = self.ctx
        view = (tuple(map(float, eye)), tuple(tuple(map(float, axis)) for axis in axes), int(skip_patch),
                float(ortho_extent))
        if view == self.drawn_view:
            return  # a kept map shows this view already
        self.drawn_view = None
        uniforms = {"near": 0.0, "far": 2.0 * self.scene_diameter, "ortho_extent": float(ortho_extent),
                    "eye": tuple(map(float, eye)), "skip_patch": int(skip_patch)}
        uniforms.update((name, tuple(map(float, axis))) for name, axis in zip(("axis_x", "axis_y", "axis_z"), axes))
        for name, value in uniforms.items():
            self.program[name] = value
        self.framebuffer.use()
        self.framebuffer.clear(0, 0, 0, 0, depth=1.0)
        ctx.enable_only(ctx.DEPTH_TEST)
        if self.opacity is not None:
            self.opacity.bind(texture_unit("OPACITY"))
        render(self.vao, mode=ctx.LINES_ADJACENCY)
        self.drawn_view = view

    def bind(self) -> None:
        """Bind the item buffer and the distance map for a pass that looks receivers up."""
        self.items.use(texture_unit("ITEM_BUFFER"))
        self.distances.use(texture_unit("DISTANCE_MAP"))
