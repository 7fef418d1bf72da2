"""Tests of the disk-among-boxes kinematics shared by TwoRoom and SimplePointMaze."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.envs.planar import given_factors, grow_boxes, is_free, push_out, segment_clear, sweep

LO, HI = np.zeros(2), np.full(2, 10.0)
WALL = np.array([[4.0, 0.0, 5.0, 10.0]])  # a full-height vertical wall
GAPPED = np.array([[4.0, 0.0, 5.0, 4.0], [4.0, 6.0, 5.0, 10.0]])  # the same wall with a gap y in (4, 6)


def test_free_move_is_exact():
    pos, blocked = sweep([1.0, 1.0], [0.5, 0.25], WALL, LO, HI)
    np.testing.assert_allclose(pos, [1.5, 1.25])
    assert not blocked.any()


@pytest.mark.parametrize("step", [3.5, 50.0])
def test_no_tunnelling_whatever_the_step(step):
    pos, blocked = sweep([1.0, 2.0], [step, 0.0], WALL, LO, HI)
    np.testing.assert_array_equal(pos, [4.0, 2.0])  # stopped exactly at the face
    assert blocked.tolist() == [True, False]


def test_slides_along_the_face_for_the_rest_of_the_step():
    pos, blocked = sweep([3.0, 2.0], [2.0, 2.0], WALL, LO, HI)
    np.testing.assert_allclose(pos, [4.0, 4.0])  # 1 unit to the face, the remaining y motion slides
    assert blocked.tolist() == [True, False]
    again, _ = sweep(pos, [1.0, 1.0], WALL, LO, HI)  # resting on the face: still no entry
    np.testing.assert_allclose(again, [4.0, 5.0])


def test_passes_through_a_gap_but_not_off_it():
    through, blocked = sweep([3.0, 5.0], [3.0, 0.0], GAPPED, LO, HI)
    np.testing.assert_allclose(through, [6.0, 5.0])
    assert not blocked.any()
    stopped, _ = sweep([3.0, 3.0], [3.0, 0.0], GAPPED, LO, HI)
    np.testing.assert_allclose(stopped, [4.0, 3.0])


def test_moving_away_from_a_face_is_free():
    pos, blocked = sweep([4.0, 2.0], [-1.0, 0.5], WALL, LO, HI)
    np.testing.assert_allclose(pos, [3.0, 2.5])
    assert not blocked.any()


def test_bounds_stop_and_slide():
    pos, blocked = sweep([9.0, 5.0], [3.0, 1.0], np.zeros((0, 4)), LO, HI)
    np.testing.assert_allclose(pos, [10.0, 6.0])
    assert blocked.tolist() == [True, False]


def test_random_steps_never_enter_a_box():
    rng = np.random.default_rng(0)
    boxes = grow_boxes(GAPPED, 0.3)
    pos = np.array([1.0, 5.0])
    for _ in range(2000):
        pos, _ = sweep(pos, rng.uniform(-2, 2, 2), boxes, LO, HI)
        assert is_free(pos, boxes, LO, HI)


def test_grow_boxes_and_push_out():
    grown = grow_boxes(WALL, 0.5)
    np.testing.assert_array_equal(grown, [[3.5, -0.5, 5.5, 10.5]])
    np.testing.assert_allclose(push_out([4.0, 3.0], grown, LO, HI), [3.5, 3.0])  # nearest face
    np.testing.assert_allclose(push_out([5.2, 3.0], grown, LO, HI), [5.5, 3.0])
    np.testing.assert_allclose(push_out([12.0, 3.0], grown, LO, HI), [10.0, 3.0])  # clipped into bounds
    assert not is_free([4.0, 3.0], grown, LO, HI) and is_free([3.5, 3.0], grown, LO, HI)


def test_segment_clear():
    assert segment_clear([3.0, 5.0], [6.0, 5.0], GAPPED)
    assert not segment_clear([3.0, 3.0], [6.0, 5.0], GAPPED)
    assert not segment_clear([4.5, 3.0], [4.5, 3.0], GAPPED)  # a point inside a box
    assert segment_clear([4.0, 1.0], [4.0, 2.0], GAPPED)  # along a face


def test_given_factors_flattens_nested_and_dotted():
    options = {"variation_values": {"agent": {"color": [1, 2, 3]}, "goal.position": [1, 1]}}
    assert given_factors(options) == {"agent.color", "goal.position"}
    assert given_factors(None) == set() and given_factors({"variation": ["all"]}) == set()
