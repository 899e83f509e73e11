"""The shooting pass: one dispatch over all receiving elements adds a shooter's light, given
its geometry and a visibility map rendered from it (dissertation §4.2; Coombe et al. 2004).

Both methods use it: progressive refinement for every shot, the hemi-cube method for the lamps
and the sky (one element per patch). `PatchBuffers` holds the per-patch storage buffers the
shooting pass and the shooter selection read.
"""

from __future__ import annotations

import numpy as np

from ..gpu import Resources, image_unit, storage, work_groups
from ..scene import Patches
from ..visibility import VisibilityMap
from .elements import ElementTextures
from .shooters import SKY, Shooter

MAX_GROUPS = 65535  # work groups per dispatch dimension guaranteed by OpenGL


def shot_uniforms(shooter: Shooter, visibility_map: VisibilityMap) -> dict:
    """The "shot" include's uniforms for one shooter and the map rendered from it."""
    vector = lambda v: tuple(map(float, v))  # noqa: E731
    return {
        "item_resolution": visibility_map.resolution,
        "shooter_patch": shooter.patch,
        "shooter_position": vector(shooter.position),
        "shooter_axis_x": vector(shooter.axes[0]),
        "shooter_axis_y": vector(shooter.axes[1]),
        "shooter_normal": vector(shooter.axes[2]),
        "shooter_polygon": [vector(c) for c in shooter.polygon],
        "shooter_area": float(shooter.area),
        "shooter_radiosity": vector(shooter.radiosity),
        "shooter_kind": shooter.kind,
        "light_direction": vector(shooter.light_direction),
        "spot_cos_half": float(shooter.spot_cos_half),
        "spot_smooth": float(shooter.spot_smooth),
        "ortho_extent": float(shooter.ortho_extent),
        "shooter_keeps_residual": int(shooter.keeps_residual),
    }


def set_uniforms(program, uniforms: dict) -> None:
    for name, value in uniforms.items():
        if program.get(name, None) is not None:  # a kernel may not use every uniform
            program[name] = value


def dispatch(program, count: int) -> None:
    """Run `program` over `count` invocations of 64, rows past the portable group limit in y."""
    groups = work_groups(count, 64)
    rows = -(-groups // MAX_GROUPS)
    program.run(-(-groups // rows), rows)


class PatchBuffers:
    """Per-patch and per-element storage buffers shared by the selection and shooting passes."""

    def __init__(self, res: Resources, patches: Patches, textures: ElementTextures):
        pad = lambda a, w: np.concatenate([a, w], axis=-1).astype(np.float32)  # noqa: E731
        self.buffers = {
            "PATCH_CORNERS": res.buffer(pad(patches.corners, np.zeros((len(patches), 4, 1))).tobytes()),
            "PATCH_NORMAL_AREA": res.buffer(pad(patches.normal, patches.area[:, None]).tobytes()),
            "PATCH_REFLECTANCE": res.buffer(pad(patches.reflectance, np.zeros((len(patches), 1))).tobytes()),
            "ELEMENT_WEIGHTS": res.buffer(textures.weights.astype(np.float32).tobytes()),
            "SHOT_ENERGY": res.buffer(reserve=16),
            # patches of one side of a surface are coplanar: the visibility lookup accepts any of them
            "PATCH_PLANE": res.buffer(patches.plane.astype(np.int32).tobytes()),
        }
        self.buffers["SHOT_ENERGY"].clear()

    def bind(self, *names: str) -> None:
        """Bind the named buffers (all of them by default) to their binding points."""
        for name in names or self.buffers:
            self.buffers[name].bind_to_storage_buffer(storage(name))


class ShootingPass:
    """The shooting pass over all receiving elements."""

    def __init__(self, res: Resources, textures: ElementTextures, buffers: PatchBuffers, kernel: str,
                 search_radius: int, record_visibility: bool = False, occluder_margin: float = -1.0,
                 occlusion: bool = True, interreflection: bool = True):
        if kernel not in ("exact", "disk"):
            raise ValueError(f"unknown kernel '{kernel}' (choose exact, disk)")
        self.res, self.ctx, self.textures, self.buffers = res, res.ctx, textures, buffers
        layout = textures.layout
        self.program = res.gpu.compute("shoot_to_elements.comp", defines={
            "ELEMENT_FORMAT": textures.image_format, "ELEMENTS": layout.elements, "GUTTER": layout.gutter,
            "KERNEL_EXACT": int(kernel == "exact"),
            "SEARCH_RADIUS": search_radius, "RECORD_VISIBILITY": int(record_visibility),
            "OCCLUDER_MARGIN": float(occluder_margin), "OCCLUSION": int(occlusion),
            "INTERREFLECTION": int(interreflection),
        })
        self.element_count = layout.patch_count * layout.elements ** 2
        self.layout_uniforms = {"patch_count": layout.patch_count, "padded_tiles_per_row": layout.padded_tiles_per_row,
                                "residual_tiles_per_row": layout.residual_tiles_per_row}
        self.visibility = res.buffer(reserve=4 * self.element_count) if record_visibility else None

    def shoot(self, shooter: Shooter, visibility_map: VisibilityMap) -> None:
        set_uniforms(self.program, {**self.layout_uniforms, **shot_uniforms(shooter, visibility_map)})
        self.buffers.bind()
        if self.visibility is not None:
            self.visibility.bind_to_storage_buffer(storage("RECORDED_VISIBILITY"))
        visibility_map.bind()
        self.textures.light.bind_to_image(image_unit("LIGHT"), read=True, write=True)
        self.textures.residual.bind_to_image(image_unit("RESIDUAL"), read=True, write=True, level=0)
        self.ctx.memory_barrier()
        dispatch(self.program, self.element_count)
        self.ctx.memory_barrier()

    def shoot_sky(self, color: np.ndarray, sky_fraction: np.ndarray, visibility_map: VisibilityMap) -> None:
        """Every element gathers ρ · color · its sky fraction ((P, S, S) array)."""
        with self.res.gpu.resources() as scoped:
            fractions = scoped.buffer(np.ascontiguousarray(sky_fraction, dtype=np.float32).tobytes())
            fractions.bind_to_storage_buffer(storage("SKY_FRACTION"))
            self.shoot(Shooter(position=np.zeros(3), axes=(np.eye(3)[0], np.eye(3)[1], np.eye(3)[2]),
                               polygon=np.zeros((4, 3)), area=0.0, radiosity=np.asarray(color), kind=SKY),
                       visibility_map)

    def recorded_visibility(self) -> np.ndarray:
        """(P * S * S,) visibility of each element in the last shot (only with record_visibility)."""
        return np.frombuffer(self.visibility.read(), dtype=np.float32).copy()
