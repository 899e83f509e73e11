"""Blender objects -> the core's Scene (world space, modifiers applied), mesh by mesh in numpy.

Faces become surfaces of 3 or 4 vertices: triangles and planar convex quads as they are; n-gons
and the quads the core's polygon checks refuse (bent, concave) through Blender's own
triangulation. Faces of zero area are skipped (a warning counts them). Vertex order follows
Blender's winding, which is the core's front convention; a mirroring object transform flips it
back. Every face is two-sided, as Cycles renders it (the core simulates a back only where it can
send or receive light). The core splits the surfaces into patches (by Patch Size or N x N).

What Cycles renders takes part in the light transport: besides mesh objects, curves, surfaces,
text and metaballs (as the meshes they evaluate to) and every instance the depsgraph holds —
collection instances, geometry-nodes and particle instances, linked duplicates. Objects that own
their mesh get lightmaps; instances share a mesh, so they only block and reflect light.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import bpy

from ..core import FaceNames, OpacityMaps, Scene, SceneError, check_has_emitter, polygon_faults
from .errors import BakeError
from .lights import export_lights
from .materials import MaterialReader
from .opacity import bake_opacity, lets_light_through, uv_layer_name
from .tags import LIGHTMAP_UV


@dataclass
class ExportedScene:
    scene: Scene
    baked_objects: list[str]  # objects that get a lightmap
    material_names: list = field(default_factory=list)  # the materials faces are made of (None: no material)
    face_material: np.ndarray | None = None  # (surfaces,) each surface's material, an index into material_names
    instances: int = 0  # instanced geometries in the light transport (they get no lightmap)
    warnings: list[str] = field(default_factory=list)


def _foreach(collection, attribute: str, width: int, dtype) -> np.ndarray:
    values = np.empty(len(collection) * width, dtype=dtype)
    collection.foreach_get(attribute, values)
    return values.reshape(-1, width) if width > 1 else values


@dataclass
class MeshFaces:
    """The surfaces of one mesh object, as arrays."""
    corners: np.ndarray  # (F, 4, 3) world space, triangles repeat their last corner
    corner_count: np.ndarray  # (F,)
    uv: np.ndarray  # (F, 4, 2) Lightmap UVs (zeros for occluders)
    reflectance: np.ndarray  # (F, 3)
    emission: np.ndarray  # (F, 3)
    material: np.ndarray  # (F,) the face's material: an index into the exporter's `material_names`
    texture_uv: np.ndarray  # (F, 4, 2) the UVs its material's textures read (zeros where it lets no light through)


GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}  # object types Cycles renders as meshes


class MeshExporter:
    def __init__(self):
        self.materials = MaterialReader()
        self.warnings: list[str] = []
        self.meshes: list[tuple[str, bool, MeshFaces]] = []  # (object name, has lightmap UVs, faces)
        self.instances = 0  # instanced geometries exported (occluders only)
        self.material_names: list = [None]  # every material a face is made of (index 0: none)
        self.material_index: dict = {None: 0}
        self.see_through: dict = {}  # material name -> it lets light through (opacity.lets_light_through)

    def add(self, obj, obj_eval, with_lightmap_uv: bool, matrix=None, name: str | None = None) -> int:
        """Append the faces of one evaluated object (at `matrix`, default its own); returns how many
        surfaces it gave."""
        try:
            mesh = obj_eval.to_mesh()
        except RuntimeError:  # an object type with no mesh to give (an empty curve, ...)
            return 0
        try:
            faces = None if mesh is None else self._faces(obj, obj_eval, mesh, with_lightmap_uv, matrix)
        finally:
            obj_eval.to_mesh_clear()
        if faces is not None:
            self.meshes.append((name or obj.name, with_lightmap_uv, faces))
        return 0 if faces is None else len(faces.corners)

    def _faces(self, obj, obj_eval, mesh, with_lightmap_uv: bool, matrix=None) -> MeshFaces | None:
        if len(mesh.polygons) == 0:
            if with_lightmap_uv:
                raise BakeError(f"object '{obj.name}' has no faces to bake")
            return None
        matrix = np.array(obj_eval.matrix_world if matrix is None else matrix, dtype=np.float64)
        local = _foreach(mesh.vertices, "co", 3, np.float32).astype(np.float64)
        positions = local @ matrix[:3, :3].T + matrix[:3, 3]
        if not np.all(np.isfinite(positions)):
            raise BakeError(f"object '{obj.name}' has vertices at NaN or infinite positions")
        loop_vertex = _foreach(mesh.loops, "vertex_index", 1, np.int32)
        uv = None
        if with_lightmap_uv:
            layer = mesh.uv_layers.get(LIGHTMAP_UV)
            if layer is None:
                raise BakeError(f"object '{obj.name}': its modifiers drop the '{LIGHTMAP_UV}' UV map;"
                                f" apply them or give the result a '{LIGHTMAP_UV}' UV map")
            uv = _foreach(layer.uv, "vector", 2, np.float32).astype(np.float64)
            if not np.all(np.isfinite(uv)):
                raise BakeError(f"object '{obj.name}': the '{LIGHTMAP_UV}' UV map has NaN values")

        loop_start = _foreach(mesh.polygons, "loop_start", 1, np.int32)
        loop_total = _foreach(mesh.polygons, "loop_total", 1, np.int32)
        material_index = _foreach(mesh.polygons, "material_index", 1, np.int32)

        # candidate faces: triangles and quads as loops (k, 4) with triangles repeating the last loop
        small = np.flatnonzero(loop_total <= 4)
        loops = loop_start[small, None] + np.minimum(np.arange(4)[None], loop_total[small, None] - 1)
        faults = polygon_faults(positions[loop_vertex[loops]], loop_total[small])
        split = faults["not_planar"] | faults["not_convex"]
        face_loops, face_polygon = [loops[~split]], [small[~split]]
        face_count = [loop_total[small[~split]]]

        # n-gons and quads the core refuses: Blender's triangulation of exactly those polygons
        needs_triangles = loop_total > 4
        needs_triangles[small[split]] = True
        if needs_triangles.any():
            mesh.calc_loop_triangles()
            tri_loops = _foreach(mesh.loop_triangles, "loops", 3, np.int32)
            tri_polygon = _foreach(mesh.loop_triangles, "polygon_index", 1, np.int32)
            chosen = needs_triangles[tri_polygon]
            face_loops.append(np.concatenate([tri_loops[chosen], tri_loops[chosen][:, 2:3]], axis=1))
            face_polygon.append(tri_polygon[chosen])
            face_count.append(np.full(int(chosen.sum()), 3, dtype=np.int32))
        face_loops = np.concatenate(face_loops)
        face_polygon = np.concatenate(face_polygon)
        face_count = np.concatenate(face_count)

        valid = ~polygon_faults(positions[loop_vertex[face_loops]], face_count)["zero_area"]
        if not valid.all():
            self.warnings.append(f"object '{obj.name}': skipped {int((~valid).sum())} faces of zero area")
        if not valid.any():
            if with_lightmap_uv:
                raise BakeError(f"object '{obj.name}' has only faces of zero area")
            return None
        face_loops, face_polygon, face_count = face_loops[valid], face_polygon[valid], face_count[valid]
        if np.linalg.det(matrix[:3, :3]) < 0:  # a mirroring transform turns the winding around
            quads = face_count == 4
            face_loops[quads] = face_loops[quads][:, ::-1]
            face_loops[~quads] = face_loops[~quads][:, [2, 1, 0, 0]]

        slots = obj_eval.material_slots
        colours = [self.materials.colours(slot.material) for slot in slots] + [self.materials.colours(None)]
        reflectance = np.stack([c[0] for c in colours])
        emission = np.stack([c[1] for c in colours])
        slot = material_index[face_polygon]
        slot = np.where((slot >= 0) & (slot < len(slots)), slot, len(slots))  # no such slot: the default material
        materials = [s.material for s in slots] + [None]
        codes = np.array([self._material_code(material) for material in materials], dtype=np.int64)
        texture_uv = np.zeros(face_loops.shape + (2,))
        for k, material in enumerate(materials):
            if material is None or not self.see_through[material.name]:
                continue
            name = uv_layer_name(material, mesh)
            if name is not None:  # a texture on no UV map reads its first texel: zeros
                layer_uv = _foreach(mesh.uv_layers[name].uv, "vector", 2, np.float32).astype(np.float64)
                chosen = slot == k
                texture_uv[chosen] = layer_uv[face_loops[chosen]]
        return MeshFaces(corners=positions[loop_vertex[face_loops]], corner_count=face_count.astype(np.int64),
                         uv=uv[face_loops] if uv is not None else np.zeros(face_loops.shape + (2,)),
                         reflectance=reflectance[slot], emission=emission[slot], material=codes[slot],
                         texture_uv=texture_uv)

    def _material_code(self, material) -> int:
        name = material.name if material is not None else None
        if name not in self.material_index:
            self.material_index[name] = len(self.material_names)
            self.material_names.append(name)
            self.see_through[name] = lets_light_through(material)
        return self.material_index[name]

    def opacity(self) -> OpacityMaps | None:
        """The opacity textures of the materials that let light through, baked by Cycles
        (`opacity.bake_opacity`), and each face's; None when no face lets light through."""
        names = [name for name in self.material_names[1:] if self.see_through.get(name)]
        if not names:
            return None
        images = bake_opacity([bpy.data.materials[name] for name in names])
        texture_of = np.full(len(self.material_names), -1, dtype=np.int64)
        for k, name in enumerate(names):
            texture_of[self.material_index[name]] = k
        index = texture_of[np.concatenate([faces.material for _, _, faces in self.meshes])]
        uv = np.concatenate([faces.texture_uv for _, _, faces in self.meshes])
        maps = OpacityMaps([images[name] for name in names], index, np.where((index >= 0)[:, None, None], uv, 0.0))
        maps.validate()
        return maps

    def scene(self, extras: dict) -> Scene:
        object_names = [name for name, _, _ in self.meshes]
        object_index = np.concatenate([np.full(len(faces.corners), number, dtype=np.int64)
                                       for number, (_, _, faces) in enumerate(self.meshes)])
        stack = lambda key: np.concatenate([getattr(faces, key) for _, _, faces in self.meshes])  # noqa: E731
        has_uv = np.concatenate([np.full(len(faces.corners), with_uv) for _, with_uv, faces in self.meshes])
        return Scene(names=FaceNames(object_names, object_index), corners=stack("corners"),
                     corner_count=stack("corner_count"), reflectance=stack("reflectance"), emission=stack("emission"),
                     object_index=object_index, object_names=object_names, uv=stack("uv"), has_uv=has_uv,
                     two_sided=np.ones(len(object_index), dtype=bool), extras=extras)


