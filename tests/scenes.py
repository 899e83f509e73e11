"""Small analytic scenes for tests (scene dicts in the JSON format of docs/architecture.md)."""

from __future__ import annotations

import numpy as np

from bench.scenes import CUBE_FACES, opposed_rectangles_form_factor  # noqa: F401 (re-exported)
from radiosity_addon.core import LightmapSettings, SolveSettings

# The settings the analytic tests are written for, finer than the default preset: final's patches
# and elements, progressive refinement, 128-pixel hemi-cubes 2 x 2 a patch, emitters in 8 x 8
# pieces; lightmaps at 64 texels a metre, 4 x 4 points a sharp texel. Fixed here, so that tuning a
# preset moves no test's reference.
ANALYTIC_SOLVE = {"quality": "final", "method": "progressive", "hemicube_res": 128, "hemicube_elements": 2,
                  "probe_pieces": 8}
ANALYTIC_LIGHTMAPS = {"quality": "final", "texel_density": 64.0, "direct_pieces": 8, "direct_subsamples": 4,
                      "sky_directions": 0}


def solve_settings(**given) -> SolveSettings:
    """ANALYTIC_SOLVE with the fields in `given` set as given."""
    return SolveSettings(**(ANALYTIC_SOLVE | given))


def lightmap_settings(**given) -> LightmapSettings:
    """ANALYTIC_LIGHTMAPS with the fields in `given` set as given."""
    return LightmapSettings(**(ANALYTIC_LIGHTMAPS | given))


def surface(name, vertices, reflectance, emission, obj=None):
    grey = lambda v: [float(v)] * 3 if np.isscalar(v) else [float(x) for x in v]  # noqa: E731
    entry = {"name": name, "vertices": [list(map(float, p)) for p in vertices],
             "reflectance": grey(reflectance), "emission": grey(emission)}
    if obj:
        entry["object"] = obj
    return entry


def box_faces(low, high) -> list:
    """The six outward faces of the axis-aligned box [low, high], counter-clockwise from outside."""
    x0, y0, z0 = low
    x1, y1, z1 = high
    return [[[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],  # top
            [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]],  # bottom
            [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
            [[x1, y1, z0], [x0, y1, z0], [x0, y1, z1], [x1, y1, z1]],
            [[x0, y1, z0], [x0, y0, z0], [x0, y0, z1], [x0, y1, z1]],
            [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]]]


def closed_cube(reflectance=0.5, emission=1.0, emitting=None, scale=1.0):
    """Unit cube (times `scale`); every face emits `emission` unless `emitting` names the faces that do."""
    return {"surfaces": [
        surface(name, np.asarray(v, float) * scale, reflectance,
                emission if emitting is None or name in emitting else 0.0)
        for name, v in CUBE_FACES.items()
    ]}


def opposed_squares(distance, receiver_reflectance=0.5, emitter_emission=1.0):
    """Unit square receiver at z=0 facing +z, unit square emitter at z=distance facing -z."""
    square = [[0, 0], [1, 0], [1, 1], [0, 1]]
    receiver = [[x, y, 0.0] for x, y in square]
    emitter = [[x, y, distance] for x, y in square][::-1]
    return {"surfaces": [surface("receiver", receiver, receiver_reflectance, 0.0),
                         surface("emitter", emitter, 0.0, emitter_emission)]}


def perpendicular_squares(receiver_reflectance=0.5, emitter_emission=1.0):
    """Unit squares sharing the edge y=0..1 at x=0: receiver on z=0 (x>0) facing +z,
    emitter on x=0 (z>0) facing +x."""
    receiver = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    emitter = [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]]
    return {"surfaces": [surface("receiver", receiver, receiver_reflectance, 0.0),
                         surface("emitter", emitter, 0.0, emitter_emission)]}


def area_weighted_mean(solution, surface_index):
    """A surface's area-weighted mean radiosity over its front patches (what its lightmap holds)."""
    patches = solution.patches
    mask = (patches.surface == surface_index) & ~patches.is_back
    area = patches.area[mask]
    return (solution.patch_radiosity[mask] * area[:, None]).sum(axis=0) / area.sum()


def light_under_ceiling(gap: float) -> dict:
    """A 2 x 2 m floor and ceiling 2 m apart; a 0.4 m emitter `gap` under the ceiling, facing down,
    two-sided (its back lights the ceiling, as Blender's emission does)."""
    floor = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
    ceiling = [[x, y, 2.0] for x, y, _ in floor][::-1]
    light = [[x, y, 2.0 - gap] for x, y in [[0.8, 0.8], [1.2, 0.8], [1.2, 1.2], [0.8, 1.2]]][::-1]
    surfaces = [surface("floor", floor, 0.5, 0.0), surface("ceiling", ceiling, 0.7, 0.0),
                surface("light", light, 0.8, 10.0)]
    surfaces[2]["two_sided"] = True
    return {"surfaces": surfaces}


