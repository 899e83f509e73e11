"""Direct light at lightmap resolution: the shooting pass over points (lightmap texels) instead
of element tiles, for the shots that light the scene directly — lamps, the sun and pieces of the
emissive patches (`direct.direct_shooters`) — so shadows and penumbrae are as sharp as the
lightmap can show, while the smooth indirect light comes from the solve."""

from __future__ import annotations

import numpy as np

from ..gpu import Resources, storage
from .shooters import Shooter
from .shooting_pass import dispatch, set_uniforms
from .shots import ShotVisibility, patch_planes, shoot_in_batches, singles_then_groups


class TexelReceivers:
    """Points that gather direct light: world positions (N, 3), normals (N, 3) and planes (N,)
    (the plane of the patch each lies on: `Patches.plane`), looked up in `visibility`'s items. With `columns` > 0 they gather no
    light: each shot's factor is kept apart, shot k of all those shot in column k (N, columns),
    for shots in no group (`read_columns`)."""

    def __init__(self, res: Resources, positions: np.ndarray, normals: np.ndarray,
                 planes: np.ndarray, kernel: str, visibility: ShotVisibility, columns: int = 0):
        self.ctx, self.count = res.ctx, len(positions)
        vec4 = lambda a: np.concatenate([a, np.zeros((len(a), 1))], axis=1).astype(np.float32)  # noqa: E731
        self.buffers = {
            "TEXEL_POSITION": res.buffer(vec4(positions).tobytes()),
            "TEXEL_NORMAL": res.buffer(vec4(normals).tobytes()),
            "TEXEL_PLANE": res.buffer(np.asarray(planes, dtype=np.int32).tobytes()),
            "TEXEL_LIGHT": res.buffer(np.zeros((self.count, 4), dtype=np.float32).tobytes()),
            "PATCH_PLANE": res.buffer(patch_planes(visibility.patches, planes=visibility.item_planes)),  # what the items show
        }
        self.columns, self.columns_filled = columns, 0
        if columns:
            self.buffers["TEXEL_COLUMNS"] = res.buffer(np.zeros((self.count, columns), dtype=np.float32).tobytes())
        self.visibility = visibility
        self.res = res
        self.defines = {"KERNEL_EXACT": int(kernel == "exact"), "HIDE_BEHIND_OCCLUDERS": 1,
                        "SHOT_COLUMNS": int(columns > 0), **visibility.defines}

    def shoot(self, shooters: list[Shooter]) -> None:
        """One batch (see `ShotVisibility.batches`): the shots that are no piece of a group first,
        as the shader reads them."""
        uniforms = self.visibility.prepare(singles_then_groups(shooters))
        program = self.res.gpu.compute("shoot_to_texels.comp", defines={
            **self.defines, "SHOT_KINDS": self.visibility.batch_single_kinds,
            "VISIBILITY_LOOKUP": self.visibility.batch_lookup})
        if self.columns:
            if self.columns_filled + len(shooters) > self.columns:
                raise ValueError(f"{self.columns_filled + len(shooters)} shots for {self.columns} columns")
            uniforms = {**uniforms, "column_offset": self.columns_filled, "column_stride": self.columns}
            self.columns_filled += len(shooters)
        set_uniforms(program, {"texel_count": self.count, **uniforms})
        for name, buffer in self.buffers.items():
            buffer.bind_to_storage_buffer(storage(name))
        self.ctx.memory_barrier()
        dispatch(program, self.count)
        self.ctx.memory_barrier()

    def shoot_all(self, shooters: list[Shooter]) -> int:
        """Every shooter, in batches; returns the batches."""
        return shoot_in_batches(self.shoot, self.visibility, shooters)

    def read_columns(self) -> np.ndarray:
        """(N, columns) float64: each shot's factor at each point (shots in the order shot)."""
        return np.frombuffer(self.buffers["TEXEL_COLUMNS"].read(), dtype=np.float32).reshape(
            self.count, self.columns).astype(np.float64)

    def read_light(self) -> np.ndarray:
        """(N, 3) float64 light H gathered by each point."""
        return np.frombuffer(self.buffers["TEXEL_LIGHT"].read(), dtype=np.float32).reshape(-1, 4)[:, :3].astype(
            np.float64)
