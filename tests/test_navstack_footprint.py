"""navstack.footprint: the base's box swept by a velocity command."""

from __future__ import annotations

import math

import numpy as np
import pytest

from navstack.footprint import box_distance, sweep_hits, turn_hits

BOX = (-0.21, 0.08, 0.155)


def test_box_distance_is_zero_inside_and_euclidean_outside():
    pts = np.array([[0.0, 0.0], [0.18, 0.0], [-0.21, 0.255], [-0.31, -0.255]])
    assert box_distance(pts, BOX) == pytest.approx([0.0, 0.10, 0.10, math.hypot(0.1, 0.1)])


def test_a_can_behind_the_side_is_hit_by_a_turn_away_from_it_not_towards_it():
    # a can's near side 2 cm off the base's left side, level with the rear
    can = np.array([[-0.18, 0.175]])
    assert turn_hits(can, (0.0, 0.0, 0.0), -math.pi / 2, BOX)  # clockwise: the rear swings left
    assert not turn_hits(can, (0.0, 0.0, 0.0), 0.3, BOX)  # a bit counter-clockwise: away from it


def test_the_sweep_is_checked_in_the_pose_frame():
    # the same can and turn, the robot at (2, 1) facing +y
    x, y, yaw = 2.0, 1.0, math.pi / 2
    c, s = math.cos(yaw), math.sin(yaw)
    can = np.array([[x + c * -0.18 - s * 0.175, y + s * -0.18 + c * 0.175]])
    assert turn_hits(can, (x, y, yaw), -math.pi / 2, BOX)
    assert not turn_hits(can, (x, y, yaw), 0.3, BOX)


def test_driving_away_from_what_the_base_touches_is_allowed_and_into_it_is_not():
    touching = np.array([[-0.215, 0.0]])  # half a centimetre behind the rear
    assert not sweep_hits(touching, (0.0, 0.0, 0.0), 0.1, 0.0, 0.4, BOX)
    assert sweep_hits(touching, (0.0, 0.0, 0.0), -0.1, 0.0, 0.4, BOX)


def test_an_arc_hits_what_its_rear_swings_into_within_the_duration():
    can = np.array([[-0.18, -0.18]])  # 2.5 cm off the right side, at the rear
    assert sweep_hits(can, (0.0, 0.0, 0.0), 0.1, 1.0, 0.4, BOX)  # left turn: the rear swings right
    assert not sweep_hits(can, (0.0, 0.0, 0.0), 0.1, 1.0, 0.01, BOX)  # too short to reach it
    assert not sweep_hits(can, (0.0, 0.0, 0.0), 0.1, -1.0, 0.4, BOX)


def test_points_inside_the_box_and_no_motion_never_hit():
    inside = np.array([[0.0, 0.1], [-0.1, -0.1]])
    assert not turn_hits(inside, (0.0, 0.0, 0.0), math.pi, BOX)
    assert not sweep_hits(np.array([[-0.22, 0.0]]), (0.0, 0.0, 0.0), 0.0, 0.0, 1.0, BOX)
    assert not sweep_hits(np.zeros((0, 2)), (0.0, 0.0, 0.0), 0.1, 1.0, 1.0, BOX)
