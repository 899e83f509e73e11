"""Blender objects -> the core's Scene (world space, modifiers applied).

Faces become surfaces of 3 or 4 vertices: triangles and planar convex quads as
they are; n-gons and bent or concave quads through Blender's own triangulation.
Degenerate faces are skipped (a warning counts them). Vertex order follows
Blender's winding, which is the core's front convention; a mirroring object
transform flips it back.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.scene import PLANARITY_TOLERANCE, Scene, SceneError, Surface, check_has_emitter
from .errors import BakeError
from .lights import export_lights
from .materials import MaterialReader
from .tags import LIGHTMAP_UV

DEGENERATE_AREA_FRACTION = 1e-10
MAX_SPLIT = 64  # pieces along one edge of a face in the Patch Size mode


@dataclass
class ExportedScene:
    scene: Scene
    baked_objects: list[str]  # objects that get a lightmap
    warnings: list[str] = field(default_factory=list)


def _foreach(collection, attribute: str, width: int, dtype) -> np.ndarray:
    values = np.empty(len(collection) * width, dtype=dtype)
    collection.foreach_get(attribute, values)
    return values.reshape(-1, width) if width > 1 else values


def _areas_and_bad_quads(corners: np.ndarray, quad: np.ndarray):
    """Area of each face (k, 4, 3) (triangles repeat a corner) and whether a quad must be split."""
    area_vector = 0.5 * np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    area = np.linalg.norm(area_vector, axis=1)
    size = np.ptp(corners, axis=1).max(axis=1)
    normal = area_vector / np.maximum(area, 1e-300)[:, None]
    off_plane = np.abs(np.einsum("kvc,kc->kv", corners - corners.mean(axis=1, keepdims=True), normal)).max(axis=1)
    edges = np.roll(corners, -1, axis=1) - corners
    turns = np.einsum("kvc,kc->kv", np.cross(edges, np.roll(edges, -1, axis=1)), normal)
    bent = off_plane > 0.5 * PLANARITY_TOLERANCE * np.maximum(size, 1e-300)
    concave = np.any(turns <= 1e-9 * size[:, None] ** 2, axis=1)
    return area, size, quad & (bent | concave)


def split_face(vertices: np.ndarray, uv: np.ndarray, patch_size: float):
    """A face as pieces about `patch_size` across (the Patch Size mode: big faces get many patches,
    small ones stay whole). Quads split on a bilinear grid, triangles into n² triangles, the
    same shapes the core's uniform subdivision makes, with UVs carried along."""
    count = len(vertices)
    edges = np.linalg.norm(np.roll(vertices, -1, axis=0) - vertices, axis=1)
    if patch_size <= 0 or edges.max() <= patch_size:
        return [(vertices, uv)]
    if count == 4:
        along_s = min(MAX_SPLIT, int(np.ceil(max(edges[0], edges[2]) / patch_size)))
        along_t = min(MAX_SPLIT, int(np.ceil(max(edges[1], edges[3]) / patch_size)))
        s = np.linspace(0.0, 1.0, along_s + 1)
        t = np.linspace(0.0, 1.0, along_t + 1)

        def at(corners, i, j):
            return (corners[0] * (1 - s[i]) * (1 - t[j]) + corners[1] * s[i] * (1 - t[j])
                    + corners[2] * s[i] * t[j] + corners[3] * (1 - s[i]) * t[j])

        return [(np.array([at(vertices, i, j), at(vertices, i + 1, j), at(vertices, i + 1, j + 1),
                           at(vertices, i, j + 1)]),
                 np.array([at(uv, i, j), at(uv, i + 1, j), at(uv, i + 1, j + 1), at(uv, i, j + 1)]))
                for j in range(along_t) for i in range(along_s)]
    n = min(MAX_SPLIT, int(np.ceil(edges.max() / patch_size)))

    def at(corners, i, r):
        return corners[0] + (corners[1] - corners[0]) * i / n + (corners[2] - corners[0]) * r / n

    pieces = []
    for r in range(n):
        for i in range(n - r):
            corners = [(i, r), (i + 1, r), (i, r + 1)]
            pieces.append(corners)
            if i < n - r - 1:
                pieces.append([(i + 1, r), (i + 1, r + 1), (i, r + 1)])
    return [(np.array([at(vertices, i, r) for i, r in piece]), np.array([at(uv, i, r) for i, r in piece]))
            for piece in pieces]


