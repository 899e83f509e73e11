"""The preview renderer: the scene from a camera, lit only by its lightmaps, to a PNG."""

from .camera import Camera, camera_from_dict, default_camera
from .png import png_bytes, tone_map, write_png
from .render import Preview, auto_exposure, render_preview, save_preview

__all__ = ["Camera", "Preview", "auto_exposure", "camera_from_dict", "default_camera", "png_bytes",
           "render_preview", "save_preview", "tone_map", "write_png"]
