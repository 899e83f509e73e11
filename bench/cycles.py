"""A Cycles bake of a core Scene through the `bpy` module: the benchmark's peer and reference.

Each surface becomes its own mesh object whose one face fills the unit UV square
(quads: (0,0) (1,0) (1,1) (0,1); triangles: (0,0) (1,0) (0,1)), so texel (row t,
column s) of its bake lies at the surface's own bilinear/barycentric parameters —
the same parameters `core.subdivide` splits on. Materials are purely
diffuse Principled BSDFs (roughness 1, specular IOR level 0) with the surface's
emission, and black on their back (the core's surfaces emit and receive only on
the front). The Combined bake of a diffuse surface is its outgoing radiance, in
the units of Blender's emission: the units of our radiosity (docs/architecture.md, Units).

Only this module of the benchmark imports bpy; it calls `bake_scene` and gets numpy back.
"""

from __future__ import annotations

import time

import numpy as np

from radiosity_addon.blender.material_bake import quiet_stdout

QUAD_UV = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
TRIANGLE_UV = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
MAX_BOUNCES = 256  # Russian roulette ends paths long before; no truncation bias


def _set_input(node, names, value):
    """Set the first socket of `names` that exists (socket names moved between Blender versions)."""
    for name in names:
        if name in node.inputs:
            node.inputs[name].default_value = value
            return
    raise KeyError(f"{node.bl_idname} has none of the inputs {names}")


def _material(bpy, surface, image):
    material = bpy.data.materials.new(f"{surface.name}_material")
    if material.node_tree is None:  # Blender < 5 makes the node tree only on request
        material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    output = nodes.new("ShaderNodeOutputMaterial")
    front = nodes.new("ShaderNodeBsdfPrincipled")
    _set_input(front, ["Base Color"], (*surface.reflectance, 1.0))
    _set_input(front, ["Roughness"], 1.0)
    _set_input(front, ["Specular IOR Level", "Specular"], 0.0)
    emission = np.asarray(surface.emission, dtype=np.float64)
    strength = float(emission.max())
    if strength > 0:
        _set_input(front, ["Emission Color", "Emission"], (*(emission / strength), 1.0))
        _set_input(front, ["Emission Strength"], strength)
    back = nodes.new("ShaderNodeBsdfDiffuse")  # black absorber: the back neither emits nor reflects
    _set_input(back, ["Color"], (0.0, 0.0, 0.0, 1.0))
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(front.outputs["BSDF"], mix.inputs[1])
    links.new(back.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    target = nodes.new("ShaderNodeTexImage")  # the bake target: the active image node
    target.image = image
    nodes.active = target
    return material


def _surface_object(bpy, surface, resolution):
    mesh = bpy.data.meshes.new(surface.name)
    vertices = [tuple(map(float, v)) for v in surface.vertices]
    mesh.from_pydata(vertices, [], [list(range(len(vertices)))])
    uv_layer = mesh.uv_layers.new(name="UVMap")
    for loop, uv in zip(mesh.polygons[0].loop_indices, TRIANGLE_UV if surface.is_triangle else QUAD_UV):
        uv_layer.data[loop].uv = uv
    mesh.update()
    image = bpy.data.images.new(f"{surface.name}_bake", resolution, resolution, alpha=False, float_buffer=True)
    mesh.materials.append(_material(bpy, surface, image))
    obj = bpy.data.objects.new(surface.name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj, image


def reproducible_cycles(scene, samples: int, seed: int, bounces: int, threads: int | None = None) -> None:
    """Render settings for an unbiased, repeatable bake: Cycles on the CPU, `samples` everywhere
    (no adaptive sampling), a fixed seed, `bounces` diffuse bounces, no clamping, no denoising."""
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = seed
    cycles.use_animated_seed = False
    cycles.max_bounces = cycles.diffuse_bounces = bounces
    cycles.sample_clamp_direct = 0.0  # clamping biases the answer; a reference must not clamp
    cycles.sample_clamp_indirect = 0.0
    if threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = threads


def _configure_cycles(bpy, samples: int, seed: int, threads: int | None):
    scene = bpy.context.scene
    reproducible_cycles(scene, samples, seed, MAX_BOUNCES, threads)
    cycles = scene.cycles
    cycles.glossy_bounces = 0
    cycles.transmission_bounces = 0
    cycles.volume_bounces = 0
    cycles.transparent_max_bounces = 0
    cycles.caustics_reflective = False
    cycles.caustics_refractive = False
    world = bpy.data.worlds.new("black")
    world.color = (0.0, 0.0, 0.0)
    if world.node_tree is not None:
        for node in world.node_tree.nodes:
            if node.type == "BACKGROUND":
                node.inputs["Strength"].default_value = 0.0
    scene.world = world
    bake = scene.render.bake
    bake.use_pass_direct = bake.use_pass_indirect = True
    bake.use_pass_emit = bake.use_pass_diffuse = True
    bake.margin = 0


def bake_scene(scene, resolution: int, samples: int, seed: int = 0, threads: int | None = None) -> dict:
    """Bake every surface of a core `Scene` at `resolution`² texels and `samples` paths per texel.

    Texels within about two texels of a surface's edge mix in samples from past the edge (an
    emitter's baked emission wobbles there by several per cent): compare interior texels.

    Returns {"texels": (surfaces, resolution, resolution, 3) float64 indexed [surface, t row, s column],
    "seconds": wall time of the bake call alone}. Resets the bpy session to factory settings.
    """
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    _configure_cycles(bpy, samples, seed, threads)
    objects, images = zip(*(_surface_object(bpy, s, resolution) for s in scene.surfaces))
    view_layer = bpy.context.view_layer
    for obj in objects:
        obj.select_set(True)
    view_layer.objects.active = objects[0]
    started = time.perf_counter()
    with quiet_stdout():
        bpy.ops.object.bake(type="COMBINED", margin=0, use_clear=True)
    seconds = time.perf_counter() - started
    texels = np.empty((len(images), resolution, resolution, 3), dtype=np.float64)
    pixels = np.empty(resolution * resolution * 4, dtype=np.float32)
    for index, image in enumerate(images):
        image.pixels.foreach_get(pixels)  # rows bottom-up: row t of the image is v = (t + 0.5) / R
        texels[index] = pixels.reshape(resolution, resolution, 4)[..., :3]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return {"texels": texels, "seconds": seconds}


def bake_object(obj, width: int, height: int, samples: int, bake_type: str = "COMBINED",
                uv_layer: str = "Lightmap") -> np.ndarray:
    """Cycles' bake of one object of the open file into a new float image on `uv_layer`:
    (height, width, 4) RGBA, alpha 1 where the bake wrote. Uses the file's own Cycles settings;
    `samples` sets only the sample count."""
    import bpy

    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = samples
    image = bpy.data.images.new(f"cycles {obj.name}", width, height, alpha=True, float_buffer=True)
    image.pixels.foreach_set(np.zeros(width * height * 4, dtype=np.float32))
    for slot in obj.material_slots:
        tree = slot.material.node_tree
        target = tree.nodes.get("cycles bake target") or tree.nodes.new("ShaderNodeTexImage")
        target.name = "cycles bake target"
        target.image = image
        tree.nodes.active = target
    view_layer = bpy.context.view_layer
    for other in view_layer.objects:
        other.select_set(other is obj)
    view_layer.objects.active = obj
    with quiet_stdout():
        bpy.ops.object.bake(type=bake_type, uv_layer=uv_layer, margin=0, use_clear=False)
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)
