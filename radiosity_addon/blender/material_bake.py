"""Materials as Cycles evaluates them: the diffuse albedo (Diffuse pass, Color only) and the
emission (Emit pass) of every baked object, baked into its 'Lightmap' UVs at its lightmap's size.

These passes need no light paths, so they are cheap, and they are exactly what Cycles shades:
image and procedural textures (sRGB-decoded as Cycles does), vertex colours, node groups, Mix
and Add shaders, the default material (a Principled BSDF: diffuse albedo 0.77 of its 0.8 base),
a Principled BSDF's diffuse part (metallic m reflects (1 − m) · base diffusely).

A material that is the same everywhere (`is_uniform`: no texture, attribute or other linked
input) needs no map: Cycles bakes it once on a 2 x 2 probe plane (`uniform_material_values`), and
an object made only of such materials gets no map at all — its faces take the probed values, and
the bake costs nothing per texel. The rest: Cycles bakes into the active image node of each
material, so objects that share a material are baked in separate calls (the fewest that keep
every call's materials apart), objects without a material get Blender's default one for the
bake, and everything the bake adds is removed again: the file is left as it was.
"""

from __future__ import annotations

import contextlib
import os
import sys

import bpy
import numpy as np

from ..core import MaterialMap
from .tags import LIGHTMAP_UV, NODE_TAG, ORIGINAL_OUTPUT, original_output_node, uses_nodes

BAKE_SAMPLES = 4  # anti-aliasing within a texel: textures finer than a texel average out
MARGIN = 2  # texels extended past every chart, so texels a face only grazes hold its values
PASSES = {"albedo": ("DIFFUSE", {"COLOR"}), "emission": ("EMIT", set())}


@contextlib.contextmanager
def quiet_stdout():
    """Cycles prints one "Info: Baking map saved ..." line per image to the C stdout: silence it."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _bake_groups(objects) -> list[list]:
    """Objects split into groups in which no two share a material (greedy colouring)."""
    groups: list[tuple[list, set]] = []
    for obj in objects:
        materials = {slot.material.name for slot in obj.material_slots if slot.material is not None}
        for members, used in groups:
            if not used & materials:
                members.append(obj)
                used |= materials
                break
        else:
            groups.append(([obj], set(materials)))
    return [members for members, _ in groups]


@contextlib.contextmanager
def cycles_for_baking(scene):
    """Cycles on the CPU with the bake's settings, restored afterwards."""
    render, cycles, bake = scene.render, scene.cycles, scene.render.bake
    saved = (render.engine, cycles.device, cycles.samples, bake.margin, bake.margin_type, bake.use_clear,
             bake.target, bake.use_selected_to_active)
    try:
        render.engine = "CYCLES"
        cycles.device = "CPU"
        cycles.samples = BAKE_SAMPLES
        bake.margin, bake.margin_type, bake.use_clear = MARGIN, "EXTEND", True
        bake.target, bake.use_selected_to_active = "IMAGE_TEXTURES", False
        yield
    finally:
        (render.engine, cycles.device, cycles.samples, bake.margin, bake.margin_type, bake.use_clear,
         bake.target, bake.use_selected_to_active) = saved


@contextlib.contextmanager
def _default_materials(objects):
    """Objects (or slots) without a material get Blender's default surface for the bake."""
    default = bpy.data.materials.new("Radiosity default material (bake only)")
    if default.node_tree is None:  # Blender 4.x makes the node tree on request
        default.use_nodes = True
    changed = []
    try:
        for obj in objects:
            if len(obj.material_slots) == 0:
                obj.data.materials.append(default)
                changed.append((obj, None))
            for index, slot in enumerate(obj.material_slots):
                if slot.material is None:
                    changed.append((obj, (index, slot.link)))
                    slot.link = "OBJECT"
                    slot.material = default
        yield
    finally:
        for obj, entry in reversed(changed):
            if entry is None:
                obj.data.materials.pop(index=len(obj.data.materials) - 1)
            else:
                index, link = entry
                slot = obj.material_slots[index]
                slot.material = None
                slot.link = link
        bpy.data.materials.remove(default)


