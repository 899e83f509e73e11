"""The furnished room's geometry as plain data (no bpy), and how much detail a triangle target buys.

The room's inside spans x ∈ [0, 6], y ∈ [0, 4], z ∈ [0, 2.8] m; walls are 15 cm thick, floor
and ceiling slabs 20 cm. The window is in the south wall (y < 0). Every piece is built in world
coordinates except the chairs, which are built at the origin facing +y and placed by rooms.py.

Detail grows with the target through the pieces whose triangle counts are known in closed form
(shapes.py): chair and table legs, books, the curtain, the vase and bowl, and the sofa's Bevel
segments and Subdivision levels (measured in Blender 5.0: a box beveled with s segments has
12(s + 1)² − 4·(s odd) triangles, and 48(s + 1)²·4^(L − 1) after L ≥ 1 subdivision levels).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .shapes import box_between, cylinder, drape, lathe, merge, triangle_count, wall_with_opening

WIDTH, DEPTH, HEIGHT = 6.0, 4.0, 2.8  # the inside, m
WALL, SLAB = 0.15, 0.2
WINDOW = (2.2, 3.8, 0.9, 2.3)  # x0, x1, z0, z1 of the opening in the south wall
SHELF_LOW, SHELF_HIGH = (5.65, 0.6, 0.0), (6.0, 1.8, 1.9)
SHELF_BOARDS = (0.0, 0.48, 0.96, 1.44, 1.88)  # bottom of each board, 2 cm thick
BOARD = 0.02
TABLE_LOW, TABLE_HIGH = (2.8, 1.6, 0.0), (4.2, 2.4, 0.76)
SOFA_BOXES = [((0.5, 3.1, 0.0), (2.7, 3.95, 0.4)),  # base
              ((0.5, 3.75, 0.4), (2.7, 3.95, 0.85)),  # back
              ((0.5, 3.1, 0.4), (0.7, 3.75, 0.62)), ((2.5, 3.1, 0.4), (2.7, 3.75, 0.62))]  # arms
CUSHION_BOXES = [((0.7 + 0.6 * k + 0.01, 3.12, 0.4), (0.7 + 0.6 * (k + 1) - 0.01, 3.74, 0.52)) for k in range(3)]
SOFA_BEVEL_WIDTH = 0.04
BOOK_COLOURS = 5  # material slots of a row of books


@dataclass(frozen=True)
class Detail:
    """The knobs that the triangle target turns."""
    bevel_segments: int = 1  # sofa and cushions
    subdivision: int = 0  # sofa and cushions
    chairs: int = 2
    leg_segments: int = 4  # chair and table legs (4: square posts)
    books_per_shelf: int = 5
    curtain_columns: int = 6
    curtain_rows: int = 4
    prop_segments: int = 8  # vase and bowl, around
    prop_rings: int = 4  # vase and bowl, up


MAX_CHAIRS = 6
MAX_BOOKS_PER_SHELF = 30
# shares of the triangles above the least detailed room; the sofa takes what is left
SHARES = {"chairs": 0.12, "books": 0.08, "curtain": 0.15, "props": 0.15}


def beveled_box_triangles(segments: int, levels: int) -> int:
    if levels == 0:
        return 12 * (segments + 1) ** 2 - 4 * (segments % 2)
    return 48 * (segments + 1) ** 2 * 4 ** (levels - 1)


def sofa_triangles(detail: Detail) -> int:
    return (len(SOFA_BOXES) + len(CUSHION_BOXES)) * beveled_box_triangles(detail.bevel_segments, detail.subdivision)


def predicted_triangles(detail: Detail) -> int:
    """The room's evaluated triangle count, from the shapes' closed forms (the builder reports the real one)."""
    return triangle_count(fixed_faces()) + triangle_count(furniture_faces(detail)) + sofa_triangles(detail)


def detail_for(triangles_target: int) -> Detail:
    """The detail whose room has about (at most, above the least detailed room) `triangles_target`
    triangles: the chairs, books and props take their shares of the triangles above the least
    detailed room, the sofa the most Subdivision and then Bevel its share allows (at least 1
    segment, no subdivision), and the curtain what is left."""
    least = Detail()
    extra = max(0, triangles_target - predicted_triangles(least))
    legs = 4 * (MAX_CHAIRS + 1)  # chairs' and table's legs, 4 each
    chairs = int(min(MAX_CHAIRS, least.chairs + extra * SHARES["chairs"] / 400))
    leg_segments = int(np.clip((SHARES["chairs"] * extra / legs + 4) / 4, 4, 64))
    books = int(min(MAX_BOOKS_PER_SHELF, least.books_per_shelf + SHARES["books"] * extra / (12 * 4)))
    segments = max(least.prop_segments, int(math.sqrt(SHARES["props"] * extra / 2)))
    detail = replace(least, chairs=chairs, leg_segments=leg_segments, books_per_shelf=books, prop_segments=segments,
                     prop_rings=max(least.prop_rings, segments // 2))
    sofa_budget = triangles_target - predicted_triangles(detail) + sofa_triangles(detail) - SHARES["curtain"] * extra
    boxes = len(SOFA_BOXES) + len(CUSHION_BOXES)
    fits = [(levels, s) for levels in range(4) for s in range(1, 9)
            if boxes * beveled_box_triangles(s, levels) <= sofa_budget]
    levels, bevel = max(fits, default=(0, 1))
    detail = replace(detail, bevel_segments=bevel, subdivision=levels)
    curtain_budget = triangles_target - predicted_triangles(detail) + 2 * least.curtain_columns * least.curtain_rows
    rows = max(least.curtain_rows, int(math.sqrt(max(curtain_budget, 0) / 4)))
    return replace(detail, curtain_columns=max(least.curtain_columns, 2 * rows), curtain_rows=rows)


# ---------------------------------------------------------------- the pieces

def fixed_faces():
    """Every piece whose detail does not change, merged (for counting)."""
    return merge(*[part for part, _ in fixed_pieces().values()])[1]


def fixed_pieces() -> dict:
    """{name: ((vertices, faces), material key)} of the shell and the plain pieces."""
    w, d, h, t = WIDTH, DEPTH, HEIGHT, WALL
    x0, x1, z0, z1 = WINDOW
    frame = 0.06  # window bars' width; 8 cm deep, in the middle of the wall's thickness
    bar_y = (-t / 2 - 0.04, -t / 2 + 0.04)
    pieces = {
        "Floor": (box_between((-t, -t, -SLAB), (w + t, d + t, 0.0)), "floor"),
        "Ceiling": (box_between((-t, -t, h), (w + t, d + t, h + SLAB)), "ceiling"),
        "Wall North": (box_between((-t, d, 0.0), (w + t, d + t, h)), "plaster"),
        "Wall West": (box_between((-t, 0.0, 0.0), (0.0, d, h)), "paint"),
        "Wall East": (box_between((w, 0.0, 0.0), (w + t, d, h)), "plaster"),
        "Window Wall": (wall_with_opening((-t, -t, 0.0), (w + t, 0.0, h), WINDOW), "plaster"),
        "Window Frame": (merge(box_between((x0, bar_y[0], z0), (x0 + frame, bar_y[1], z1)),
                               box_between((x1 - frame, bar_y[0], z0), (x1, bar_y[1], z1)),
                               box_between((x0 + frame, bar_y[0], z0), (x1 - frame, bar_y[1], z0 + frame)),
                               box_between((x0 + frame, bar_y[0], z1 - frame), (x1 - frame, bar_y[1], z1)),
                               box_between(((x0 + x1 - frame) / 2, bar_y[0], z0 + frame),
                                           ((x0 + x1 + frame) / 2, bar_y[1], z1 - frame))), "frame"),
        # a plane 1 cm off the wall, and the emissive panel 2 cm under the ceiling, facing down
        "Painting": (([(0.01, 1.5, 1.2), (0.01, 2.4, 1.2), (0.01, 2.4, 1.8), (0.01, 1.5, 1.8)], [(0, 1, 2, 3)]),
                     "painting"),
        "Ceiling Panel": (([(2.4, 1.7, h - 0.02), (2.4, 2.3, h - 0.02), (3.6, 2.3, h - 0.02),
                            (3.6, 1.7, h - 0.02)], [(0, 1, 2, 3)]), "panel"),
        "Rug": (box_between((0.6, 1.8, 0.0), (2.2, 3.0, 0.012)), "rug"),
    }
    lo, hi = SHELF_LOW, SHELF_HIGH
    side = [box_between(lo, (hi[0], lo[1] + BOARD, hi[2])), box_between((lo[0], hi[1] - BOARD, 0.0), hi)]
    boards = [box_between((lo[0], lo[1] + BOARD, z), (hi[0], hi[1] - BOARD, z + BOARD)) for z in SHELF_BOARDS]
    back = box_between((hi[0] - BOARD, lo[1] + BOARD, 0.0), (hi[0], hi[1] - BOARD, hi[2]))  # against the wall
    pieces["Shelf"] = (merge(*side, *boards, back), "shelf")
    return pieces


def furniture_faces(detail: Detail):
    """The detail-dependent pieces other than the sofa, merged (for counting)."""
    parts = [table(detail), curtain(detail), vase(detail), bowl(detail)]
    parts += [chair(detail)] * detail.chairs + [books(detail, level, np.random.default_rng(0))[:2]
                                                for level in range(len(SHELF_BOARDS) - 1)]
    return merge(*parts)[1]


def legs(corners, radius: float, height: float, segments: int):
    return merge(*[cylinder((x, y, 0.0), radius, height, segments) for x, y in corners])


def table(detail: Detail):
    (xl, yl, _), (xh, yh, zh) = TABLE_LOW, TABLE_HIGH
    inset, top = 0.08, 0.04
    corners = [(xl + inset, yl + inset), (xh - inset, yl + inset), (xl + inset, yh - inset), (xh - inset, yh - inset)]
    return merge(box_between((xl, yl, zh - top), (xh, yh, zh)), legs(corners, 0.03, zh - top, detail.leg_segments))


def chair(detail: Detail):
    """At the origin, the seat's centre above it, facing +y (its back at −y)."""
    half, seat, thick = 0.21, 0.43, 0.04
    corners = [(sx * (half - 0.03), sy * (half - 0.03)) for sx in (-1, 1) for sy in (-1, 1)]
    return merge(box_between((-half, -half, seat), (half, half, seat + thick)),
                 box_between((-half, -half, seat + thick), (half, -half + 0.03, seat + thick + 0.45)),
                 legs(corners, 0.018, seat, detail.leg_segments))