def check_emitters(scene: Scene) -> None:
    """Refuse a scene where nothing emits: no lamp, no world colour, no emissive face (read off the
    materials or baked into a material map)."""
    if any(np.any(material.emission > 0) for material in scene.material_maps.values()):
        return
    try:
        check_has_emitter(scene)
    except SceneError:
        raise BakeError("nothing emits light: add a lamp, give the world a colour, or give a mesh an"
                        " emissive material (Emission Strength > 0)") from None


def add_occluders(exporter: MeshExporter, depsgraph, baked) -> None:
    """Every other geometry the depsgraph renders: objects (evaluated, modifiers applied) and their
    instances, each at its own world matrix. Hidden from renders: left out, as Cycles does."""
    baked_names = {obj.name for obj in baked}
    for instance in depsgraph.object_instances:
        obj_eval = instance.object
        original = obj_eval.original
        if obj_eval.type not in GEOMETRY_TYPES or original.hide_render:
            continue
        if instance.is_instance:
            parent = instance.parent.original.name if instance.parent else "instance"
            exporter.instances += 1
            exporter.add(original, obj_eval, with_lightmap_uv=False, matrix=instance.matrix_world.copy(),
                         name=f"{parent}/{original.name}#{exporter.instances}")
        elif original.name not in baked_names:
            exporter.add(original, obj_eval, with_lightmap_uv=False)