@contextlib.contextmanager
def _original_shading(objects):
    """Materials that show an earlier bake render through their own output while Cycles bakes
    them (else it would bake the lightmap's emission); every output's active flag is restored."""
    outputs = {}
    for obj in objects:
        for slot in obj.material_slots:
            material = slot.material
            if material is None or material.node_tree is None or material.get(ORIGINAL_OUTPUT) is None:
                continue
            outputs[material.name] = (material, [(n, n.is_active_output) for n in material.node_tree.nodes
                                                 if n.bl_idname == "ShaderNodeOutputMaterial"])
    try:
        for material, _ in outputs.values():
            original = original_output_node(material)
            if original is not None:
                original.is_active_output = True
        yield
    finally:
        for _, flags in outputs.values():
            for node, active in flags:
                if active:
                    node.is_active_output = True


@contextlib.contextmanager
def bake_targets(objects, images: dict):
    """Every material of `objects` gets an active Image Texture node showing its object's image."""
    added, active = [], {}
    try:
        for obj in objects:
            for slot in obj.material_slots:
                tree = slot.material.node_tree
                if slot.material.name in active:  # (embedded node trees all have one name)
                    continue
                active[slot.material.name] = (tree, tree.nodes.active)
                node = tree.nodes.new("ShaderNodeTexImage")
                node[NODE_TAG] = 1
                node.image = images[obj.name]
                tree.nodes.active = node
                added.append((tree, node))
        yield
    finally:
        for tree, node in added:
            tree.nodes.remove(node)
        for tree, previous in active.values():
            tree.nodes.active = previous


def _pixels(image) -> np.ndarray:
    width, height = image.size
    values = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(values)
    return values.reshape(height, width, 4)[..., :3].copy()


def run_steps(steps):
    """What a generator of steps (a bake's preparation, yielding what each next step does) returns,
    all its steps run at once (scripts, the command line)."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


def bake_material_maps(context, objects, sizes: dict) -> dict:
    """{object name: MaterialMap} for `objects` (each with a 'Lightmap' UV map), at `sizes`
    {object name: (width, height)}."""
    return run_steps(bake_material_maps_steps(context, objects, sizes))


def bake_material_maps_steps(context, objects, sizes: dict):
    """`bake_material_maps` a Cycles pass at a time: yields what the next pass bakes."""
    objects = [obj for obj in objects if obj.name in sizes]
    if not objects:
        return {}
    maps = {obj.name: {} for obj in objects}
    images = {obj.name: bpy.data.images.new(f"{obj.name} material bake", *sizes[obj.name], alpha=False,
                                            float_buffer=True) for obj in objects}
    view_layer = context.view_layer
    selected, active_object = [o for o in view_layer.objects if o.select_get()], view_layer.objects.active
    try:
        with cycles_for_baking(context.scene), _default_materials(objects), _original_shading(objects):
            groups = _bake_groups(objects)
            for number, group in enumerate(groups):
                with bake_targets(group, images):
                    for obj in view_layer.objects:
                        obj.select_set(obj in group)
                    view_layer.objects.active = group[0]
                    for name, (kind, passes) in PASSES.items():
                        texels = sum(sizes[obj.name][0] * sizes[obj.name][1] for obj in group)
                        yield (f"baking {len(group)} object(s)' {name} with Cycles ({texels // 1000}k texels,"
                               f" {number + 1}/{len(groups)})")
                        with quiet_stdout():
                            bpy.ops.object.bake(type=kind, pass_filter=passes, uv_layer=LIGHTMAP_UV,
                                                margin=MARGIN, margin_type="EXTEND", use_clear=True)
                        for obj in group:
                            maps[obj.name][name] = _pixels(images[obj.name])
    finally:
        for image in images.values():
            bpy.data.images.remove(image)
        for obj in view_layer.objects:
            obj.select_set(obj in selected)
        view_layer.objects.active = active_object
    return {name: MaterialMap(albedo=values["albedo"], emission=values["emission"]) for name, values in maps.items()}


# shader nodes whose albedo and emission are the same at every point while no input but their
# shader ones is linked
UNIFORM_SHADERS = {"ShaderNodeBsdfPrincipled", "ShaderNodeBsdfDiffuse", "ShaderNodeEmission", "ShaderNodeAddShader",
                   "ShaderNodeMixShader", "NodeReroute"}


def is_uniform(material) -> bool:
    """Does Cycles shade `material` with one albedo and one emission everywhere (None: Blender's
    default surface)? Its surface must be Principled, Diffuse and Emission shaders, mixed or added,
    with no linked input but the shader ones (no texture, attribute, normal map, driver node), and
    nothing on the output's Displacement. Such a material needs no map: one probe gives its values."""
    if material is None:
        return True
    if material.node_tree is None or not uses_nodes(material):
        return False
    output = original_output_node(material)
    if output is None:
        return False
    if any(socket.is_linked for socket in output.inputs if socket.name not in ("Surface", "Volume")):
        return False
    surface = output.inputs.get("Surface")
    pending = [surface.links[0].from_node] if surface is not None and surface.is_linked else []
    seen = set()
    while pending:
        node = pending.pop()
        if node.name in seen:
            continue
        seen.add(node.name)
        if node.bl_idname not in UNIFORM_SHADERS or node.mute:
            return False
        for socket in node.inputs:
            if not socket.is_linked:
                continue
            if socket.type != "SHADER" and node.bl_idname != "NodeReroute":
                return False
            pending.append(socket.links[0].from_node)
    return True


