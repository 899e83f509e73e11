"""Hemi-cube item buffers on the GPU (dissertation §4.1.1): what a point sees, as the
cosine-weighted fraction of its hemisphere covered by each patch.

The scene is drawn into the five faces of a hemi-cube at each point as an item buffer of
patch ids (depth test on). The pixels showing patch j, weighted by their delta form factors,
sum to the fraction patch j covers: F_ij for a hemi-cube at patch i's centre (the hemi-cube
method), the sky fraction 1 - sum_j for one at an element (the world colour). Work is
batched: many hemi-cubes share one atlas framebuffer and are drawn by one multi-draw call, each
face only the triangle clusters its frustum reaches (face_culling.py); a compute shader reduces
the atlas into rows on the GPU; one readback per batch.
"""

from __future__ import annotations

import numpy as np

from ..gpu import FORM_FACTOR_ONE, MAX_WORK_GROUPS, Resources, render_indirect, storage, texture_unit, work_groups
from ..scene import Patches
from ..scene.geometry import tangent_frames
from .face_culling import COMMAND_WORDS, draw_commands, triangle_clusters
from .item_geometry import item_geometry, vertex_format
from .opacity import OpacityAtlas
from .opacity import defines as opacity_defines

ATLAS_LIMIT = 4096  # atlas side in pixels (llvmpipe allows 16384; 4096 keeps memory modest)
NO_PATCH = 0
ROW_BUFFER_BYTES = 1 << 25  # a batch's coverage rows on the GPU, at most (32 MiB)