def export_scene(depsgraph, baked, occluders=None, lamps=(), world=None) -> ExportedScene:
    """`baked`: mesh objects that get lightmaps (each needs a 'Lightmap' UV map); `occluders`: other
    objects that only take part in the light transport — None for everything else the depsgraph
    renders, instances included (`add_occluders`). `lamps` (light objects, see
    `lights.render_lamps`) and `world` go into the scene's extras as "lights" and "world"."""
    exporter = MeshExporter()
    exporter.materials = MaterialReader(cycles_bakes_inputs=True)  # the bake replaces their guesses
    for obj in baked:
        exporter.add(obj, obj.evaluated_get(depsgraph), with_lightmap_uv=True)
    baked_reader, exporter.materials = exporter.materials, MaterialReader()  # occluders keep what is read
    if occluders is None:
        add_occluders(exporter, depsgraph, baked)
    else:
        for obj in occluders:
            exporter.add(obj, obj.evaluated_get(depsgraph), with_lightmap_uv=False)
    if not exporter.meshes:
        raise BakeError("nothing to bake: the selected objects have no faces")
    extras, light_warnings = export_lights(depsgraph, lamps, world)
    scene = exporter.scene(extras)
    try:
        scene.opacity = exporter.opacity()
    except RuntimeError as error:  # Cycles refused (a message of its own)
        raise BakeError(f"Cycles could not bake the materials' alpha: {str(error).strip().splitlines()[-1]}") from None
    face_material = np.concatenate([faces.material for _, _, faces in exporter.meshes])
    return ExportedScene(scene=scene, baked_objects=[obj.name for obj in baked], material_names=exporter.material_names,
                         face_material=face_material, instances=exporter.instances,
                         warnings=baked_reader.warnings + exporter.materials.warnings + exporter.warnings
                         + light_warnings)
