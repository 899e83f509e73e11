"""The 'Lightmap' UV map of each baked mesh: the user's own, or one made by Lightmap Pack.

Made maps are recorded so a cancelled or failed bake removes them again and the
.blend stays exactly as it was; the user's other UV maps are never touched.
"""

from __future__ import annotations

import contextlib
import io

import numpy as np

from .errors import BakeError
from .tags import CREATED_UV, LIGHTMAP_UV

MAX_UV_MAPS = 8  # Blender's limit per mesh


def meshes_without_lightmap_uv(objects) -> list:
    meshes = {obj.data.name: obj.data for obj in objects if LIGHTMAP_UV not in obj.data.uv_layers}
    return list(meshes.values())


def add_lightmap_uvs(context, objects, margin: float) -> list:
    """Give every mesh of `objects` lacking one a packed 'Lightmap' UV map (Blender's Lightmap
    Pack operator); returns the meshes changed. On failure nothing stays changed."""
    import bpy

    meshes = meshes_without_lightmap_uv(objects)
    for mesh in meshes:
        if mesh.library is not None or not mesh.is_editable:
            raise BakeError(f"mesh '{mesh.name}' is linked from a library and has no '{LIGHTMAP_UV}' UV map;"
                            f" add one in the library file")
        if len(mesh.uv_layers) >= MAX_UV_MAPS:
            raise BakeError(f"mesh '{mesh.name}' already has {MAX_UV_MAPS} UV maps; rename one to"
                            f" '{LIGHTMAP_UV}' or remove one")
    for mesh in meshes:
        positions = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", positions)
        if not np.all(np.isfinite(positions)):
            raise BakeError(f"mesh '{mesh.name}' has vertices at NaN or infinite positions")
    # one object per mesh: the operator packs the meshes of the selected objects
    owners = list({obj.data.name: obj for obj in objects if obj.data in meshes}.values())
    changed = []
    try:
        for mesh in meshes:
            previous_active = mesh.uv_layers.active_index
            layer = mesh.uv_layers.new(name=LIGHTMAP_UV, do_init=False)
            changed.append((mesh, previous_active))
            mesh.uv_layers.active = layer
        if owners:
            # Lightmap Pack writes into the active UV map and chats on stdout
            with contextlib.redirect_stdout(io.StringIO()), \
                    context.temp_override(selected_objects=owners, active_object=owners[0], object=owners[0]):
                try:
                    bpy.ops.uv.lightmap_pack(PREF_CONTEXT="ALL_FACES", PREF_PACK_IN_ONE=False, PREF_NEW_UVLAYER=False,
                                             PREF_BOX_DIV=12, PREF_MARGIN_DIV=margin)
                except RuntimeError as error:  # degenerate input to Blender's packer
                    names = ", ".join(f"'{mesh.name}'" for mesh in meshes)
                    raise BakeError(f"Lightmap Pack failed on {names} ({str(error).strip().splitlines()[-1]});"
                                    f" give the mesh a '{LIGHTMAP_UV}' UV map yourself") from None
        for mesh, previous_active in changed:
            mesh.uv_layers.active_index = max(previous_active, 0)
            mesh[CREATED_UV] = True
    except BaseException:
        remove_lightmap_uvs([mesh for mesh, _ in changed])
        raise
    return meshes


def remove_lightmap_uvs(meshes) -> None:
    """Undo `add_lightmap_uvs` for these meshes (keeps the user's active UV map)."""
    for mesh in meshes:
        layer = mesh.uv_layers.get(LIGHTMAP_UV)
        if layer is None:
            continue
        active_name = mesh.uv_layers.active.name if mesh.uv_layers.active else None
        render_name = next((uv.name for uv in mesh.uv_layers if uv.active_render), None)
        mesh.uv_layers.remove(layer)
        if active_name and active_name != LIGHTMAP_UV and active_name in mesh.uv_layers:
            mesh.uv_layers.active = mesh.uv_layers[active_name]
        if render_name and render_name != LIGHTMAP_UV and render_name in mesh.uv_layers:
            mesh.uv_layers[render_name].active_render = True
        if CREATED_UV in mesh:
            del mesh[CREATED_UV]
