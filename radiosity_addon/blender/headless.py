"""`python -m radiosity_addon bake FILE.blend ...`: the add-on's bake without Blender's UI.

Runs with the `bpy` module (or inside `blender -b --python`): opens the file,
registers the add-on if Blender has not, bakes through the same transaction as
the operator and saves EXRs and/or a copy of the file.
"""

from __future__ import annotations

import sys
from pathlib import Path

import bpy

from ..core.solution import SolveSettings
from .bake import bake_blocking
from .errors import BakeError


class CommandLineSettings:
    """scene.radiosity with the solver settings replaced by the command line's (which has more knobs)."""

    def __init__(self, scene_settings, solve_settings: SolveSettings, texel_density=None, max_resolution=None,
                 patch_size=None):
        self._scene_settings = scene_settings
        self._solve_settings = solve_settings
        # --patch-size splits faces in the export; without it --subdiv splits every face N x N
        self.patch_mode = "SIZE" if patch_size else "SUBDIVISION"
        self.patch_size = patch_size or 0.0
        if patch_size:
            solve_settings.subdiv = 1
        if texel_density is not None:
            scene_settings.texel_density = texel_density
        if max_resolution is not None:
            scene_settings.max_resolution = max_resolution

    def solve_settings(self) -> SolveSettings:
        return self._solve_settings

    def __getattr__(self, name):
        return getattr(self._scene_settings, name)


def ensure_registered() -> None:
    """Blender with the extension enabled has registered it already; the bpy module has not."""
    if not hasattr(bpy.types.Scene, "radiosity") or not hasattr(bpy.types, "RADIOSITY_OT_bake"):
        from . import register

        register()


def chosen_objects(names: str | None) -> list:
    if names:
        wanted = [name.strip() for name in names.split(",") if name.strip()]
        missing = [name for name in wanted if name not in bpy.data.objects]
        if missing:
            raise BakeError(f"no object named {', '.join(repr(m) for m in missing)} in the file")
        return [bpy.data.objects[name] for name in wanted]
    view_layer = bpy.context.view_layer
    return [obj for obj in view_layer.objects if obj.type == "MESH" and obj.visible_get()]


def render_preview(path: Path, size: int = 256, samples: int = 8) -> None:
    """A still from the file's camera with Cycles on the CPU: the baked lightmaps are emission,
    so a few samples give a clean picture."""
    scene = bpy.context.scene
    if scene.camera is None:
        raise BakeError("the file has no camera for --preview")
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    # `size` is the longer side; the file's aspect ratio is kept
    longest = max(scene.render.resolution_x, scene.render.resolution_y)
    scene.render.resolution_percentage = max(1, min(100, round(100 * size / longest)))
    scene.render.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"
    scene.render.filepath = str(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.render.render(write_still=True)


def bake_file(blend: str, solve_settings: SolveSettings, objects: str | None = None, output_dir: str | None = None,
              save_as: str | None = None, preview: str | None = None, texel_density: float | None = None,
              max_resolution: int | None = None, preview_size: int = 256, patch_size: float | None = None,
              progress=None):
    """Bake FILE.blend; returns (summary line, the solve's report). User errors raise BakeError (one line)."""
    path = Path(blend)
    if not path.is_file():
        raise BakeError(f"file '{blend}' does not exist")
    if output_dir is None and save_as is None:
        raise BakeError("nothing would be kept: give --output-dir DIR (EXR lightmaps) and/or --save-as OUT.blend")
    bpy.ops.wm.open_mainfile(filepath=str(path.resolve()), load_ui=False)
    ensure_registered()
    scene = bpy.context.scene
    if patch_size is not None and not patch_size > 0:
        raise BakeError(f"--patch-size must be positive, got {patch_size}")
    settings = CommandLineSettings(scene.radiosity, solve_settings, texel_density, max_resolution, patch_size)
    if output_dir is None:
        scene.radiosity.output = "PACK"
    plan = bake_blocking(bpy.context, settings, objects=chosen_objects(objects),
                         output_dir=Path(output_dir).resolve() if output_dir else None, on_progress=progress)
    for line in plan.warnings:
        print(f"warning: {line}", file=sys.stderr)
    if save_as is not None:
        target = Path(save_as).resolve()
        target.parent.mkdir(parents=True, exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=str(target), relative_remap=True)
    if preview is not None:
        render_preview(Path(preview).resolve(), preview_size)
    return plan.summary, plan.report


