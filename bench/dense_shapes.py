"""Dense meshes as arrays, of the kinds production scenes are made of: (vertices (V, 3) float,
triangles (T, 3) int), fronts counter-clockwise seen from outside. No bpy: production.py turns them
into objects. Every builder takes a resolution and says how many triangles it gives, so a scene can
be sized by its triangle count.
"""

from __future__ import annotations

import math

import numpy as np


def grid(origin, along_u, along_v, n: int, m: int | None = None, heights=None):
    """A parallelogram in n x m quads of two triangles (2nm), front along u x v; `heights`
    ((n+1) x (m+1)) lift its points along that front."""
    m = m or n
    origin, along_u, along_v = (np.asarray(a, dtype=np.float64) for a in (origin, along_u, along_v))
    i, j = np.meshgrid(np.arange(n + 1), np.arange(m + 1), indexing="ij")
    points = origin + i[..., None] / n * along_u + j[..., None] / m * along_v
    if heights is not None:
        normal = np.cross(along_u, along_v)
        points = points + np.asarray(heights)[..., None] * normal / np.linalg.norm(normal)
    index = np.arange((n + 1) * (m + 1)).reshape(n + 1, m + 1)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    triangles = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return points.reshape(-1, 3), triangles


def grid_triangles(n: int, m: int | None = None) -> int:
    return 2 * n * (m or n)


def merge(*parts):
    """One mesh of several (vertices, triangles)."""
    vertices, triangles, offset = [], [], 0
    for part_vertices, part_triangles in parts:
        vertices.append(np.asarray(part_vertices, dtype=np.float64))
        triangles.append(np.asarray(part_triangles) + offset)
        offset += len(part_vertices)
    return np.concatenate(vertices), np.concatenate(triangles)


def rounded_box(centre, size, radius: float, n: int):
    """A box with rounded edges and corners (each side an n x n grid pushed onto the rounded
    shape, as a Subdivision Surface over a bevelled box gives), 12 n² triangles."""
    centre, half = np.asarray(centre, dtype=np.float64), np.asarray(size, dtype=np.float64) / 2
    radius = min(radius, float(half.min()) * 0.99)
    inner = half - radius
    parts = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            u, v = (axis + 1) % 3, (axis + 2) % 3
            origin, along_u, along_v = np.zeros(3), np.zeros(3), np.zeros(3)
            origin[axis], origin[u], origin[v] = sign, -1.0, -1.0
            along_u[u], along_v[v] = 2.0, 2.0
            if sign < 0:
                along_u, along_v = along_v, along_u
                origin[u], origin[v] = -1.0, -1.0
            vertices, triangles = grid(origin, along_u, along_v, n)
            parts.append((vertices, triangles))
    unit, triangles = merge(*parts)  # a cube of side 2 (its seams' points repeat: a mesh of six sides)
    box_point = unit * half
    core = np.clip(box_point, -inner, inner)
    offset = box_point - core
    length = np.linalg.norm(offset, axis=1, keepdims=True)
    rounded = core + offset / np.maximum(length, 1e-12) * radius
    return centre + rounded, triangles


def rounded_box_triangles(n: int) -> int:
    return 12 * n * n


def cylinder(centre, radius: float, height: float, segments: int, rings: int, taper: float = 1.0, caps: bool = True):
    """An upright cylinder (its top radius `taper` times its bottom's) of segments x rings quads,
    and fans at the ends: 2 segments rings (+ 2 segments with caps) triangles."""
    centre = np.asarray(centre, dtype=np.float64)
    angle = np.linspace(0, 2 * math.pi, segments, endpoint=False)
    z = np.linspace(0, height, rings + 1)
    scale = 1 + (taper - 1) * z / height
    ring = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    points = np.concatenate([np.concatenate([ring * radius * s, np.full((segments, 1), h)], axis=1)
                             for s, h in zip(scale, z)]) + centre
    index = np.arange((rings + 1) * segments).reshape(rings + 1, segments)
    a, b = index[:-1], np.roll(index[:-1], -1, axis=1)
    c, d = np.roll(index[1:], -1, axis=1), index[1:]
    triangles = [np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)]
    if caps:
        bottom, top = len(points), len(points) + 1
        points = np.concatenate([points, [centre, centre + [0, 0, height]]])
        first, last = index[0], index[-1]
        triangles += [np.stack([np.full(segments, bottom), np.roll(first, -1), first], -1),
                      np.stack([np.full(segments, top), last, np.roll(last, -1)], -1)]
    return points, np.concatenate(triangles)


