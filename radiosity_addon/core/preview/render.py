"""Preview renderer: the scene seen from a camera, lit only by its lightmaps.

Each object's lightmap (with its coverage-aware mip chain) is uploaded as a
float texture sampled with LINEAR_MIPMAP_LINEAR, clamped at the edges, and
the surfaces are drawn with back faces culled (a lightmap holds the front). A
"light" lightmap (H) is shown as E + ρ H with each surface's own values.
The picture is rendered `supersample` times larger and box-filtered down.

Exposure (the PNG, see `png` for the tone map): without an explicit exposure, it
is chosen so that the 99.9th percentile of the largest colour channel of
non-emitting surfaces maps to 1: lit surfaces fill the range without clipping
(clipping one channel would shift their hue, and with it the colour bleeding
the picture is meant to show), while emitters clip to white-ish.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpu import GPU, Resources, open_gpu, render, storage, texture_unit
from ..lightmap import gl_mip_count
from ..scene import Scene
from .camera import Camera, default_camera
from .png import tone_map, write_png

EXPOSURE_PERCENTILE = 99.9


@dataclass
class Preview:
    radiance: np.ndarray  # (H, W, 3) float32 linear, row 0 at the top
    surface_index: np.ndarray  # (H, W) int32 surface seen at the pixel centre, -1 for none


def _surface_triangles(scene: Scene, lightmap) -> np.ndarray:
    """An object's vertex array (two fan triangles per surface, the second dropped for a triangle)
    of position, lightmap UV and surface index."""
    indices = lightmap.surfaces
    fans = np.array([[0, 1, 2], [0, 2, 3]])
    keep = np.ones((len(indices), 2), dtype=bool)
    keep[scene.is_triangle[indices], 1] = False
    array = np.empty((len(indices), 2, 3), dtype=[("position", "f4", 3), ("uv", "f4", 2), ("surface", "i4")])
    array["position"] = scene.corners[indices][:, fans]
    array["uv"] = lightmap.surface_uv[:, fans]
    array["surface"] = indices[:, None, None]
    return array[keep].reshape(-1)


def _lightmap_texture(res: Resources, lightmap):
    """The lightmap with our coverage-aware levels, as far as their sizes are OpenGL's (GL stops
    sampling at MAX_LEVEL; sizes that are multiples of 8 give at least 4 levels)."""
    width, height = lightmap.size
    levels = lightmap.levels[:gl_mip_count(lightmap.levels)]
    ctx = res.ctx
    texture = res.texture((width, height), 4, levels[0].tobytes(), dtype="f4")
    texture.build_mipmaps(base=0, max_level=len(levels) - 1)  # allocates the levels
    for level, image in enumerate(levels[1:], start=1):
        texture.write(np.ascontiguousarray(image).tobytes(), level=level)
    texture.filter = (ctx.LINEAR_MIPMAP_LINEAR, ctx.LINEAR)
    texture.repeat_x = texture.repeat_y = False  # clamp to edge
    return texture


def render_preview(scene: Scene, lightmaps: dict, camera: Camera | None = None, width: int = 512,
                   height: int = 512, supersample: int = 2, gpu: GPU | None = None) -> Preview:
    """Render the scene with its lightmaps (see the module doc)."""
    camera = camera or default_camera(scene)
    big_w, big_h = width * supersample, height * supersample
    diameter = max(scene.diameter, 1e-9)
    distance = np.linalg.norm((scene.bounds[0] + scene.bounds[1]) / 2 - camera.eye)
    near = max(1e-4 * diameter, (distance - diameter) * 0.5) if distance > diameter else 1e-3 * diameter
    matrix = camera.view_projection(width / height, near, distance + diameter)
    with open_gpu(gpu) as preview_gpu, preview_gpu.resources() as res:
        ctx = res.ctx
        program = preview_gpu.program("preview_scene.vert", "preview_lightmap_trilinear.frag")
        program["view_projection"].write(matrix.T.astype("f4").tobytes())
        fbo = res.value_and_id_target((big_w, big_h))  # colour, and the surface of each pixel
        ctx.enable_only(ctx.DEPTH_TEST | ctx.CULL_FACE)  # only fronts emit and receive
        ctx.front_face = "ccw"
        ctx.depth_func = "<"
        rgba = lambda values: np.concatenate([values, np.zeros((len(values), 1))], axis=1).astype("f4")  # noqa: E731
        res.buffer(rgba(scene.reflectance).tobytes()).bind_to_storage_buffer(storage("SURFACE_REFLECTANCE"))
        res.buffer(rgba(scene.emission).tobytes()).bind_to_storage_buffer(storage("SURFACE_EMISSION"))
        for lightmap in lightmaps.values():
            program["shows_light"] = int(lightmap.content == "light")
            with preview_gpu.resources() as scoped:  # one object's texture and geometry at a time
                texture = _lightmap_texture(scoped, lightmap)
                vbo = scoped.buffer(_surface_triangles(scene, lightmap).tobytes())
                vao = scoped.vertex_array(program, [(vbo, "3f 2f 1i", "in_position", "in_uv", "in_surface")])
                texture.use(location=texture_unit("LIGHTMAP"))
                render(vao)
        radiance = np.frombuffer(fbo.read(components=4, dtype="f4", attachment=0), dtype=np.float32)
        ids = np.frombuffer(fbo.read(components=1, dtype="i4", attachment=1), dtype=np.int32)
    radiance = radiance.reshape(big_h, big_w, 4)[::-1, :, :3]  # GL rows start at the bottom
    ids = ids.reshape(big_h, big_w)[::-1]
    radiance = radiance.reshape(height, supersample, width, supersample, 3).mean(axis=(1, 3))
    centre = supersample // 2
    return Preview(radiance=radiance.astype(np.float32),
                   surface_index=(ids[centre::supersample, centre::supersample] - 1).astype(np.int32))


def auto_exposure(scene: Scene, preview: Preview) -> float:
    """Exposure mapping the EXPOSURE_PERCENTILE of non-emitting surfaces' largest channel to 1."""
    emitting = np.append(np.any(scene.emission > 0, axis=1), True)  # [-1]: background
    lit = ~emitting[preview.surface_index]
    brightest_channel = preview.radiance[lit].max(axis=-1)
    reference = np.percentile(brightest_channel, EXPOSURE_PERCENTILE) if brightest_channel.size else 0.0
    return 1.0 / reference if reference > 0 else 1.0


def save_preview(path, scene: Scene, preview: Preview, exposure: float | None = None) -> float:
    """Tone-map and write the preview as a PNG; returns the exposure used."""
    exposure = auto_exposure(scene, preview) if exposure is None else exposure
    write_png(path, tone_map(preview.radiance, exposure))
    return exposure
