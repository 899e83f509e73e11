"""A furnished room (rooms.py) baked stage by stage as the add-on bakes it, each stage's seconds
and peak memory recorded: what tools/measure_scaling.py plots against the room's size and what
tests/bench/test_scaling.py compares between two sizes.

Stages: export (the evaluated meshes, lamps and world), material maps (Cycles' albedo and
emission bakes), the core solve's own stages (analyse, subdivide, refine, direct light, shots or
form factors and the linear solve, ...), lightmaps, and the write-back into the file. All run in
this process (no solver child), so its memory is the solve's. A stage's peak memory is the
resident set's high-water mark while it ran (Linux: /proc/self/clear_refs resets it when a stage
starts; elsewhere the peak so far). `bake_room_with_cycles` times Cycles on the same room, into
lightmaps of the same sizes (the peer of issue 13's scaling curve).
"""

from __future__ import annotations

import contextlib
import re
import time
from pathlib import Path

import bpy

from radiosity_addon import core
from radiosity_addon.blender import apply
from radiosity_addon.blender.bake import baked_materials, choose_objects
from radiosity_addon.blender.export import export_scene
from radiosity_addon.blender.headless import ensure_registered
from radiosity_addon.blender.lights import render_lamps
from . import rooms


def high_water_mb() -> float:
    """The resident set's peak since the last reset, MiB (0 where /proc is not there)."""
    try:
        with open("/proc/self/status") as status:
            return int(re.search(r"VmHWM:\s+(\d+)", status.read()).group(1)) / 1024
    except OSError:
        return 0.0


def reset_high_water() -> None:
    with contextlib.suppress(OSError), open("/proc/self/clear_refs", "w") as refs:
        refs.write("5")


class Stages:
    """Seconds and peak MiB per named stage. Stages may nest (refinement runs direct-light shots):
    an inner stage's time and peak count in the stages around it too."""

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.peak_mb: dict[str, float] = {}
        self.open: list[str] = []

    def _peak(self, names, value: float) -> None:
        for name in names:
            self.peak_mb[name] = max(self.peak_mb.get(name, 0.0), value)

    @contextlib.contextmanager
    def stage(self, name: str):
        self._peak(self.open, high_water_mb())  # the enclosing stages' peak before the reset
        reset_high_water()
        self.open.append(name)
        started = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - started
            self.open.pop()
            self._peak(self.open + [name], high_water_mb())


class MeasuredTimer(core.StageTimer):
    """The core's stage timer, recording each stage into `stages` too (with its peak memory)."""

    def __init__(self, stages: Stages):
        super().__init__()
        self.stages = stages

    @contextlib.contextmanager
    def stage(self, name: str):
        with self.stages.stage(name), super().stage(name):
            yield


def bake_room_in_stages(triangles: int, solve: dict, lightmaps: dict | None = None, material_maps: bool = True) -> dict:
    """Build the room of `triangles` and bake all its meshes with the panel's settings and `solve`
    (SolveSettings fields; a "quality" first sets its preset) and `lightmaps` replaced. Without
    `material_maps` the surfaces keep their materials' mean colours (no Cycles bake)."""
    return bake_in_stages(lambda: rooms.build_room(triangles), triangles, solve, lightmaps, material_maps)


def bake_production_in_stages(triangles: int, solve: dict, objects: int = 10, lightmaps: dict | None = None) -> dict:
    """The same for the production terrace (production.py) of `triangles` in about `objects` objects."""
    from . import production
    return bake_in_stages(lambda: production.build_production(triangles, objects), triangles, solve, lightmaps)


def bake_in_stages(build, triangles: int, solve: dict, lightmaps: dict | None = None, material_maps: bool = True) -> dict:
    """`build()` a scene (its summary: "triangles"), then bake its meshes stage by stage."""
    built = build()
    ensure_registered()
    context = bpy.context
    objects = choose_objects(context, [obj for obj in context.scene.objects if obj.type == "MESH"])
    options = context.scene.radiosity.bake_options(objects).overridden(dict(solve), lightmaps)
    stages = Stages()
    started = time.perf_counter()
    with stages.stage("export"):
        exported = export_scene(context.evaluated_depsgraph_get(), objects, lamps=render_lamps(context.view_layer),
                                world=context.scene.world)
    scene, factors = exported.scene, {}
    if material_maps:
        with stages.stage("material maps"):
            scene, factors = baked_materials(context, exported, objects, options)
    with core.open_gpu() as gpu:
        with stages.stage("job"):  # what the solver process reads (solver_process/protocol.py)
            job_bytes = job_size(scene)
        solution = core.solve(scene, options.solve, gpu=gpu, timer=MeasuredTimer(stages))
        with stages.stage("lightmaps"):
            lightmaps_made = core.bake_lightmaps(scene, solution, options.lightmaps, gpu=gpu,
                                                 objects=list(exported.baked_objects))
            images = {name: lightmap.filled_image() for name, lightmap in lightmaps_made.items()}
    with stages.stage("write-back"):
        written = apply.write_images(images, "PACK", None)
        apply.show_lightmaps(objects, written, options.lightmaps.content, factors)
    report = solution.report.to_dict()
    return {"triangles_target": triangles, "triangles": built["triangles"], "method": report["method"],
            "patches": report["counts"]["patches"], "elements": report["counts"].get("elements"),
            "shots": report.get("shots"), "why": (report.get("method_choice") or {}).get("reason"),
            "seconds": time.perf_counter() - started, "stage_seconds": stages.seconds,
            "stage_peak_mb": stages.peak_mb, "texels": int(sum(i.shape[0] * i.shape[1] for i in images.values())),
            "clusters": report["counts"].get("clusters", 0), "objects": len(objects), "job_mb": job_bytes / 2 ** 20,
            "sizes": {name: [int(image.shape[1]), int(image.shape[0])] for name, image in images.items()}}


def job_size(scene) -> int:
    """Bytes of the scene's arrays file, as the solver process gets it, written and read back here."""
    import tempfile

    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / "scene.npz"
        core.save_scene(scene, path)
        core.load_scene(path, require_emitter=False)
        return path.stat().st_size


def bake_room_with_cycles(triangles: int, sizes: dict, samples: int, directory, family: str = "rooms",
                          objects: int = 10) -> dict:
    """The same room (built again: it is deterministic; or the production terrace in `objects`
    objects) saved in `directory` and baked by Cycles into lightmaps of `sizes` ({object: [width,
    height]}: ours) at `samples` per texel, all objects in one bake call
    (blend_reference.bake_lightmaps): its seconds and this process's peak memory."""
    from . import blend_reference, production
    if family == "production":
        path = Path(directory) / f"production_{triangles}_{objects}.blend"
        built = production.save_production(path, triangles, objects)
    else:
        path = Path(directory) / f"room_{triangles}.blend"
        built = rooms.save_room(path, triangles)
    reset_high_water()
    bake = blend_reference.bake_lightmaps(path, sizes, "combined", samples, seed=1)
    return {"triangles_target": triangles, "triangles": built["triangles"], "method": f"cycles {samples} spp",
            "seconds": bake["seconds"], "peak_mb": high_water_mb(),
            "texels": int(sum(w * h for w, h in sizes.values()))}
