"""`python -m radiosity_addon bake FILE.blend ...`: the add-on's bake without Blender's UI.

Runs with the `bpy` module (or inside `blender -b --python`): opens the file,
registers the add-on if Blender has not, bakes through the same transaction as
the operator and saves EXRs and/or a copy of the file.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import bpy

from .bake import bake_blocking
from .errors import BakeError


@dataclass
class HeadlessBake:
    """A bake of a .blend without the UI: the file's own settings, with the given ones replaced."""
    file: str
    solve_options: dict = field(default_factory=dict)  # SolveSettings fields to replace
    lightmap_options: dict = field(default_factory=dict)  # LightmapSettings fields to replace
    objects: str | None = None  # "A,B": the objects to bake (default: every visible mesh)
    output_dir: str | None = None  # EXR lightmaps into this folder
    save_as: str | None = None  # the baked file
    preview: str | None = None  # a Cycles render of the baked file
    preview_size: int = 256


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


def bake_file(request: HeadlessBake, progress=None):
    """Bake the file; returns (summary line, the solve's report dict). User errors raise BakeError
    (one line). The settings stored in the file (`scene.radiosity`) are read, never changed.
    progress(BakeClock), if given, is called ten times a second while the solver runs."""
    path = Path(request.file)
    if not path.is_file():
        raise BakeError(f"file '{request.file}' does not exist")
    if request.output_dir is None and request.save_as is None:
        raise BakeError("nothing would be kept: give --output-dir DIR (EXR lightmaps) and/or --save-as OUT.blend")
    bpy.ops.wm.open_mainfile(filepath=str(path.resolve()), load_ui=False)
    ensure_registered()
    objects = chosen_objects(request.objects)
    options = bpy.context.scene.radiosity.bake_options(objects).overridden(request.solve_options,
                                                                           request.lightmap_options)
    if request.output_dir is None:
        options.output = "PACK"
    plan = bake_blocking(bpy.context, options, objects=objects,
                         output_dir=Path(request.output_dir).resolve() if request.output_dir else None,
                         on_progress=progress)
    for line in plan.warnings:
        print(f"warning: {line}", file=sys.stderr)
    if request.save_as is not None:
        target = Path(request.save_as).resolve()
        target.parent.mkdir(parents=True, exist_ok=True)
        bpy.ops.wm.save_as_mainfile(filepath=str(target), relative_remap=True)
    if request.preview is not None:
        render_preview(Path(request.preview).resolve(), request.preview_size)
    return plan.summary, plan.report
