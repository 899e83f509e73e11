"""Preview renderer: the scene seen from a camera, lit only by its lightmaps.

Each object's lightmap (with its coverage-aware mip chain) is uploaded as a
float texture sampled with LINEAR_MIPMAP_LINEAR, clamped at the edges, and
the surfaces are drawn with back faces culled (only fronts emit and receive).
The picture is rendered `supersample` times larger and box-filtered down.

Tone map (the PNG): `srgb(clamp(radiance × exposure, 0, 1))`, with sRGB's
piecewise encoding and rounding to 8 bits. Without an explicit exposure, it
is chosen so that the 99.9th percentile of the largest colour channel of
non-emitting surfaces maps to 1: lit surfaces fill the range without clipping
(clipping one channel would shift their hue, and with it the colour bleeding
the picture is meant to show), while emitters clip to white-ish.

PNGs are written with zlib and struct only (no imaging library in the core).
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import gl
from .lightmap import gl_mip_count
from .scene import Scene, SceneError

EXPOSURE_PERCENTILE = 99.9


@dataclass
class Camera:
    eye: np.ndarray  # (3,) scene units
    forward: np.ndarray  # (3,) viewing direction
    up: np.ndarray  # (3,)
    fov_y_degrees: float

    def view_projection(self, aspect: float, near: float, far: float) -> np.ndarray:
        """4x4 world -> clip matrix (OpenGL conventions, row-major numpy)."""
        forward = self.forward / np.linalg.norm(self.forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        view = np.eye(4)
        view[:3, :3] = np.stack([right, up, -forward])
        view[:3, 3] = -view[:3, :3] @ self.eye
        focal = 1.0 / math.tan(math.radians(self.fov_y_degrees) / 2)
        projection = np.array([
            [focal / aspect, 0, 0, 0],
            [0, focal, 0, 0],
            [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0, 0, -1, 0],
        ])
        return projection @ view


def camera_from_dict(data: dict) -> Camera:
    try:
        camera = Camera(eye=np.asarray(data["eye"], dtype=np.float64),
                        forward=np.asarray(data["forward"], dtype=np.float64),
                        up=np.asarray(data.get("up", [0, 1, 0]), dtype=np.float64),
                        fov_y_degrees=float(data.get("fov_y_degrees", 39.3)))
    except (KeyError, TypeError, ValueError) as error:
        raise SceneError(f"scene: 'camera' needs 'eye' and 'forward' (3 numbers each) ({error})") from None
    if camera.eye.shape != (3,) or camera.forward.shape != (3,) or camera.up.shape != (3,):
        raise SceneError("scene: 'camera' eye, forward and up must be 3 numbers each")
    if not 0 < camera.fov_y_degrees < 180 or np.linalg.norm(np.cross(camera.forward, camera.up)) == 0:
        raise SceneError("scene: 'camera' needs a field of view in (0, 180) and an up not along forward")
    return camera


def default_camera(scene: Scene) -> Camera:
    """The scene's own `camera` (the bundled Cornell box carries the official one), else a
    view along +z that frames the scene's bounding sphere."""
    if "camera" in scene.extras:
        return camera_from_dict(scene.extras["camera"])
    low, high = scene.bounds
    centre, radius = (low + high) / 2, np.linalg.norm(high - low) / 2
    fov = 39.3
    distance = radius / math.sin(math.radians(fov) / 2)
    return Camera(eye=centre - np.array([0, 0, distance]), forward=np.array([0.0, 0, 1]),
                  up=np.array([0.0, 1, 0]), fov_y_degrees=fov)


@dataclass
class Preview:
    radiance: np.ndarray  # (H, W, 3) float32 linear, row 0 at the top
    surface_index: np.ndarray  # (H, W) int32 surface seen at the pixel centre, -1 for none


def _surface_triangles(scene: Scene, lightmaps: dict) -> dict[str, np.ndarray]:
    """Per object, a vertex array (fan triangles) of position, lightmap UV and surface index."""
    arrays = {}
    for name, lightmap in lightmaps.items():
        rows = []
        for index, uv in lightmap.surface_uv.items():
            vertices = scene.surfaces[index].vertices
            for k in range(1, len(vertices) - 1):
                for corner in (0, k, k + 1):
                    rows.append((vertices[corner], uv[corner], index))
        array = np.empty(len(rows), dtype=[("position", "f4", 3), ("uv", "f4", 2), ("surface", "i4")])
        array["position"] = [r[0] for r in rows]
        array["uv"] = [r[1] for r in rows]
        array["surface"] = [r[2] for r in rows]
        arrays[name] = array
    return arrays


