"""Cycles' own answer on a .blend, baked into each mesh's 'Lightmap' UV map: the reference our
lightmaps of the same file are compared with (compare.py).

The file is baked as its author made it: its materials, lamps, world, modifiers and two-sided
faces (emissive backs included) are left alone. Only the render settings are set (Cycles on the
CPU, no clamping, MAX_BOUNCES diffuse bounces, no denoising, no adaptive sampling, a fixed
seed), and what a bake needs is added in memory, never saved: a target image node in each
material, a copy of a material that two baked objects share (an image node can hold only one
object's image; the copy shades the same), and Blender's default material for an object that has
none (Cycles renders it so: `default_materials`). All objects are baked in one `bpy.ops.object.bake`
call per content, each into its own image.

Two contents:
- "combined": the Combined pass, outgoing radiance B (emission included);
- "light": the Diffuse pass, Direct + Indirect without Color: the light H arriving at the surface,
  in the units where a diffuse surface gives B = E + ρH.

Cycles bakes a face's front (the side its normal points to): light reaching only its back bakes black.

`cycles_lightmaps` caches each bake on disk (key: the file's content hash, the content, samples,
seed, sizes and these settings); `reference_with_noise` averages two seeds and gives half their
difference as the reference's own noise.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import bpy
import numpy as np

from .cycles import quiet_stdout, reproducible_cycles

CONTENTS = ("combined", "light")
MAX_BOUNCES = 128
UV_MAP = "Lightmap"
SETTINGS_VERSION = 1  # in the cache key: change it when the bake settings below change
TARGET_NODE = "Reference Bake Target"


def _bake_settings(scene, content: str) -> str:
    """Pass settings of `content`; returns the bake type."""
    bake = scene.render.bake
    bake.use_pass_direct = bake.use_pass_indirect = True
    if content == "combined":
        bake.use_pass_diffuse = bake.use_pass_glossy = bake.use_pass_transmission = bake.use_pass_emit = True
        return "COMBINED"
    bake.use_pass_color = False
    return "DIFFUSE"


def _shared_materials(objects) -> set:
    users: dict = {}
    for obj in objects:
        for material in {slot.material for slot in obj.material_slots}:
            users[material] = users.get(material, 0) + 1
    return {material for material, count in users.items() if count > 1}


def default_materials(obj) -> None:
    """Give an object without a material (no slot, or an empty one) a new material, which Blender
    makes as its default surface: Cycles renders a mesh without a material exactly so (measured: a
    render with either is the same to the last bit), and a bake needs a material to hold its image
    node. Each object gets its own; a mesh without slots gets one slot (every user of the mesh
    renders it alike)."""
    def default():
        material = bpy.data.materials.new(f"{obj.name} default surface (reference bake only)")
        if material.node_tree is None:  # Blender 4.x makes the node tree on request
            material.use_nodes = True
        return material

    if not obj.material_slots:
        obj.data.materials.append(None)
    for slot in obj.material_slots:
        if slot.material is None:
            slot.link = "OBJECT"
            slot.material = default()


def add_bake_targets(objects, sizes: dict) -> dict:
    """One zeroed float image per object, the active image node of each of its materials; a
    material shared between baked objects is copied for each of them, an object without a material
    gets Blender's default one. Returns {name: image}."""
    for obj in objects:
        if UV_MAP not in obj.data.uv_layers:
            raise ValueError(f"object '{obj.name}' has no '{UV_MAP}' UV map")
        default_materials(obj)
    shared = _shared_materials(objects)
    images = {}
    for obj in objects:
        width, height = sizes[obj.name]
        image = bpy.data.images.new(f"reference {obj.name}", width, height, alpha=True, float_buffer=True)
        image.pixels.foreach_set(np.zeros(width * height * 4, dtype=np.float32))  # alpha 0: not baked
        images[obj.name] = image
        copies = {}
        for slot in obj.material_slots:
            material = slot.material
            if material in shared:
                material = copies.setdefault(material, material.copy())
                slot.link = "OBJECT"  # this object's own material; the mesh keeps the original
                slot.material = material
            tree = material.node_tree
            target = tree.nodes.get(TARGET_NODE) or tree.nodes.new("ShaderNodeTexImage")
            target.name = TARGET_NODE
            target.image = image
            tree.nodes.active = target
    return images


def _select(objects) -> None:
    view_layer = bpy.context.view_layer
    for other in view_layer.objects:
        other.select_set(False)
    for obj in objects:
        obj.select_set(True)
    view_layer.objects.active = objects[0]