def chair_places(count: int) -> list[tuple[tuple[float, float], float]]:
    """((x, y), yaw in degrees) of the first `count` chairs around the table, facing it."""
    (xl, yl, _), (xh, yh, _) = TABLE_LOW, TABLE_HIGH
    xm, ym, gap = (xl + xh) / 2, (yl + yh) / 2, 0.3
    places = [((xm - 0.35, yl - gap), 0.0), ((xm + 0.35, yh + gap), 180.0), ((xm + 0.35, yl - gap), 0.0),
              ((xm - 0.35, yh + gap), 180.0), ((xl - gap, ym), -90.0), ((xh + gap, ym), 90.0)]
    return places[:count]


def books(detail: Detail, level: int, rng):
    """One row of books standing on shelf board `level`, spines towards the room (−x):
    (vertices, faces, material index per face) — each book one of BOOK_COLOURS colours."""
    (xl, yl, _), (xh, yh, _) = SHELF_LOW, SHELF_HIGH
    floor = SHELF_BOARDS[level] + BOARD
    clearance = SHELF_BOARDS[level + 1] - floor
    count = detail.books_per_shelf
    inner = yh - yl - 2 * BOARD
    widths = np.minimum(rng.uniform(0.02, 0.05, count), 0.95 * inner / count)
    heights = rng.uniform(0.5, 0.85, count) * clearance
    depths = rng.uniform(0.6, 0.9, count) * (xh - xl - BOARD)
    starts = yl + BOARD + 0.002 + np.concatenate([[0.0], np.cumsum(widths[:-1] + 0.002)])
    parts = [box_between((xh - BOARD - depth, y, floor), (xh - BOARD, y + width, floor + height))
             for y, width, height, depth in zip(starts, widths, heights, depths)]
    vertices, faces = merge(*parts)
    colours = rng.integers(0, BOOK_COLOURS, count)
    return vertices, faces, np.repeat(colours, 6).tolist()


def curtain(detail: Detail):
    """Beside the window, 10 cm in front of the wall: one sheet, no thickness."""
    return drape((WINDOW[1] + 0.1, 0.1, 0.3), 0.7, HEIGHT - 0.45, detail.curtain_columns, detail.curtain_rows,
                 depth=0.06, folds=3)


def _profile(radius, height: float, rings: int):
    heights = np.linspace(0.0, height, rings)
    return list(zip(radius(heights / height), heights))


def vase(detail: Detail):
    """On the table; open at the top."""
    def radius(s):
        return 0.05 + 0.035 * np.sin(np.pi * np.minimum(s / 0.75, 1.0)) - 0.02 * np.maximum(s - 0.75, 0) / 0.25

    return lathe(_profile(radius, 0.28, detail.prop_rings), detail.prop_segments, (3.3, 2.0, TABLE_HIGH[2]))


def bowl(detail: Detail):
    """On the table: an open hemispherical shell, one sheet."""
    def radius(s):
        return 0.03 + 0.1 * np.sin(0.5 * np.pi * s)

    return lathe(_profile(radius, 0.08, detail.prop_rings), detail.prop_segments, (3.8, 2.1, TABLE_HIGH[2]))
