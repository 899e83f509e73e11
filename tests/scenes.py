"""Small analytic scenes for tests (scene dicts in the JSON format of docs/architecture.md)."""

from __future__ import annotations

import numpy as np

from radiosity_addon.bench.scenes import CUBE_FACES, opposed_rectangles_form_factor  # noqa: F401 (re-exported)


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