def bake_lightmaps(path, sizes: dict, content: str, samples: int, seed: int = 0, threads: int | None = None,
                   one_call: bool = True) -> dict:
    """Open `path` and bake the objects of `sizes` ({name: (width, height)}) with Cycles.
    Returns {"images": {name: float32 (H, W, 4)}, alpha 1 where baked, "seconds": the bake
    calls' wall time}. `one_call=False` bakes object by object (to check that one call is the same)."""
    if content not in CONTENTS:
        raise ValueError(f"content must be one of {CONTENTS}, got {content!r}")
    bpy.ops.wm.open_mainfile(filepath=str(Path(path).resolve()), load_ui=False)
    missing = [name for name in sizes if bpy.data.objects.get(name) is None]
    if missing:
        raise ValueError(f"{path}: no object named {', '.join(map(repr, missing))}")
    scene = bpy.context.scene
    reproducible_cycles(scene, samples, seed, MAX_BOUNCES, threads)
    bake_type = _bake_settings(scene, content)
    objects = [bpy.data.objects[name] for name in sizes]
    images = add_bake_targets(objects, sizes)
    started = time.perf_counter()
    for batch in ([objects] if one_call else [[obj] for obj in objects]):
        _select(batch)
        with quiet_stdout():
            bpy.ops.object.bake(type=bake_type, uv_layer=UV_MAP, margin=0, use_clear=False,
                                target="IMAGE_TEXTURES")
    seconds = time.perf_counter() - started
    baked = {}
    for name, image in images.items():
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        baked[name] = pixels.reshape(height, width, 4)
    return {"images": baked, "seconds": seconds}


def file_hash(path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def cache_key(path, sizes: dict, content: str, samples: int, seed: int) -> str:
    described = {"file": file_hash(path), "content": content, "samples": samples, "seed": seed,
                 "sizes": sorted([name, list(size)] for name, size in sizes.items()),
                 "settings": SETTINGS_VERSION, "blender": bpy.app.version_string}
    return hashlib.sha256(json.dumps(described, sort_keys=True).encode()).hexdigest()[:20]


def cycles_lightmaps(path, sizes: dict, content: str, samples: int, seed: int = 0, cache_dir=None,
                     threads: int | None = None) -> dict:
    """bake_lightmaps(...), from the cache in `cache_dir` when it holds this bake (None: no cache).
    The result's "cached" says which."""
    cache = None
    if cache_dir is not None:
        cache = Path(cache_dir) / f"cycles_{content}_{cache_key(path, sizes, content, samples, seed)}.npz"
        if cache.exists():
            with np.load(cache) as stored:
                names = json.loads(str(stored["names"]))
                return {"images": {name: stored[f"image_{i}"] for i, name in enumerate(names)},
                        "seconds": float(stored["seconds"]), "cached": True}
    result = bake_lightmaps(path, sizes, content, samples, seed, threads)
    if cache is not None:
        cache.parent.mkdir(parents=True, exist_ok=True)
        names = list(result["images"])
        np.savez_compressed(cache, names=json.dumps(names), seconds=result["seconds"],
                            **{f"image_{i}": result["images"][name] for i, name in enumerate(names)})
    return {**result, "cached": False}


REFERENCE_SEEDS = (1, 2)
# Cycles' own rows against the reference bake with a seed of their own: with the reference's first
# seed, their samples are correlated with half of it and they look closer to it than they are
# (measured on the Cornell box against 512 x 2: 1024 samples 1.54 % with seed 1, 1.77 % with seed 3)
ROW_SEED = 3


def reference_with_noise(path, sizes: dict, content: str, samples: int, seeds=REFERENCE_SEEDS, cache_dir=None,
                         threads: int | None = None) -> dict:
    """The mean of two seeds' bakes and its noise: {"images" (mean, alpha: baked by both),
    "noise" (half their difference, alpha as images), "seconds" (both bakes), "samples" (per seed)}."""
    first, second = (cycles_lightmaps(path, sizes, content, samples, seed, cache_dir, threads) for seed in seeds)
    images, noise = {}, {}
    for name, a in first["images"].items():
        b = second["images"][name]
        alpha = np.minimum(a[..., 3:], b[..., 3:])
        images[name] = np.concatenate([(a[..., :3] + b[..., :3]) / 2, alpha], axis=-1)
        noise[name] = np.concatenate([(a[..., :3] - b[..., :3]) / 2, alpha], axis=-1)
    return {"images": images, "noise": noise, "seconds": first["seconds"] + second["seconds"], "samples": samples}