def uniform_materials(names) -> dict:
    """{name: material} of the uniform ones among material `names` (None: no material, uniform)."""
    found = {name: bpy.data.materials.get(name) if name is not None else None for name in names}
    return {name: material for name, material in found.items()
            if (material is not None or name is None) and is_uniform(material)}


def uniform_material_values(materials) -> dict:
    """{material name (None: no material): (albedo, emission)} as Cycles bakes them (Diffuse Color,
    Emit) for uniform `materials`: one 2 x 2 probe plane per material, all in one bake per pass."""
    materials = list({(m.name if m is not None else None): m for m in materials}.items())
    if not materials:
        return {}
    values = {name: {} for name, _ in materials}
    with _probe_scene() as scene:
        probes = [_probe_plane(scene, f"Radiosity material probe {k}", material, float(k))
                  for k, (_, material) in enumerate(materials)]
        objects = [obj for obj, _ in probes]
        images = {obj.name: bpy.data.images.new(f"{obj.name} bake", 2, 2, alpha=False, float_buffer=True)
                  for obj in objects}
        try:
            with _default_materials(objects), _original_shading(objects), bake_targets(objects, images):
                for kind, (pass_type, passes) in PASSES.items():
                    _bake_probes(scene, objects, pass_type, passes)
                    for (name, _), obj in zip(materials, objects):
                        values[name][kind] = _pixels(images[obj.name]).reshape(-1, 3).mean(axis=0).astype(np.float64)
        finally:
            for image in images.values():
                bpy.data.images.remove(image)
            for obj, mesh in probes:
                bpy.data.objects.remove(obj)
                bpy.data.meshes.remove(mesh)
    return {name: (entry["albedo"], entry["emission"]) for name, entry in values.items()}


def _principled_nodes(objects) -> list:
    """(material, node) of every Principled BSDF in the materials of `objects`."""
    seen, found = set(), []
    for obj in objects:
        for slot in obj.material_slots:
            material = slot.material
            if material is None or material.node_tree is None or material.name in seen:
                continue
            seen.add(material.name)
            found += [(material, node) for node in material.node_tree.nodes
                      if node.bl_idname == "ShaderNodeBsdfPrincipled"]
    return found


