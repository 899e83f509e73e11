"""The GPU pass that lays patch lattices into UV space (lightmap_texel_radiosity.frag): texel
centres inside a patch's UV footprint get its interpolated value and its id; a texel footprints
only graze takes the value of the nearest footprint at its nearest point. Lightmaps are made
this way, and material maps are read back per patch through the same ids."""

from __future__ import annotations

import numpy as np

from ..gpu import GPU, render, storage


def rasterize(gpu: GPU, corners_texels: np.ndarray, lattice: np.ndarray, size: tuple[int, int]):
    """GPU pass: (H, W, 3) float32 values and (H, W) int32 signed local patch ids (see the shader)."""
    width, height = size
    count, side = lattice.shape[:2]
    low = np.floor(corners_texels.min(axis=1)) - 1  # one texel more: grazed texels count too
    high = np.ceil(corners_texels.max(axis=1)) + 1
    box = np.stack([low, np.stack([high[:, 0], low[:, 1]], 1), high,
                    low, high, np.stack([low[:, 0], high[:, 1]], 1)], axis=1)  # (P, 6, 2)
    vertices = np.empty(count * 6, dtype=[("texel", "f4", 2), ("patch", "i4")])
    vertices["texel"] = box.reshape(-1, 2)
    vertices["patch"] = np.repeat(np.arange(count, dtype=np.int32), 6)
    lattice_rgba = np.zeros((count, side, side, 4), dtype=np.float32)
    lattice_rgba[..., :3] = lattice

    program = gpu.program("lightmap_patch_bounds.vert", "lightmap_texel_radiosity.frag")
    program["size"].value = (float(width), float(height))
    program["elements"].value = side - 2
    ctx = gpu.ctx
    with gpu.resources() as res:
        corner_buffer = res.buffer(corners_texels.astype(np.float32).tobytes())
        lattice_buffer = res.buffer(lattice_rgba.tobytes())
        vbo = res.buffer(vertices.tobytes())
        vao = res.vertex_array(program, [(vbo, "2f 1i", "in_texel", "in_patch")])
        fbo = res.value_and_id_target((width, height))  # radiance, and the patch of each texel
        ctx.enable_only(ctx.DEPTH_TEST)  # no culling: mirrored UV charts wind clockwise
        ctx.depth_func = "<"
        corner_buffer.bind_to_storage_buffer(storage("LATTICE_CORNERS"))
        lattice_buffer.bind_to_storage_buffer(storage("LATTICE_VALUES"))
        render(vao)
        values = np.frombuffer(fbo.read(components=4, dtype="f4", attachment=0), dtype=np.float32)
        ids = np.frombuffer(fbo.read(components=1, dtype="i4", attachment=1), dtype=np.int32)
    return values.reshape(height, width, 4)[..., :3], ids.reshape(height, width)


def footprint_means(gpu: GPU, corners_uv: np.ndarray, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Means of `image` (H, W, C) over the texels whose centres lie inside each UV footprint
    (corners_uv (n, 4, 2), triangles repeating their last corner): (n, C) means and (n,) texel
    counts (0: the footprint holds no texel centre; its mean is then 0)."""
    height, width = image.shape[:2]
    size = np.array([width, height], dtype=np.float64)
    count = len(corners_uv)
    _, signed_ids = rasterize(gpu, corners_uv * size, np.zeros((count, 3, 3, 3)), (width, height))
    inside = signed_ids > 0
    owner = signed_ids[inside] - 1
    texels = np.bincount(owner, minlength=count).astype(np.float64)
    values = image[inside].astype(np.float64)
    sums = np.stack([np.bincount(owner, values[:, c], minlength=count) for c in range(values.shape[1])], axis=1)
    return sums / np.maximum(texels, 1)[:, None], texels