def grid_triangles(origin, along_u, along_v, n: int, m: int | None = None, uv_box=((0.0, 0.0), (1.0, 1.0)),
                   heights=None):
    """A parallelogram split into n x m quads of two triangles each (the front along along_u x along_v),
    as triangles (2nm, 3, 3) and their UVs (2nm, 3, 2) laid over `uv_box`; `heights` (n+1, m+1) lift the
    grid's points along the normal (a rough surface)."""
    m = m or n
    origin, along_u, along_v = (np.asarray(v, dtype=np.float64) for v in (origin, along_u, along_v))
    i, j = np.meshgrid(np.arange(n + 1), np.arange(m + 1), indexing="ij")
    points = origin + i[..., None] / n * along_u + j[..., None] / m * along_v
    if heights is not None:
        normal = np.cross(along_u, along_v)
        points = points + np.asarray(heights)[..., None] * normal / np.linalg.norm(normal)
    (u0, v0), (u1, v1) = uv_box
    uv = np.stack([u0 + (u1 - u0) * i / n, v0 + (v1 - v0) * j / m], axis=-1)

    def cells(x):
        return x[:-1, :-1], x[1:, :-1], x[1:, 1:], x[:-1, 1:]

    a, b, c, d = cells(points)
    ua, ub, uc, ud = cells(uv)
    triangles = np.concatenate([np.stack([a, b, c], 2).reshape(-1, 3, 3), np.stack([a, c, d], 2).reshape(-1, 3, 3)])
    uvs = np.concatenate([np.stack([ua, ub, uc], 2).reshape(-1, 3, 2), np.stack([ua, uc, ud], 2).reshape(-1, 3, 2)])
    return triangles, uvs


def sphere_triangles(centre, radius: float, rings: int):
    """A latitude-longitude sphere, fronts outwards: triangles (n, 3, 3) and UVs (u = longitude, v = latitude)."""
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, 2 * rings + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    points = np.asarray(centre, dtype=np.float64) + radius * np.stack(
        [np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    uv = np.stack([p / (2 * np.pi), 1 - t / np.pi], axis=-1)

    def cells(x):
        return x[:-1, :-1], x[1:, :-1], x[1:, 1:], x[:-1, 1:]

    a, b, c, d = cells(points)
    ua, ub, uc, ud = cells(uv)
    triangles = np.concatenate([np.stack([a, c, b], 2).reshape(-1, 3, 3), np.stack([a, d, c], 2).reshape(-1, 3, 3)])
    uvs = np.concatenate([np.stack([ua, uc, ub], 2).reshape(-1, 3, 2), np.stack([ua, ud, uc], 2).reshape(-1, 3, 2)])
    area = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1)
    keep = area > 1e-10 * radius * radius  # the poles' collapsed cells
    return triangles[keep], uvs[keep]


def triangle_scene(parts, quads=(), lights=None, world=None):
    """A Scene of triangle meshes and quads, as the Blender exporter makes one (every face two-sided,
    names made on demand): `parts` (object, triangles (n, 3, 3), UVs (n, 3, 2), reflectance, emission),
    `quads` (object, corners (4, 3), UVs (4, 2), reflectance, emission)."""
    from radiosity_addon.core import FaceNames, Scene
    corners, uvs, objects, reflectance, emission, counts, names = [], [], [], [], [], [], []
    grey = lambda v: np.full(3, float(v)) if np.isscalar(v) else np.asarray(v, dtype=np.float64)  # noqa: E731
    for name, triangles, uv, rho, e in parts:
        number = len(names)
        names.append(name)
        corners.append(np.concatenate([triangles, triangles[:, 2:3]], axis=1))
        uvs.append(np.concatenate([uv, uv[:, 2:3]], axis=1))
        objects.append(np.full(len(triangles), number))
        reflectance.append(np.tile(grey(rho), (len(triangles), 1)))
        emission.append(np.tile(grey(e), (len(triangles), 1)))
        counts.append(np.full(len(triangles), 3))
    for name, quad, uv, rho, e in quads:
        number = len(names)
        names.append(name)
        corners.append(np.asarray(quad, dtype=np.float64)[None])
        uvs.append(np.asarray(uv, dtype=np.float64)[None])
        objects.append(np.array([number]))
        reflectance.append(grey(rho)[None])
        emission.append(grey(e)[None])
        counts.append(np.array([4]))
    object_index = np.concatenate(objects)
    extras = {}
    if lights:
        extras["lights"] = lights
    if world is not None:
        extras["world"] = {"color": list(world)}
    corners = np.concatenate(corners)
    return Scene(names=FaceNames(names, object_index), corners=corners, corner_count=np.concatenate(counts),
                 reflectance=np.concatenate(reflectance), emission=np.concatenate(emission), object_index=object_index,
                 object_names=names, uv=np.concatenate(uvs), has_uv=np.ones(len(corners), dtype=bool),
                 two_sided=np.ones(len(corners), dtype=bool), extras=extras)
