"""Shooting in the progressive method: who shoots next, and adding ΔB to receivers.

`Selector` picks the patch of largest unshot power from the residual's mip
level log2(S) on the GPU and reads back 64 bytes (`READBACK`). `Shooter`
describes a shooter by geometry only (position, frame, polygon, area, unshot
radiosity), and `Gatherer.shoot(shooter, visibility_map)` adds ΔB to every
receiving element given that geometry and a visibility map rendered from the
shooter's position. Patches are the shooters here; a point or directional
light would be another `Shooter` kind with its own kernel branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import gl
from .element_textures import ElementTextures
from .patches import Patches, bilinear
from .visibility import VisibilityMap, frame_from_normal

READBACK = ("64 bytes per shot: best patch power and index, its unshot power centroid (s, t), its mean residual"
            " (RGB), total unshot power (RGB),"
            " and the previous shot's hit and reflected fractions (fixed point sums)")
MAX_GROUPS = 65535  # work groups per dispatch dimension guaranteed by OpenGL


@dataclass
class Shooter:
    position: np.ndarray  # (3,) eye of its visibility map
    axes: tuple  # (x, y, normal) orthonormal
    polygon: np.ndarray  # (4, 3) corners, counter-clockwise from the front
    area: float
    radiosity: np.ndarray  # (3,) unshot radiosity being shot (a point lamp: intensity; a sun: irradiance)
    patch: int = -1  # the patch whose residual this shot clears
    kind: int = 0  # 0: polygon, 1: point lamp, 2: directional (sun) — see shoot_to_elements.comp
    light_direction: tuple = (0.0, 0.0, -1.0)  # spot axis / sun travel direction
    spot_cos_half: float = -1.0  # -1: no cone
    spot_smooth: float = 0.0
    ortho_extent: float = 0.0  # > 0: orthographic visibility map (sun)

    @property
    def power(self) -> np.ndarray:
        return self.area * self.radiosity


class PatchShooters:
    """Patches as shooters: their geometry computed once per solve, a `Shooter` per shot."""

    def __init__(self, patches: Patches):
        self.corners = patches.corners
        self.normal = patches.normal
        self.center = patches.center
        self.area = patches.area

    def shooter(self, index: int, radiosity: np.ndarray, eye_parameters=None) -> Shooter:
        """Patch `index` shooting `radiosity`; its visibility map is rendered from its centre, or
        from the bilinear point at `eye_parameters` (s, t) (the centroid of its unshot power)."""
        normal = self.normal[index]
        x, y = frame_from_normal(normal, self.corners[index, 1] - self.corners[index, 0])
        if eye_parameters is None:
            position = self.center[index]
        else:
            position = bilinear(self.corners[index:index + 1], np.float64(eye_parameters[0]),
                                np.float64(eye_parameters[1]))[0]
        return Shooter(position=position, axes=(x, y, normal), polygon=self.corners[index],
                       area=float(self.area[index]), radiosity=np.asarray(radiosity, dtype=np.float64), patch=index)


def patch_shooter(patches: Patches, index: int, radiosity: np.ndarray, eye_parameters=None) -> Shooter:
    """One-off `PatchShooters(patches).shooter(...)` (tests, tools)."""
    return PatchShooters(patches).shooter(index, radiosity, eye_parameters)


@dataclass
class Selection:
    patch: int  # -1 when nothing is left to shoot
    score: float
    residual: np.ndarray  # (3,) mean unshot radiosity of that patch
    centroid: np.ndarray  # (2,) bilinear (s, t) of that patch's unshot power centroid
    unshot: np.ndarray  # (3,) total unshot power
    last_shot: np.ndarray  # (4,) previous shot: hit fraction, reflected fraction per channel


class PatchBuffers:
    """Per-patch and per-element storage buffers shared by the selection and shooting passes."""

    def __init__(self, ctx, patches: Patches, textures: ElementTextures):
        pad = lambda a, w: np.concatenate([a, w], axis=-1).astype(np.float32)  # noqa: E731
        self.corners = ctx.buffer(pad(patches.corners, np.zeros((len(patches), 4, 1))).tobytes())
        self.normal_area = ctx.buffer(pad(patches.normal, patches.area[:, None]).tobytes())
        self.reflectance = ctx.buffer(pad(patches.reflectance, np.zeros((len(patches), 1))).tobytes())
        self.weights = ctx.buffer(textures.weights.astype(np.float32).tobytes())
        self.energy = ctx.buffer(reserve=16)
        self.energy.clear()
        # patches of one scene surface are coplanar: the visibility lookup accepts any of them
        self.plane = ctx.buffer(patches.surface.astype(np.int32).tobytes())

    def bind(self) -> None:
        for binding, buffer in enumerate((self.corners, self.normal_area, self.reflectance, self.weights, self.energy)):
            buffer.bind_to_storage_buffer(binding)
        self.plane.bind_to_storage_buffer(7)

    def release(self) -> None:
        for buffer in (self.corners, self.normal_area, self.reflectance, self.weights, self.energy, self.plane):
            buffer.release()


class Selector:
    def __init__(self, ctx, textures: ElementTextures, buffers: PatchBuffers):
        self.ctx, self.textures, self.buffers = ctx, textures, buffers
        layout = textures.layout
        self.program = gl.compute(ctx, "select_shooter.comp")
        self.program["level"] = layout.level
        self.program["patch_count"] = layout.patch_count
        self.program["tiles_per_row"] = layout.residual_tiles_per_row
        self.program["elements"] = layout.elements
        self.program["residual"] = 0
        self.result = ctx.buffer(reserve=64)

    def select(self) -> Selection:
        self.buffers.bind()
        self.result.bind_to_storage_buffer(6)
        self.textures.residual.use(0)
        self.ctx.memory_barrier()
        self.program.run(1)
        self.ctx.memory_barrier()
        raw = np.frombuffer(self.result.read(), dtype=np.float32)
        index = int(np.frombuffer(raw[1].tobytes(), dtype=np.int32)[0])
        score = float(raw[0])
        residual, unshot = raw[4:7].astype(np.float64), raw[8:11].astype(np.float64)
        if self.textures.channels == 1:  # a grey scene's one channel stands for all three
            residual, unshot = np.repeat(residual[:1], 3), np.repeat(unshot[:1], 3)
        return Selection(patch=index if score > 0 else -1, score=score, residual=residual,
                         centroid=raw[2:4].astype(np.float64), unshot=unshot, last_shot=raw[12:16].astype(np.float64))

    def release(self) -> None:
        self.program.release()
        self.result.release()


class Gatherer:
    """The shooting pass over all receiving elements."""

    def __init__(self, ctx, textures: ElementTextures, buffers: PatchBuffers, kernel: str, search_radius: int,
                 record_visibility: bool = False, occluder_margin: float = -1.0, occlusion: bool = True,
                 interreflection: bool = True):
        if kernel not in ("exact", "disk"):
            raise ValueError(f"unknown kernel '{kernel}' (choose exact, disk)")
        self.ctx, self.textures, self.buffers = ctx, textures, buffers
        layout = textures.layout
        self.program = gl.compute(ctx, "shoot_to_elements.comp", defines={
            "IMAGE_FORMAT": textures.image_format, "ELEMENTS": layout.elements, "GUTTER": layout.gutter,
            "KERNEL_EXACT": int(kernel == "exact"),
            "SEARCH_RADIUS": search_radius, "RECORD_VISIBILITY": int(record_visibility),
            "OCCLUDER_MARGIN": float(occluder_margin), "OCCLUSION": int(occlusion),
            "INTERREFLECTION": int(interreflection),
        })
        self.element_count = layout.patch_count * layout.elements ** 2
        self.program["patch_count"] = layout.patch_count
        self.program["padded_tiles_per_row"] = layout.padded_tiles_per_row
        self.program["residual_tiles_per_row"] = layout.residual_tiles_per_row
        for sampler, unit in (("item_buffer", 0), ("distance_map", 1)):
            if self.program.get(sampler, None) is not None:  # unused without occlusion
                self.program[sampler] = unit
        self.visibility = ctx.buffer(reserve=4 * self.element_count) if record_visibility else None

    def shoot(self, shooter: Shooter, visibility_map: VisibilityMap) -> None:
        vector = lambda v: tuple(map(float, v))  # noqa: E731
        uniforms = {
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
        }
        for name, value in uniforms.items():
            if self.program.get(name, None) is not None:  # a kernel may not use every uniform
                self.program[name] = value
        self.buffers.bind()
        if self.visibility is not None:
            self.visibility.bind_to_storage_buffer(5)
        visibility_map.items.use(0)
        visibility_map.distances.use(1)
        self.textures.radiosity.bind_to_image(0, read=True, write=True)
        self.textures.residual.bind_to_image(1, read=True, write=True, level=0)
        self.ctx.memory_barrier()
        groups = gl.groups(self.element_count, 64)
        rows = -(-groups // MAX_GROUPS)
        self.program.run(-(-groups // rows), rows)
        self.ctx.memory_barrier()

    def shoot_sky(self, color: np.ndarray, sky_fraction: np.ndarray, visibility_map: VisibilityMap) -> None:
        """Every element gathers ρ · color · its sky fraction ((P, S, S) array)."""
        fractions = self.ctx.buffer(np.ascontiguousarray(sky_fraction, dtype=np.float32).tobytes())
        try:
            fractions.bind_to_storage_buffer(8)
            self.shoot(Shooter(position=np.zeros(3), axes=(np.eye(3)[0], np.eye(3)[1], np.eye(3)[2]),
                               polygon=np.zeros((4, 3)), area=0.0, radiosity=np.asarray(color), kind=3),
                       visibility_map)
        finally:
            fractions.release()

    def recorded_visibility(self) -> np.ndarray:
        """(P * S * S,) visibility of each element in the last shot (only with record_visibility)."""
        return np.frombuffer(self.visibility.read(), dtype=np.float32).copy()

    def release(self) -> None:
        self.program.release()
        if self.visibility is not None:
            self.visibility.release()
