"""Mesh shapes as plain data: (vertices, faces) with faces as tuples of vertex indices whose
winding points the front outwards (counter-clockwise seen from the front). No bpy: the room
builder (rooms.py) and the sample files (tools/make_sample_blends.py) turn them into objects.

Each shape's triangle count (n-gons counted as n − 2 triangles) is given where a builder sizes
detail by it.
"""

from __future__ import annotations

import math

import numpy as np


def box(centre, size, inward=False):
    """Eight corners and six quads of an axis-aligned box; fronts face out (or in). 12 triangles."""
    cx, cy, cz = centre
    sx, sy, sz = (s / 2 for s in size)
    vertices = [(cx + dx * sx, cy + dy * sy, cz + dz * sz)
                for dz in (-1, 1) for dy in (-1, 1) for dx in (-1, 1)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    if inward:
        faces = [tuple(reversed(f)) for f in faces]
    return vertices, faces


def box_between(low, high):
    """The box with opposite corners `low` and `high`."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    return box(tuple((low + high) / 2), tuple(high - low))


def merge(*parts):
    """One (vertices, faces) of several: the parts stay separate shells of one mesh."""
    vertices, faces = [], []
    for part_vertices, part_faces in parts:
        offset = len(vertices)
        vertices.extend(tuple(map(float, v)) for v in part_vertices)
        faces.extend(tuple(offset + i for i in face) for face in part_faces)
    return vertices, faces


def triangle_count(faces) -> int:
    return sum(len(face) - 2 for face in faces)


def faces_facing(quads, outward_normals):
    """(vertices, faces) of loose quads given by corner positions, each wound so that its normal
    points along its `outward_normals` entry; shared corners become shared vertices."""
    corners = np.asarray(quads, dtype=float)  # (Q, 4, 3)
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    backwards = np.einsum("ij,ij->i", normals, np.asarray(outward_normals, dtype=float)) < 0
    corners[backwards] = corners[backwards][:, ::-1]
    unique, index = np.unique(np.round(corners.reshape(-1, 3), 9), axis=0, return_inverse=True)
    return [tuple(v) for v in unique], [tuple(face) for face in index.reshape(-1, 4).tolist()]


def wall_with_opening(low, high, opening):
    """A closed wall slab from corner `low` to `high`, thin along y, with a rectangular hole
    through it: `opening` = (x0, x1, z0, z1). A 3 × 3 grid less its middle on each side, the 4
    reveals of the hole and the outer rim split at the same grid lines (no T-junctions):
    32 quads, 64 triangles."""
    (x_low, y_front, z_low), (x_high, y_back, z_high) = low, high
    x0, x1, z0, z1 = opening
    xs, zs = (x_low, x0, x1, x_high), (z_low, z0, z1, z_high)
    quads, normals = [], []
    for y, facing in ((y_front, -1.0), (y_back, 1.0)):
        for i in range(3):
            for k in range(3):
                if (i, k) == (1, 1):
                    continue  # the hole
                quads.append([(xs[i], y, zs[k]), (xs[i + 1], y, zs[k]), (xs[i + 1], y, zs[k + 1]),
                              (xs[i], y, zs[k + 1])])
                normals.append((0.0, facing, 0.0))

    def across_x(x, z_from, z_to):  # a quad at x spanning the thickness
        return [(x, y_front, z_from), (x, y_back, z_from), (x, y_back, z_to), (x, y_front, z_to)]

    def across_z(z, x_from, x_to):  # a quad at z spanning the thickness
        return [(x_from, y_front, z), (x_to, y_front, z), (x_to, y_back, z), (x_from, y_back, z)]

    quads += [across_x(x0, z0, z1), across_x(x1, z0, z1), across_z(z0, x0, x1), across_z(z1, x0, x1)]
    normals += [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1)]  # the reveals face into the hole
    for k in range(3):
        quads += [across_x(x_low, zs[k], zs[k + 1]), across_x(x_high, zs[k], zs[k + 1])]
        normals += [(-1, 0, 0), (1, 0, 0)]
    for i in range(3):
        quads += [across_z(z_low, xs[i], xs[i + 1]), across_z(z_high, xs[i], xs[i + 1])]
        normals += [(0, 0, -1), (0, 0, 1)]
    return faces_facing(quads, normals)


def lathe(profile, segments: int, centre=(0.0, 0.0, 0.0), cap_bottom=True):
    """A surface of revolution about the vertical through `centre`: `profile` is [(radius, height)]
    from the bottom up, open at the top. 2·segments·(len(profile) − 1) triangles, plus
    segments − 2 for the bottom cap."""
    cx, cy, cz = centre
    angles = 2 * math.pi * np.arange(segments) / segments
    vertices = [(cx + r * math.cos(a), cy + r * math.sin(a), cz + h) for r, h in profile for a in angles]
    faces = []
    for ring in range(len(profile) - 1):
        low, high = ring * segments, (ring + 1) * segments
        faces += [(low + k, low + (k + 1) % segments, high + (k + 1) % segments, high + k) for k in range(segments)]
    if cap_bottom:
        faces.append(tuple(reversed(range(segments))))  # faces down
    return vertices, faces


def cylinder(centre_bottom, radius: float, height: float, segments: int):
    """A closed upright cylinder: 4·segments − 4 triangles (a 4-segment one is a square post)."""
    vertices, faces = lathe([(radius, 0.0), (radius, height)], segments, centre_bottom)
    top = len(vertices) - segments
    return vertices, faces + [tuple(range(top, top + segments))]


def drape(origin, width: float, height: float, columns: int, rows: int, depth: float, folds: int):
    """A hanging cloth: one sheet (no thickness) in the x–z plane from `origin` (its lower left),
    waved along y into `folds` folds of `depth`, its front towards +y. 2·columns·rows triangles."""
    ox, oy, oz = origin
    u = np.linspace(0.0, 1.0, columns + 1)
    xs = ox + width * u
    ys = oy + 0.5 * depth * np.sin(2 * math.pi * folds * u)
    zs = oz + height * np.linspace(0.0, 1.0, rows + 1)
    vertices = [(float(xs[i]), float(ys[i]), float(z)) for z in zs for i in range(columns + 1)]
    stride = columns + 1
    faces = [(k * stride + i, (k + 1) * stride + i, (k + 1) * stride + i + 1, k * stride + i + 1)
             for k in range(rows) for i in range(columns)]
    return vertices, faces