def delta_form_factors(resolution: int, normalize: bool = True) -> np.ndarray:
    """Delta form factors of one hemi-cube tile: (3R, R) image, rows [0, R) top face,
    then the four half side faces of R/2 rows each (z = height above the base).

    Squared forms (docs/architecture.md): top ΔA / (π (x²+y²+1)²), side z ΔA / (π (x²+z²+1)²).
    Normalized, the whole hemi-cube sums to exactly 1.
    """
    r = resolution
    x = -1 + (np.arange(r) + 0.5) * 2 / r
    pixel_area = (2 / r) ** 2
    top = pixel_area / (np.pi * (x[None, :] ** 2 + x[:, None] ** 2 + 1) ** 2)
    z = (np.arange(r // 2) + 0.5) * 2 / r
    side = z[:, None] * pixel_area / (np.pi * (x[None, :] ** 2 + z[:, None] ** 2 + 1) ** 2)
    tile = np.concatenate([top] + [side] * 4, axis=0)
    return tile / tile.sum() if normalize else tile


def fixed_point_weights(tile: np.ndarray) -> np.ndarray:
    """Round to integers that sum to exactly 2^31, so a full hemi-cube row sums to 1."""
    weights = np.floor(tile.ravel() * FORM_FACTOR_ONE).astype(np.int64)
    shortfall = FORM_FACTOR_ONE - int(weights.sum())
    # give the rounding remainder to the largest fractional parts
    fractions = tile.ravel() * FORM_FACTOR_ONE - weights
    weights[np.argsort(fractions)[::-1][:shortfall]] += 1
    return weights.astype(np.uint32)


def patch_frames(patches: Patches):
    """Centre, tangent, bitangent, normal of every patch (orthonormal frames)."""
    return tangent_frames(patches.center, patches.normal, patches.corners[:, 1] - patches.corners[:, 0])


def face_instances(hemicube_frames, resolution: int, tiles_per_row: int, atlas_size: tuple[int, int]) -> np.ndarray:
    """Per-instance rows (eye, right, up, forward, tile rect, up_min) for the 5 faces of the
    hemi-cubes at `hemicube_frames`, laid out like `delta_form_factors` inside each tile."""
    centre, t, b, n = hemicube_frames
    count = len(centre)
    # (forward, right, up, row offset in tile, rows, up_min) for top, +t, -t, +b, -b
    faces = [
        (n, t, b, 0, resolution, -1.0),
        (t, b, n, resolution, resolution // 2, 0.0),
        (-t, -b, n, resolution + resolution // 2, resolution // 2, 0.0),
        (b, -t, n, 2 * resolution, resolution // 2, 0.0),
        (-b, t, n, 2 * resolution + resolution // 2, resolution // 2, 0.0),
    ]
    slot = np.arange(count)
    tile_x = (slot % tiles_per_row) * resolution
    tile_y = (slot // tiles_per_row) * 3 * resolution
    width, height = atlas_size
    rows = []
    for forward, right, up, row_offset, row_count, up_min in faces:
        x0 = tile_x / width * 2 - 1
        x1 = (tile_x + resolution) / width * 2 - 1
        y0 = (tile_y + row_offset) / height * 2 - 1
        y1 = (tile_y + row_offset + row_count) / height * 2 - 1
        rect = np.stack([x0, y0, x1, y1], axis=1)
        rows.append(np.concatenate([centre, right, up, forward, rect, np.full((count, 1), up_min)], axis=1))
    # instance order: slot-major, 5 faces each
    return np.stack(rows, axis=1).reshape(count * 5, -1).astype(np.float32)


NEAR = 1e-7  # of the scene's diameter: nearer than that a hemi-cube sees nothing (depth is logarithmic)


class HemicubeAtlas:
    """Hemi-cube item buffers of one set of patches, many per atlas, drawn by one multi-draw call:
    `draw(frames)` fills slots 0..len(frames) - 1 (front items: patch id + 1; backs: the twin's
    id + 1, or `back_item` where the back is not simulated; 0: nothing)."""

    def __init__(self, res: Resources, patches: Patches, resolution: int, scene_diameter: float,
                 max_slots: int | None = None, used_slots: int | None = None, backs_hide: bool = False):
        """`backs_hide`: an item buffer for lookups (not form factors): the back of a patch whose back
        is not simulated shows as its id with the BACK_OF bit (include/shot.glsl), so it hides what is
        behind it (a face inside a closed mesh)."""
        ctx = res.ctx
        self.ctx = ctx
        self.patches = patches
        self.resolution = resolution
        self.patch_count = len(patches)
        self.tiles_per_row = max(1, ATLAS_LIMIT // resolution)
        tile_rows = max(1, ATLAS_LIMIT // (3 * resolution))
        if max_slots is not None:  # no larger than the batches need
            self.tiles_per_row = min(self.tiles_per_row, max_slots)
            tile_rows = min(tile_rows, -(-max_slots // self.tiles_per_row))
        # one work group of the reduction per slot in z: small hemi-cubes (8 px: 87 040 tiles) stay within its limit
        self.slots = min(self.tiles_per_row * tile_rows, MAX_WORK_GROUPS)
        self.atlas_size = (self.tiles_per_row * resolution, tile_rows * 3 * resolution)
        # `used_slots`: only the tile rows those fill are allocated (llvmpipe zero-fills a target,
        # so rows no hemi-cube uses cost time);
        # the viewport stays the whole atlas, so every hemi-cube falls on the same pixels
        if used_slots is not None:
            self.slots = max(1, min(self.slots, used_slots))
        target = (self.atlas_size[0], min(self.atlas_size[1], -(-self.slots // self.tiles_per_row) * 3 * resolution))
        self.row_length = self.patch_count + 1  # the last column: backs of patches

        geometry = item_geometry(patches, face_pixels=resolution * resolution * 3 // 5)
        self.looked_up_surfaces = geometry.looked_up
        looked_up = geometry.looked_up > 0  # else a shader without the lookup (its varyings cost fill)
        textured = geometry.opacity_index is not None and bool((geometry.opacity_index >= 0).any())
        self.opacity = None
        if textured:  # alpha-cut surfaces: their fragments go where the texture's alpha is under the cutoff
            self.opacity = OpacityAtlas(res, patches.opacity)
            geometry.vertices["opacity_rect"] = self.opacity.vertex_rects(geometry.opacity_index)
        self.program = res.gpu.program("hemicube_item_buffer.vert", "hemicube_item_buffer.frag",
                                       defines={"LOOKUP": int(looked_up), "BACKS_HIDE": int(backs_hide),
                                                **opacity_defines(textured)})
        self.uniforms = {"near": NEAR * scene_diameter, "far": 4.0 * scene_diameter, "back_item": self.row_length}
        self.clusters = triangle_clusters(geometry.vertices["p"], geometry.indices)
        self.vertex_buffer = res.buffer(geometry.vertices.tobytes())
        self.index_buffer = res.buffer(self.clusters.indices.tobytes())
        self.command_buffer = res.buffer(reserve=4 * COMMAND_WORDS)
        self.triangles_drawn = 0  # by the batches so far, after culling (the work llvmpipe's time follows)
        self.drawn_frames = None  # the frames the atlas holds now
        self.draws_skipped = 0  # draws of the frames it held already
        self.lookup_buffers = {
            "LOOKUP_CUTS": res.buffer(geometry.cuts.tobytes()),
            "LOOKUP_BINS": res.buffer(geometry.bins.tobytes()),
            "LOOKUP_TABLE": res.buffer(geometry.table.tobytes()),
            "LOOKUP_TWINS": res.buffer(geometry.twins.tobytes()),
        } if looked_up else {}
        fields, attributes = vertex_format(looked_up, textured)
        self.instance_buffer = res.buffer(reserve=self.slots * 5 * 17 * 4)
        self.vao = res.vertex_array(
            self.program,
            [
                (self.vertex_buffer, fields, *attributes),
                (self.instance_buffer, "3f 3f 3f 3f 4f 1f/i",
                 "in_eye", "in_right", "in_up", "in_forward", "in_tile", "in_up_min"),
            ],
            index_buffer=self.index_buffer,
            index_element_size=4,
        )
        self.item_texture = res.scratch_texture(target, 1, dtype="u4")  # `draw` clears it
        self.depth = res.scratch_depth(target)
        self.framebuffer = res.framebuffer([self.item_texture], self.depth)

    def draw(self, hemicube_frames) -> None:
        """Draw the hemi-cubes at `hemicube_frames` (centre, x, y, pole arrays; at most `slots`),
        unless the atlas holds just those already (a kept atlas shot from the same pieces again)."""
        ctx = self.ctx
        frames = tuple(np.array(v, dtype=np.float64) for v in hemicube_frames)
        if self.drawn_frames is not None and all(
                a.shape == b.shape and np.array_equal(a, b) for a, b in zip(frames, self.drawn_frames)):
            self.draws_skipped += 1
            return
        self.drawn_frames = None  # until drawn
        instances = face_instances(hemicube_frames, self.resolution, self.tiles_per_row, self.atlas_size)
        self.instance_buffer.write(instances.tobytes())
        for name, value in self.uniforms.items():
            if self.program.get(name, None) is not None:  # a variant may not read one (BACKS_HIDE: back_item)
                self.program[name] = value
        for name, buffer in self.lookup_buffers.items():
            buffer.bind_to_storage_buffer(storage(name))
        if self.opacity is not None:
            self.opacity.bind(texture_unit("OPACITY"))
        commands = draw_commands(self.clusters, instances)
        self.triangles_drawn += int(commands[:, 0].sum()) // 3
        self.framebuffer.use()
        ctx.viewport = (0, 0, *self.atlas_size)  # the layout's, not the allocated rows' (`used_slots`)
        self.framebuffer.clear(0, 0, 0, 0, depth=1.0)
        ctx.enable_only(ctx.DEPTH_TEST)
        if len(commands) == 0:
            return
        if self.command_buffer.size < commands.nbytes:
            self.command_buffer.orphan(commands.nbytes)
        self.command_buffer.write(commands.tobytes())
        render_indirect(self.vao, self.command_buffer, len(commands))
        self.drawn_frames = frames

    def bind(self, unit: int) -> None:
        self.item_texture.use(unit)


class HemicubeRenderer(HemicubeAtlas):
    """Hemi-cubes reduced to coverage rows on the GPU: `coverage(frames)` per batch."""

    def __init__(self, res: Resources, patches: Patches, resolution: int, scene_diameter: float,
                 max_slots: int | None = None, used_slots: int | None = None):
        # no more slots than `max_slots`, nor than ROW_BUFFER_BYTES of rows hold: the row
        # buffer is cleared every batch (8-pixel hemi-cubes fit 87 040 to an atlas: 0.6 GiB of rows at 2k patches)
        by_rows = max(1, ROW_BUFFER_BYTES // (4 * (len(patches) + 1)))
        super().__init__(res, patches, resolution, scene_diameter,
                         by_rows if max_slots is None else max(1, min(max_slots, by_rows)), used_slots)
        self.reduce = res.gpu.compute("hemicube_form_factor_rows.comp")
        weights = fixed_point_weights(delta_form_factors(resolution))
        self.weight_buffer = res.buffer(weights.tobytes())
        self.row_buffer = res.buffer(reserve=self.slots * self.row_length * 4)

    def rows(self, indices: np.ndarray) -> np.ndarray:
        """Rows `indices` (at most `slots` of them) of F (float64, len(indices) x P)."""
        return self.coverage(tuple(v[indices] for v in patch_frames(self.patches)))[:, :-1]

    def coverage(self, hemicube_frames, dtype=np.float64, out: np.ndarray | None = None) -> np.ndarray:
        """For hemi-cubes at `hemicube_frames` (at most `slots`): (count, P + 1) fractions of each
        hemisphere (cosine-weighted) covered by each patch's front, then by backs of patches;
        1 minus a row's sum is what sees the sky. float32 rounds each entry once, as float64
        then float32 would (1 / FORM_FACTOR_ONE is a power of two), at half the conversion's cost.
        `out` (count, k ≤ P + 1) of `dtype`: the rows' first k columns are written into it and it
        is returned — no temporary of the rows' size (whose pages' first touch costs time)."""
        ctx = self.ctx
        count = len(hemicube_frames[0])
        self.draw(hemicube_frames)
        self.row_buffer.clear()
        self.item_texture.use(texture_unit("ITEM_BUFFER"))
        self.weight_buffer.bind_to_storage_buffer(storage("DELTA_FORM_FACTORS"))
        self.row_buffer.bind_to_storage_buffer(storage("FORM_FACTOR_ROWS"))
        self.reduce["tile_size"] = (self.resolution, 3 * self.resolution)
        self.reduce["tiles_per_row"] = self.tiles_per_row
        self.reduce["row_length"] = self.row_length
        self.reduce["slots"] = count
        ctx.memory_barrier()
        self.reduce.run(work_groups(self.resolution, 16), work_groups(3 * self.resolution, 16), count)
        ctx.memory_barrier()
        sums = np.frombuffer(self.row_buffer.read(size=count * self.row_length * 4), dtype=np.uint32)
        sums = sums.reshape(count, self.row_length)
        if out is None:
            out = np.empty(sums.shape, dtype=dtype)
        return np.multiply(sums[:, :out.shape[1]], dtype(1.0 / FORM_FACTOR_ONE), out=out, dtype=dtype)
