"""Automatic lightmap UVs for objects whose surfaces come without any.

Coplanar surfaces of one object that share an edge form one chart (so the two
triangles of the Cornell box's left wall are one seamless chart); every chart
is its surface(s) projected onto their plane at a common scale (texels per
scene unit), and the charts are shelf-packed, each keeping `pad` texels of
free space on every side for the texels its polygons touch and its gutter.
Loops here run over the surfaces and charts of objects that came without UVs (scene files
written by hand or by tools); the Blender exporter always gives UVs, so they never run on a
user's furnished room. Never over texels or patches.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SolveError
from ..scene import Surface


@dataclass
class ChartLayout:
    """Where an object's surfaces land in its lightmap."""
    size: tuple[int, int]  # (width, height) in texels
    scale: float  # texels per scene unit
    uv_maps: dict[int, np.ndarray]  # surface index -> (2, 4) affine map: uv = M @ [x, y, z, 1]


def _edge_keys(surface: Surface, quantum: float) -> list[tuple]:
    corners = [tuple(np.round(v / quantum).astype(np.int64)) for v in surface.vertices]
    return [tuple(sorted((corners[k], corners[(k + 1) % len(corners)]))) for k in range(len(corners))]


# Faces sharing an edge whose normals differ by less than this unfold into one chart with
# negligible stretch (1 - cos 1° = 1.5e-4): e.g. the Cornell box's left wall, 3 mm off-plane.
FLAT_COSINE = math.cos(math.radians(1.0))


def group_charts(surfaces: dict[int, Surface], indices: list[int], scene_size: float) -> list[list[int]]:
    """Connected groups of (nearly) coplanar surfaces sharing an edge (union-find over `indices`)."""
    quantum = 1e-6 * scene_size
    parent = {i: i for i in indices}

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    # a chart keeps its first surface's normal, so gentle bends cannot add up along a chain of
    # faces into a curved chart that its projection would fold
    chart_normal = {i: surfaces[i].normal for i in indices}
    owner_of_edge: dict[tuple, int] = {}
    for i in indices:
        for key in _edge_keys(surfaces[i], quantum):
            j = owner_of_edge.setdefault(key, i)
            a, b = root(i), root(j)
            if a != b and chart_normal[a] @ chart_normal[b] > FLAT_COSINE:
                parent[a] = b
    groups: dict[int, list[int]] = {}
    for i in indices:
        groups.setdefault(root(i), []).append(i)
    return list(groups.values())


@dataclass
class _Chart:
    surfaces: list[int]
    origin: np.ndarray  # (3,) world point mapped to the chart's (0, 0)
    axes: np.ndarray  # (2, 3) orthonormal in-plane axes, scene units
    extent: np.ndarray  # (2,) width, height in scene units


def _chart(surfaces: dict[int, Surface], members: list[int]) -> _Chart:
    """Project the members onto the first one's plane, turned so their bounding box is smallest
    (the smallest box of a convex hull lies along one of its edges: try every edge)."""
    normal = surfaces[members[0]].normal
    points = np.concatenate([surfaces[i].vertices for i in members])
    edges = np.concatenate([np.roll(surfaces[i].vertices, -1, axis=0) - surfaces[i].vertices for i in members])
    first = edges[np.argmax(np.linalg.norm(edges, axis=1))]
    first = first - (first @ normal) * normal  # other members may tilt off the plane slightly
    base = np.stack([first, np.cross(normal, first)]) / np.linalg.norm(first)  # an in-plane frame
    flat = edges @ base.T
    flat = flat[np.linalg.norm(flat, axis=1) > 0]
    # box orientations repeat every 90°: one candidate per distinct edge angle (a grid has few)
    angles = np.unique(np.round(np.mod(np.arctan2(flat[:, 1], flat[:, 0]), np.pi / 2), 6))
    directions = np.stack([np.cos(angles), np.sin(angles)], axis=1) @ base  # (D, 3) unit u axes
    u_coords = points @ directions.T  # (n, D)
    v_coords = points @ np.cross(normal, directions).T  # (u, v, normal) right-handed: seen from the front
    areas = np.ptp(u_coords, axis=0) * np.ptp(v_coords, axis=0)
    best = int(np.argmin(areas))
    axes = np.stack([directions[best], np.cross(normal, directions[best])])
    coords = points @ axes.T
    low, high = coords.min(axis=0), coords.max(axis=0)
    extent = high - low
    if extent[1] > extent[0]:  # landscape charts pack better on shelves; a 90° turn keeps the front
        axes, extent = np.stack([axes[1], -axes[0]]), extent[::-1]
        low = np.array([low[1], -high[0]])
    origin = axes.T @ low  # world-space offset whose projection is `low`
    return _Chart(surfaces=members, origin=origin, axes=axes, extent=extent)


