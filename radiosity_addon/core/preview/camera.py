"""The preview's camera: the scene file's `camera`, or a view that frames the scene."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from ..scene import Scene


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
