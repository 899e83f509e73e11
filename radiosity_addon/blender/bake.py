"""The bake as a transaction: prepare (main thread) -> solve (a child process) -> finish or roll back.

`prepare` may add 'Lightmap' UV maps and a progressive bake in the UI shows a live preview;
`rollback` takes both back, so a cancelled or failed bake leaves the .blend exactly as it was.
`finish` writes the images and switches the shading only once the solve has succeeded.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import core
from ..core import USER_ERRORS as CORE_USER_ERRORS
from ..core import SolveCancelled, SolveError
from . import apply
from .errors import BakeError
from .export import check_emitters, export_scene
from .lightmap_uv import add_lightmap_uvs, remove_lightmap_uvs
from .material_bake import (bake_material_maps_steps, principled_diffuse_factors, run_steps, uniform_material_values,
                            uniform_materials)
from .progress import BakeClock
from .lights import render_lamps
from .live_preview import LivePreview
from .options import BakeOptions
from .worker import BakeWorker

# errors the user can cause: reported as their message, one line
USER_ERRORS = (BakeError,) + CORE_USER_ERRORS


@dataclass
class BakePlan:
    objects: list  # bpy objects that get lightmaps
    worker: BakeWorker
    output: str  # 'PACK' or 'EXR'
    directory: Path | None
    added_uv_meshes: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    started: float = field(default_factory=time.monotonic)
    report: dict = field(default_factory=dict)  # the solve's report (its JSON), once finished
    scene: object = None  # the bpy scene baked: its settings record what the bake simulated
    summary: str = ""
    content: str = "light"  # what the lightmaps hold, and so how the materials show them
    diffuse_factors: dict = field(default_factory=dict)  # material -> Principled node -> RGB (light content)
    instances: int = 0  # instanced geometries that took part without a lightmap
    preview: LivePreview | None = None  # made by the first snapshot of a progressive bake in the UI


def choose_objects(context, objects=None) -> list:
    """The mesh objects to bake: `objects` if given, else the selection. Refuses an unusable choice."""
    chosen = list(objects) if objects is not None else list(context.selected_objects)
    if not chosen:
        raise BakeError("select the mesh objects to bake first")
    meshes = [obj for obj in chosen if obj.type == "MESH"]
    if not meshes:
        kinds = ", ".join(sorted({obj.type.lower() for obj in chosen}))
        raise BakeError(f"no mesh among the selected objects ({kinds}); select meshes to bake")
    if context.mode != "OBJECT":
        raise BakeError("switch to Object Mode to bake")
    return meshes


def prepare(context, options: BakeOptions, objects=None, output_dir=None, preview_interval=None) -> BakePlan:
    """Check, export and hand the solve to a worker (not yet started). `preview_interval`: seconds
    between live previews of a progressive solve (None: none)."""
    return run_steps(prepare_steps(context, options, objects, output_dir, preview_interval))


def prepare_steps(context, options: BakeOptions, objects=None, output_dir=None, preview_interval=None,
                  clock: BakeClock | None = None):
    """`prepare` a step at a time: yields what the next step does (the export, each Cycles pass of
    the materials), so the UI shows it and answers between steps; returns the plan, whose worker
    reports to `clock` (the bake's, from its start). Closed before it ends, it takes back what it
    added (the Lightmap UV maps; the material bakes undo their own changes as they close)."""
    baked = choose_objects(context, objects)
    try:
        options.solve.validate()
        options.lightmaps.validate()
    except SolveError as error:
        raise BakeError(str(error)) from None
    output = "EXR" if output_dir is not None else options.output
    directory = Path(output_dir) if output_dir is not None else apply.default_exr_directory()
    apply.check_output(output, directory)

    added = add_lightmap_uvs(context, baked, options.uv_margin)
    try:
        yield f"exporting {len(baked)} object(s)"
        exported = export_scene(context.evaluated_depsgraph_get(), baked,
                                occluders=None if options.include_unselected else [],
                                lamps=render_lamps(context.view_layer), world=context.scene.world)
        scene, diffuse_factors = yield from baked_materials_steps(context, exported, baked, options)
    except BaseException:  # a fault, or the steps closed (Esc, a file loaded)
        remove_lightmap_uvs(added)
        raise
    worker = BakeWorker(scene, options.solve, exported.baked_objects, options.lightmaps, preview_interval, clock)
    warnings = list(exported.warnings)
    if exported.instances:
        warnings.append(f"{exported.instances} instance(s) block and reflect light but get no lightmap"
                        " (they share their mesh with others)")
    return BakePlan(objects=baked, worker=worker, output=output, directory=directory, added_uv_meshes=added,
                    warnings=warnings, scene=context.scene, content=options.lightmaps.content,
                    diffuse_factors=diffuse_factors, instances=exported.instances)


def baked_materials(context, exported, baked, options: BakeOptions):
    """The exported scene with Cycles' own albedo and emission: probed once per uniform material
    (every face made of one), baked into material maps for the baked objects with any other
    material; and the diffuse factors of their Principled BSDFs for a "light" lightmap's baked look."""
    return run_steps(baked_materials_steps(context, exported, baked, options))


def baked_materials_steps(context, exported, baked, options: BakeOptions):
    """`baked_materials` a Cycles pass at a time (`prepare_steps`)."""
    scene = exported.scene
    names, face_material = exported.material_names, exported.face_material
    object_of = {name: k for k, name in enumerate(scene.object_names)}
    try:
        uniform = uniform_materials(names)
        face_uniform = np.isin(face_material, [k for k, name in enumerate(names) if name in uniform])
        object_mapped = np.zeros(len(scene.object_names), dtype=bool)
        np.logical_or.at(object_mapped, scene.object_index, ~face_uniform)
        mapped = [obj for obj in baked if object_mapped[object_of[obj.name]]]
        probed = face_uniform & ~object_mapped[scene.object_index]
        probed_codes = np.unique(face_material[probed])
        yield f"baking {len(probed_codes)} uniform material(s) with Cycles"
        values = uniform_material_values([uniform[names[k]] for k in probed_codes])
        sizes = core.lightmap_sizes(scene, options.lightmaps, [obj.name for obj in mapped]) if mapped else {}
        maps = yield from bake_material_maps_steps(context, mapped, sizes)
        factors = {}
        if options.lightmaps.content == "light":
            yield "measuring the Principled BSDFs' diffuse part with Cycles"
            factors = principled_diffuse_factors(baked)
    except RuntimeError as error:  # Cycles refused (a message of its own)
        raise BakeError(f"Cycles could not bake the materials: {str(error).strip().splitlines()[-1]}") from None
    reflectance, emission = scene.reflectance.copy(), scene.emission.copy()
    for k in probed_codes:
        albedo, emitted = values[names[k]]
        faces = probed & (face_material == k)
        reflectance[faces] = np.clip(albedo, 0.0, core.MAX_REFLECTANCE)
        emission[faces] = np.maximum(emitted, 0.0)
    scene = dataclasses.replace(scene, reflectance=reflectance, emission=emission, material_maps=maps)
    check_emitters(scene)
    return scene, factors


def start(plan: BakePlan) -> None:
    try:
        plan.worker.start()
    except OSError as error:  # no Python to run, no temporary folder
        rollback(plan)
        raise BakeError(f"cannot start the solver process ({error.strerror or error})") from None


def show_preview(plan: BakePlan) -> bool:
    """Show the newest snapshot of the solve, if one came since the last call (then True)."""
    snapshot = plan.worker.take_preview()
    if snapshot is None:
        return False
    plan.preview = plan.preview or LivePreview(plan.objects, plan.content, plan.diffuse_factors)
    plan.preview.show(snapshot)
    return True


def rollback(plan: BakePlan) -> None:
    """Leave the file as it was before `prepare`, and end the solver process."""
    plan.worker.discard()
    if plan.preview is not None:
        plan.preview.take_back()
        plan.preview = None
    remove_lightmap_uvs(plan.added_uv_meshes)


def finish(plan: BakePlan) -> str:
    """Apply a finished worker's result, or roll back and raise its error. Returns a summary line."""
    worker = plan.worker
    if worker.error is not None or worker.result is None:
        rollback(plan)
        error = worker.error
        if isinstance(error, SolveCancelled) or worker.cancelled:
            raise SolveCancelled("bake cancelled; nothing was changed")
        if isinstance(error, USER_ERRORS):
            raise BakeError(str(error)) from None
        raise error if error is not None else BakeError("the bake stopped without a result")
    result = worker.result
    plan.report = result.report
    try:
        written = apply.write_images(result.images, plan.output, plan.directory)
    except BaseException:
        rollback(plan)
        raise
    try:
        apply.show_lightmaps(plan.objects, written, plan.content, plan.diffuse_factors)
    except BaseException:  # a bug: better unbaked and consistent than half wired
        for obj in plan.objects:
            apply.remove_bake(obj)
        rollback(plan)
        raise
    if plan.preview is not None:
        plan.preview.release()
    worker.discard(wait=False)  # its exit and its folder's removal on a thread: nothing waits for them
    seconds = time.monotonic() - plan.started
    plan.scene.radiosity.last_bake = result.summary
    return (f"baked {len(plan.objects)} object(s) in {seconds:.1f} s ({result.report['method']},"
            f" {result.report['counts']['patches']} patches)")


def bake_blocking(context, options: BakeOptions, objects=None, output_dir=None, should_cancel=None,
                  on_progress=None):
    """Scripts, background mode and the command line: the whole bake, waiting for the worker.
    Returns the finished plan: its summary line, warnings and the solve's report. `on_progress`
    (the bake's BakeClock) is called at each step of the preparation and ten times a second after."""
    clock = BakeClock()
    steps = prepare_steps(context, options, objects, output_dir, clock=clock)
    while True:
        try:
            clock.preparing(next(steps))
        except StopIteration as prepared:
            plan = prepared.value
            break
        if on_progress is not None:
            on_progress(clock)
    start(plan)
    try:
        while not plan.worker.wait(0.1):
            if should_cancel is not None and should_cancel():
                plan.worker.cancel()
            if on_progress is not None:
                on_progress(plan.worker.clock)
    except BaseException:  # Ctrl+C: end the solver, then leave the file as it was
        rollback(plan)
        raise
    plan.summary = finish(plan)
    return plan