def _lightmap_texture(ctx, lightmap):
    """The lightmap with our coverage-aware levels, as far as their sizes are OpenGL's (GL stops
    sampling at MAX_LEVEL; sizes that are multiples of 8 give at least 4 levels)."""
    width, height = lightmap.size
    levels = lightmap.levels[:gl_mip_count(lightmap.levels)]
    texture = ctx.texture((width, height), 4, levels[0].tobytes(), dtype="f4")
    texture.build_mipmaps(base=0, max_level=len(levels) - 1)  # allocates the levels
    for level, image in enumerate(levels[1:], start=1):
        texture.write(np.ascontiguousarray(image).tobytes(), level=level)
    texture.filter = (ctx.LINEAR_MIPMAP_LINEAR, ctx.LINEAR)
    texture.repeat_x = texture.repeat_y = False  # clamp to edge
    return texture


def render_preview(scene: Scene, lightmaps: dict, camera: Camera | None = None, width: int = 512,
                   height: int = 512, supersample: int = 2, ctx=None) -> Preview:
    """Render the scene with its lightmaps (see the module doc)."""
    camera = camera or default_camera(scene)
    big_w, big_h = width * supersample, height * supersample
    diameter = max(scene.diameter, 1e-9)
    distance = np.linalg.norm((scene.bounds[0] + scene.bounds[1]) / 2 - camera.eye)
    near = max(1e-4 * diameter, (distance - diameter) * 0.5) if distance > diameter else 1e-3 * diameter
    matrix = camera.view_projection(width / height, near, distance + diameter)
    with gl.gl_context(ctx) as gl_ctx:
        program = gl.program(gl_ctx, "preview_scene.vert", "preview_lightmap_trilinear.frag")
        program["view_projection"].write(matrix.T.astype("f4").tobytes())
        program["lightmap"].value = 0
        resources = [program]
        try:
            color = gl_ctx.texture((big_w, big_h), 4, dtype="f4")
            surface = gl_ctx.texture((big_w, big_h), 1, dtype="i4")
            depth = gl_ctx.depth_renderbuffer((big_w, big_h))
            fbo = gl_ctx.framebuffer([color, surface], depth)
            resources += [color, surface, depth, fbo]
            fbo.use()
            fbo.viewport = (0, 0, big_w, big_h)
            fbo.clear(depth=1.0)
            gl_ctx.enable_only(gl_ctx.DEPTH_TEST | gl_ctx.CULL_FACE)  # only fronts emit and receive
            gl_ctx.front_face = "ccw"
            gl_ctx.depth_func = "<"
            for name, vertices in _surface_triangles(scene, lightmaps).items():
                texture = _lightmap_texture(gl_ctx, lightmaps[name])
                vbo = gl_ctx.buffer(vertices.tobytes())
                vao = gl_ctx.vertex_array(program, [(vbo, "3f 2f 1i", "in_position", "in_uv", "in_surface")])
                texture.use(location=0)
                vao.render()
                for resource in (vao, vbo, texture):
                    resource.release()
            radiance = np.frombuffer(fbo.read(components=4, dtype="f4", attachment=0), dtype=np.float32)
            ids = np.frombuffer(fbo.read(components=1, dtype="i4", attachment=1), dtype=np.int32)
        finally:
            for resource in reversed(resources):
                resource.release()
    radiance = radiance.reshape(big_h, big_w, 4)[::-1, :, :3]  # GL rows start at the bottom
    ids = ids.reshape(big_h, big_w)[::-1]
    radiance = radiance.reshape(height, supersample, width, supersample, 3).mean(axis=(1, 3))
    centre = supersample // 2
    return Preview(radiance=radiance.astype(np.float32),
                   surface_index=(ids[centre::supersample, centre::supersample] - 1).astype(np.int32))


def auto_exposure(scene: Scene, preview: Preview) -> float:
    """Exposure mapping the EXPOSURE_PERCENTILE of non-emitting surfaces' largest channel to 1."""
    emitting = np.array([bool(np.any(s.emission > 0)) for s in scene.surfaces] + [True])  # [-1]: background
    lit = ~emitting[preview.surface_index]
    brightest_channel = preview.radiance[lit].max(axis=-1)
    reference = np.percentile(brightest_channel, EXPOSURE_PERCENTILE) if brightest_channel.size else 0.0
    return 1.0 / reference if reference > 0 else 1.0


def tone_map(radiance: np.ndarray, exposure: float) -> np.ndarray:
    """Linear radiance -> 8-bit sRGB: scale by exposure, clamp to [0, 1], sRGB-encode, round."""
    x = np.clip(radiance * exposure, 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def png_bytes(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of an (H, W, 3) uint8 array, row 0 at the top."""
    height, width, _ = rgb.shape
    rows = np.concatenate([np.zeros((height, 1), np.uint8), rgb.reshape(height, -1)], axis=1)  # filter 0

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(rows.tobytes(), 9)) + chunk(b"IEND", b""))


def write_png(path, rgb: np.ndarray) -> None:
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_bytes(png_bytes(rgb))


def save_preview(path, scene: Scene, preview: Preview, exposure: float | None = None) -> float:
    """Tone-map and write the preview as a PNG; returns the exposure used."""
    exposure = auto_exposure(scene, preview) if exposure is None else exposure
    write_png(path, tone_map(preview.radiance, exposure))
    return exposure
