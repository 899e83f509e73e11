"""The shooting pass: one dispatch over all receiving elements adds the light of a batch of
shots, given their records and the visibility rendered from them (`shots.ShotVisibility`;
dissertation §4.2; Coombe et al. 2004).

Both methods use it: progressive refinement for every shot, the hemi-cube method for the lamps
and the sky (one element per patch). `PatchBuffers` holds the per-patch storage buffers the
shooting pass and the shooter selection read.
"""

from __future__ import annotations

import numpy as np

from ..gpu import MAX_WORK_GROUPS, SHOT_ENERGY_ONE, Resources, image_unit, storage, work_groups
from ..scene import Patches
from .elements import ElementTextures
from .shooters import SKY, Shooter
from .shots import MAX_SHOTS, ShotVisibility, patch_planes, shoot_in_batches


def set_uniforms(program, uniforms: dict) -> None:
    for name, value in uniforms.items():
        if program.get(name, None) is not None:  # a kernel may not use every uniform
            program[name] = value


def dispatch(program, count: int) -> None:
    """Run `program` over `count` invocations of 64, rows past the portable group limit in y."""
    groups = work_groups(count, 64)
    rows = -(-groups // MAX_WORK_GROUPS)
    program.run(-(-groups // rows), rows)


class PatchBuffers:
    """Per-patch and per-element storage buffers shared by the selection and shooting passes."""

    def __init__(self, res: Resources, patches: Patches, textures: ElementTextures,
                 cluster_of: np.ndarray | None = None):
        pad = lambda a, w: np.concatenate([a, w], axis=-1).astype(np.float32)  # noqa: E731
        self.buffers = {
            "PATCH_CORNERS": res.buffer(pad(patches.corners, np.zeros((len(patches), 4, 1))).tobytes()),
            "PATCH_NORMAL_AREA": res.buffer(pad(patches.normal, patches.area[:, None]).tobytes()),
            # what is reflected into the residual: an alpha-cut patch reflects on its opaque share only
            # (shots use its whole polygon), its B = E + ρ H holds where it is opaque
            "PATCH_REFLECTANCE": res.buffer(pad(patches.reflectance * patches.coverage[:, None],
                                                np.zeros((len(patches), 1))).tobytes()),
            "ELEMENT_WEIGHTS": res.buffer(textures.weights.astype(np.float32).tobytes()),
            "SHOT_ENERGY": res.buffer(reserve=16 * MAX_SHOTS),  # per shot: hit, reflected RGB
            "PATCH_PLANE": res.buffer(patch_planes(patches, cluster_of)),
        }
        self.buffers["SHOT_ENERGY"].clear()

    def bind(self, *names: str) -> None:
        """Bind the named buffers (all of them by default) to their binding points."""
        for name in names or self.buffers:
            self.buffers[name].bind_to_storage_buffer(storage(name))


class ShootingPass:
    """The shooting pass over all receiving elements, a batch of shots per dispatch."""

    def __init__(self, res: Resources, textures: ElementTextures, buffers: PatchBuffers, kernel: str,
                 visibility: ShotVisibility, record_visibility: bool = False, interreflection: bool = True):
        if kernel not in ("exact", "disk"):
            raise ValueError(f"unknown kernel '{kernel}' (choose exact, disk)")
        self.res, self.ctx, self.textures, self.buffers = res, res.ctx, textures, buffers
        self.visibility_source = visibility
        layout = textures.layout
        self.defines = {
            "ELEMENT_FORMAT": textures.image_format, "ELEMENTS": layout.elements, "GUTTER": layout.gutter,
            "KERNEL_EXACT": int(kernel == "exact"), "RECORD_VISIBILITY": int(record_visibility),
            "INTERREFLECTION": int(interreflection), "HIDE_BEHIND_OCCLUDERS": 1, **visibility.defines,
        }
        self.element_count = layout.patch_count * layout.elements ** 2
        self.layout_uniforms = {"patch_count": layout.patch_count, "padded_tiles_per_row": layout.padded_tiles_per_row,
                                "residual_tiles_per_row": layout.residual_tiles_per_row}
        self.visibility = res.buffer(reserve=4 * self.element_count) if record_visibility else None

    def shoot(self, shooters: list[Shooter]) -> None:
        """One batch (at most the visibility's capacity; a sun or the sky alone)."""
        self.gather(self.visibility_source.prepare(shooters))

    def gather(self, uniforms: dict) -> None:
        """The dispatch for the batch the visibility has prepared (`ShotVisibility.prepare`)."""
        source = self.visibility_source  # the variant for what the batch holds (compiled once each)
        program = self.res.gpu.compute("shoot_to_elements.comp", defines={
            **self.defines, "SHOT_KINDS": source.batch_kinds, "VISIBILITY_LOOKUP": source.batch_lookup})
        set_uniforms(program, {**self.layout_uniforms, **uniforms})
        self.buffers.bind()
        if self.visibility is not None:
            self.visibility.bind_to_storage_buffer(storage("RECORDED_VISIBILITY"))
        self.textures.light.bind_to_image(image_unit("LIGHT"), read=True, write=True)
        self.textures.residual.bind_to_image(image_unit("RESIDUAL"), read=True, write=True, level=0)
        self.ctx.memory_barrier()
        dispatch(program, self.element_count)
        self.ctx.memory_barrier()

    def shoot_all(self, shooters: list[Shooter]) -> int:
        """Every shooter, in batches; returns the batches."""
        return shoot_in_batches(self.shoot, self.visibility_source, shooters)

    def read_energy(self, count: int) -> np.ndarray:
        """(count, 4) float64 per shot of the last batches since the previous read: the hit fraction
        and the reflected fractions (RGB) of its power; the sums restart at zero."""
        buffer = self.buffers.buffers["SHOT_ENERGY"]
        sums = np.frombuffer(buffer.read(size=16 * count), dtype=np.uint32).reshape(count, 4)
        buffer.clear()
        return sums.astype(np.float64) / SHOT_ENERGY_ONE

    def shoot_sky(self, color: np.ndarray, sky_fraction: np.ndarray) -> None:
        """Every element gathers ρ · color · its sky fraction ((P, S, S) array)."""
        with self.res.gpu.resources() as scoped:
            fractions = scoped.buffer(np.ascontiguousarray(sky_fraction, dtype=np.float32).tobytes())
            fractions.bind_to_storage_buffer(storage("SKY_FRACTION"))
            self.shoot([Shooter(position=np.zeros(3), axes=(np.eye(3)[0], np.eye(3)[1], np.eye(3)[2]),
                                polygon=np.zeros((4, 3)), area=0.0, radiosity=np.asarray(color), kind=SKY)])

    def recorded_visibility(self) -> np.ndarray:
        """(P * S * S,) visibility of each element in the last batch's first shot (record_visibility)."""
        return np.frombuffer(self.visibility.read(), dtype=np.float32).copy()