def cylinder_triangles(segments: int, rings: int, caps: bool = True) -> int:
    return 2 * segments * rings + (2 * segments if caps else 0)


def icosphere(subdivisions: int):
    """A unit icosphere: 20 * 4^subdivisions triangles."""
    t = (1 + math.sqrt(5)) / 2
    vertices = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
                         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=np.float64)
    triangles = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                          [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                          [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    vertices /= np.linalg.norm(vertices, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
        unique, inverse = np.unique(edges, axis=0, return_inverse=True)
        middle = vertices[unique].mean(axis=1)
        middle /= np.linalg.norm(middle, axis=1, keepdims=True)
        m = len(vertices) + inverse.ravel().reshape(3, -1).T  # (T, 3): the middles of edges 01, 12, 20
        vertices = np.concatenate([vertices, middle])
        a, b, c = triangles.T
        triangles = np.concatenate([np.stack([a, m[:, 0], m[:, 2]], 1), np.stack([b, m[:, 1], m[:, 0]], 1),
                                    np.stack([c, m[:, 2], m[:, 1]], 1), m])
    return vertices, triangles


def boulder(centre, radius: float, subdivisions: int, roughness: float = 0.12, seed: int = 0):
    """A sculpt-like rock: an icosphere pushed in and out by smooth noise and fine grain."""
    vertices, triangles = icosphere(subdivisions)
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(24, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    phases = rng.uniform(0, 2 * math.pi, 24)
    frequencies = rng.uniform(1.5, 6.0, 24)
    bumps = sum(np.sin(f * vertices @ d + p) / f for d, p, f in zip(directions, phases, frequencies))
    grain = rng.normal(0.0, 0.15, len(vertices))
    scale = 1 + roughness * (bumps / 3 + grain * 0.2)
    squash = np.array([1.2, 1.0, 0.75])
    points = vertices * scale[:, None] * squash * radius + np.asarray(centre, dtype=np.float64)
    points[:, 2] = np.maximum(points[:, 2], float(centre[2]) - 0.75 * radius * 0.9)  # sits on the ground
    return points, triangles


def icosphere_triangles(subdivisions: int) -> int:
    return 20 * 4 ** subdivisions


def cards(centres, normals, ups, size: float):
    """Square cards (two triangles each) at `centres` facing `normals`, their v axis along `ups`;
    UVs (4 per card, (0, 0) to (1, 1)) returned too: (vertices, triangles, uv per vertex)."""
    centres, normals, ups = (np.asarray(a, dtype=np.float64) for a in (centres, normals, ups))
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    v = ups - np.einsum("nd,nd->n", ups, normals)[:, None] * normals
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    u = np.cross(v, normals)
    half = size / 2
    corners = np.stack([centres - half * u - half * v, centres + half * u - half * v,
                        centres + half * u + half * v, centres - half * u + half * v], axis=1)
    base = 4 * np.arange(len(centres))[:, None]
    triangles = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]])
    uv = np.tile(np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64), (len(centres), 1))
    return corners.reshape(-1, 3), triangles, uv


def soup(vertices, triangles):
    """The same triangles with no vertex shared (as many imports give them)."""
    return np.asarray(vertices)[np.asarray(triangles).ravel()], np.arange(3 * len(triangles)).reshape(-1, 3)
