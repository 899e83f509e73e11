"""How shots are grouped into batches (pure Python, no GPU): the pieces of one emitting polygon
stay together, so that a texel pass can take the polygon's exact factor once per group
(shoot_to_texels.comp), and the records say where each group's shots are."""

from __future__ import annotations

import types

import numpy as np

from radiosity_addon.core.shooting.lamps import polygon_shooters
from radiosity_addon.core.shooting.shooters import DIRECTIONAL, SKY, Shooter
from radiosity_addon.core.shooting.shots import (GROUP_VEC4S, MAX_SHOTS, SHOT_VEC4S, ShotVisibility,
                                                 piece_groups, shot_records, singles_then_groups)

SQUARE = np.array([[0, 0, 1.0], [0, 1, 1], [1, 1, 1], [1, 0, 1]])


def pieces(side: float, split: int) -> list[Shooter]:
    """A `side` square emitter in `split` x `split` pieces (a scene of the size that splits it so)."""
    shooters = polygon_shooters(SQUARE * side, np.ones(3), scene_diameter=side / split * 64, max_split=split)
    assert len(shooters) == split * split
    return shooters


def single(kind: int = 0) -> Shooter:
    return Shooter(position=np.zeros(3), axes=(np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])),
                   polygon=SQUARE, area=1.0, radiosity=np.ones(3), kind=kind)


def test_pieces_of_one_polygon_form_a_group_only_when_all_are_there():
    a, b = pieces(1.0, 2), pieces(2.0, 3)
    groups, wholes = piece_groups([single(), *a, single(), *b])
    assert groups.tolist() == [0, 1, 1, 1, 1, 0] + [2] * 9
    np.testing.assert_allclose(wholes[1], SQUARE * 2.0)
    groups, wholes = piece_groups(a[:3] + b)  # an incomplete polygon: its pieces shoot one by one
    assert groups.tolist() == [0, 0, 0] + [1] * 9 and len(wholes) == 1
    assert [s.whole is None for s in singles_then_groups([*a, single()])] == [True] + [False] * 4


def test_records_say_where_each_group_is():
    a, b = pieces(1.0, 2), pieces(2.0, 2)
    records = shot_records([single(), *a, *b], [-1] * 9)
    assert records.shape == (MAX_SHOTS * (SHOT_VEC4S + GROUP_VEC4S), 4)
    shots = records[:MAX_SHOTS * SHOT_VEC4S].reshape(MAX_SHOTS, SHOT_VEC4S, 4)
    corners = records[MAX_SHOTS * SHOT_VEC4S:].reshape(MAX_SHOTS, GROUP_VEC4S, 4)
    assert shots[:9, 3, 3].tolist() == [0, 1, 1, 1, 1, 2, 2, 2, 2]
    assert corners[:2, :2, 3].tolist() == [[1, 5], [5, 9]]
    np.testing.assert_allclose(corners[1, :, :3], SQUARE * 2.0)


def test_batches_keep_a_polygons_pieces_together_where_they_fit():
    visibility = types.SimpleNamespace(capacity=9, alone=lambda s: s.kind in (DIRECTIONAL, SKY))
    a, b, c = pieces(1.0, 2), pieces(2.0, 2), pieces(3.0, 4)  # 4, 4 and 16 pieces
    batches = ShotVisibility.batches(visibility, [single(), single(), *a, *b, single(DIRECTIONAL), *c])
    # b does not fit after a (6 + 4 > 9): a batch of its own; the sun alone; c fits in no batch: split
    assert [len(batch) for batch in batches] == [6, 4, 1, 9, 7]
    assert batches[0][2:] == a and batches[1] == b and batches[2][0].kind == DIRECTIONAL
    assert piece_groups(batches[3])[1] == [] and piece_groups(batches[1])[0].tolist() == [1] * 4