@contextlib.contextmanager
def _probe_scene():
    """A scene of its own for probe planes, with Cycles' bake settings: a bake there syncs the
    probes alone, not the user's scene (a large scene takes longer to sync than its probes)."""
    scene = bpy.data.scenes.new("Radiosity probes")
    try:
        with cycles_for_baking(scene):
            yield scene
    finally:
        bpy.data.scenes.remove(scene)


def _bake_probes(scene, objects, pass_type: str, passes: set) -> None:
    """One Cycles bake of `objects` (planes of the probe scene) into their materials' active images."""
    view_layer = scene.view_layers[0]
    view_layer.update()
    for obj in objects:
        obj.select_set(True, view_layer=view_layer)
    with bpy.context.temp_override(scene=scene, view_layer=view_layer, active_object=objects[0], object=objects[0],
                                   selected_objects=objects, selected_editable_objects=objects), quiet_stdout():
        bpy.ops.object.bake(type=pass_type, pass_filter=passes, uv_layer=LIGHTMAP_UV, margin=0, use_clear=True)


def _probe_plane(scene, name: str, material, z: float):
    """A unit square at height `z` with a 'Lightmap' UV map filling [0, 1]² and `material` (None:
    no slot), linked into `scene`: a bake fills every pixel of its image from one material."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(0, 0, z), (1, 0, z), (1, 1, z), (0, 1, z)], [], [(0, 1, 2, 3)])
    layer = mesh.uv_layers.new(name=LIGHTMAP_UV)
    for loop, uv in zip(mesh.polygons[0].loop_indices, ((0, 0), (1, 0), (1, 1), (0, 1))):
        layer.data[loop].uv = uv
    if material is not None:
        mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj, mesh


def _probe(scene, source_node, index: int):
    """A small plane whose material is `source_node`'s unlinked settings with a white Base Color
    and no emission, with an image node to bake into."""
    material = bpy.data.materials.new(f"Radiosity probe {index}")
    if material.node_tree is None:
        material.use_nodes = True
    nodes = material.node_tree.nodes
    node = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    for socket in source_node.inputs:
        target = node.inputs.get(socket.identifier) or node.inputs.get(socket.name)
        if target is not None and hasattr(socket, "default_value") and hasattr(target, "default_value"):
            with contextlib.suppress(TypeError, ValueError, AttributeError):
                target.default_value = socket.default_value
    node.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    node.inputs["Emission Strength"].default_value = 0.0
    image = bpy.data.images.new(f"Radiosity probe {index}", 2, 2, alpha=False, float_buffer=True)
    target = nodes.new("ShaderNodeTexImage")
    target.image = image
    nodes.active = target
    obj, mesh = _probe_plane(scene, f"Radiosity probe {index}", material, float(index))
    return obj, material, image, mesh


def principled_diffuse_factors(objects) -> dict:
    """{material name: {Principled node name: RGB}}: the fraction of its Base Color that each
    Principled BSDF reflects diffusely, as Cycles measures it (its specular layer, metallic and
    transmission take the rest). The light lightmap's baked look multiplies Base Color by it."""
    nodes = _principled_nodes(objects)
    if not nodes:
        return {}
    factors: dict = {}
    with _probe_scene() as scene:
        probes = [_probe(scene, node, k) for k, (_, node) in enumerate(nodes)]
        try:
            _bake_probes(scene, [probe[0] for probe in probes], "DIFFUSE", {"COLOR"})
            for (material, node), (_, _, image, _) in zip(nodes, probes):
                factors.setdefault(material.name, {})[node.name] = _pixels(image).reshape(-1, 3).mean(axis=0)
        finally:
            for obj, material, image, mesh in probes:
                bpy.data.objects.remove(obj)
                bpy.data.meshes.remove(mesh)
                bpy.data.materials.remove(material)
                bpy.data.images.remove(image)
    return factors