def _shelf_pack(boxes: np.ndarray, width: int) -> tuple[np.ndarray, int]:
    """Place (n, 2) integer boxes (w, h) on shelves of `width`, tallest first.
    Returns (n, 2) lower-left corners and the height used (inf if a box is wider than `width`)."""
    if boxes[:, 0].max() > width:
        return np.zeros_like(boxes), math.inf
    corners = np.zeros_like(boxes)
    x = y = shelf_height = 0
    for k in np.argsort(-boxes[:, 1], kind="stable"):
        w, h = boxes[k]
        if x + w > width:
            x, y, shelf_height = 0, y + shelf_height, 0
        corners[k] = (x, y)
        x += w
        shelf_height = max(shelf_height, h)
    return corners, y + shelf_height


def _boxes(charts: list[_Chart], scale: float, pad: int) -> np.ndarray:
    return np.array([np.ceil(c.extent * scale).astype(int) + 2 * pad for c in charts]).reshape(-1, 2)


def natural_size(charts: list[_Chart], scale: float, pad: int) -> tuple[int, int]:
    """Width and height the charts need at `scale`, packed into a roughly square image."""
    boxes = _boxes(charts, scale, pad)
    width = max(int(boxes[:, 0].max()), int(math.ceil(math.sqrt((boxes[:, 0] * boxes[:, 1]).sum()) * 1.05)))
    _, height = _shelf_pack(boxes, width)
    return width, int(height)


def _fits(charts, scale, pad, size) -> bool:
    _, height = _shelf_pack(_boxes(charts, scale, pad), size[0])
    return height <= size[1]


def largest_fitting_scale(charts: list[_Chart], size: tuple[int, int], pad: int, object_name: str) -> float:
    """Bisection for the largest scale at which the charts fit into `size` texels."""
    total_area = sum(float(c.extent.prod()) for c in charts)
    high = math.sqrt(size[0] * size[1] / max(total_area, 1e-30))  # even without pads no larger
    low = 0.0
    if not _fits(charts, 1e-9 * high, pad, size):
        raise SolveError(
            f"object '{object_name}': {len(charts)} charts with {pad}-texel margins do not fit into a"
            f" {size[0]}x{size[1]} lightmap; raise its resolution"
        )
    for _ in range(40):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _fits(charts, middle, pad, size) else (low, middle)
    return low


def make_charts(surfaces: dict[int, Surface], indices: list[int], scene_size: float) -> list[_Chart]:
    """Charts of the surfaces `indices` (`surfaces` maps each index to its Surface)."""
    return [_chart(surfaces, members) for members in group_charts(surfaces, indices, scene_size)]


def place_charts(charts: list[_Chart], size: tuple[int, int], scale: float, pad: int) -> ChartLayout:
    """UV maps of every surface once the charts are packed at `scale` into `size`."""
    boxes = _boxes(charts, scale, pad)
    corners, _ = _shelf_pack(boxes, size[0])
    texel_to_uv = 1.0 / np.asarray(size, dtype=np.float64)
    uv_maps = {}
    for chart, corner in zip(charts, corners):
        # uv = ((x - origin) . axes * scale + corner + pad) / size
        linear = chart.axes * scale * texel_to_uv[:, None]
        offset = (corner + pad) * texel_to_uv - linear @ chart.origin
        m = np.concatenate([linear, offset[:, None]], axis=1)
        for index in chart.surfaces:
            uv_maps[index] = m
    return ChartLayout(size=size, scale=scale, uv_maps=uv_maps)