class MeshExporter:
    def __init__(self, patch_size: float = 0.0):
        self.patch_size = patch_size
        self.materials = MaterialReader()
        self.warnings: list[str] = []
        self.surfaces: list[Surface] = []

    def add(self, obj, obj_eval, with_lightmap_uv: bool) -> int:
        """Append the faces of one evaluated object; returns how many surfaces it gave."""
        mesh = obj_eval.to_mesh()
        try:
            return self._add_mesh(obj, obj_eval, mesh, with_lightmap_uv)
        finally:
            obj_eval.to_mesh_clear()

    def _add_mesh(self, obj, obj_eval, mesh, with_lightmap_uv: bool) -> int:
        if len(mesh.polygons) == 0:
            if with_lightmap_uv:
                raise BakeError(f"object '{obj.name}' has no faces to bake")
            return 0
        matrix = np.array(obj_eval.matrix_world, dtype=np.float64)
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
        corners = positions[loop_vertex[loops]]
        area, size, split = _areas_and_bad_quads(corners, loop_total[small] == 4)
        keep = ~split
        face_loops = [loops[keep]]
        face_polygon = [small[keep]]
        face_count = [loop_total[small[keep]]]

        # n-gons and bent/concave quads: Blender's triangulation of exactly those polygons
        needs_triangles = np.zeros(len(loop_total), dtype=bool)
        needs_triangles[loop_total > 4] = True
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

        corners = positions[loop_vertex[face_loops]]
        area, size, _ = _areas_and_bad_quads(corners, np.zeros(len(corners), dtype=bool))
        valid = area > DEGENERATE_AREA_FRACTION * np.maximum(size, 1e-300) ** 2
        if not valid.all():
            self.warnings.append(f"object '{obj.name}': skipped {int((~valid).sum())} faces of zero area")
        if not valid.any():
            if with_lightmap_uv:
                raise BakeError(f"object '{obj.name}' has only faces of zero area")
            return 0
        if np.linalg.det(matrix[:3, :3]) < 0:  # a mirroring transform turns the winding around
            quads = face_count == 4
            face_loops[quads] = face_loops[quads][:, ::-1]
            face_loops[~quads] = face_loops[~quads][:, [2, 1, 0, 0]]

        slots = obj_eval.material_slots
        for index in np.flatnonzero(valid):
            count = int(face_count[index])
            face = face_loops[index, :count]
            slot_index = int(material_index[face_polygon[index]])
            material = slots[slot_index].material if slot_index < len(slots) else None
            reflectance, emission = self.materials.colours(material)
            face_uv = uv[face] if uv is not None else np.zeros((count, 2))  # occluders get no image
            for vertices, piece_uv in split_face(positions[loop_vertex[face]], face_uv, self.patch_size):
                # built directly, not through scene_from_dict: the checks above (finite, non-degenerate,
                # planar convex quads, reflectance < 1) are those it makes, vectorized per mesh
                self.surfaces.append(Surface(name=f"{obj.name}#{len(self.surfaces)}", vertices=vertices,
                                             reflectance=reflectance, emission=emission, object=obj.name,
                                             uv=piece_uv if uv is not None else None))
        return int(valid.sum())


def export_scene(depsgraph, baked, occluders, patch_size: float = 0.0, lamps=(), world=None) -> ExportedScene:
    """`baked`: mesh objects that get lightmaps (each needs a 'Lightmap' UV map); `occluders`: other
    mesh objects that only take part in the light transport. `patch_size` > 0 splits faces into
    surfaces about that size (then solve with subdivision 1). `lamps` (light objects, see
    `lights.scene_lamps`) and `world` go into the scene's extras as "lights" and "world"."""
    exporter = MeshExporter(patch_size)
    for obj in baked:
        exporter.add(obj, obj.evaluated_get(depsgraph), with_lightmap_uv=True)
    for obj in occluders:
        exporter.add(obj, obj.evaluated_get(depsgraph), with_lightmap_uv=False)
    if not exporter.surfaces:
        raise BakeError("nothing to bake: the selected objects have no faces")
    extras, light_warnings = export_lights(depsgraph, lamps, world)
    scene = Scene(surfaces=exporter.surfaces, extras=extras)
    try:
        check_has_emitter(scene)
    except SceneError:
        raise BakeError("nothing emits light: add a lamp, give the world a colour, or give a mesh an"
                        " emissive material (Emission Strength > 0)") from None
    return ExportedScene(scene=scene, baked_objects=[obj.name for obj in baked],
                         warnings=exporter.materials.warnings + exporter.warnings + light_warnings)
