"""Frontier exploration on hand-made grids: frontiers, their goals, the end of exploring."""

import math

import numpy as np
import pytest

from planning import InvalidInputError, OccupancyGrid, inflate
from planning.frontiers import frontiers, next_frontier, path_distances

RES = 0.05


def corridor(known_until: float) -> OccupancyGrid:
    """A 6 m x 1.5 m corridor along x, walled, known (free) up to x = ``known_until``."""
    data = np.zeros((30, 120), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[:, int(known_until / RES) :] = -1
    return OccupancyGrid(data, RES, (0.0, 0.0))


def test_the_frontier_is_where_the_known_corridor_ends():
    fs = frontiers(inflate(corridor(3.0), 0.2), (0.5, 0.75))
    assert len(fs) == 1
    f = fs[0]
    assert f.middle[0] == pytest.approx(2.975, abs=0.06)
    gx, gy, yaw = f.goal
    assert 2.5 < gx < 3.0 and abs(yaw) < 0.3  # just short of it, facing the unknown
    assert f.distance == pytest.approx(gx - 0.5, abs=0.15)


def test_a_fully_known_map_has_nothing_left_to_explore():
    assert next_frontier(inflate(corridor(6.0), 0.2), (0.5, 0.75)) is None


def test_goals_that_failed_are_avoided():
    cm = inflate(corridor(3.0), 0.2)
    first = next_frontier(cm, (0.5, 0.75))
    assert first is not None
    assert next_frontier(cm, (0.5, 0.75), avoid=[first.goal]) is None


def test_path_distances_go_around_walls():
    data = np.zeros((40, 40), np.int8)
    data[0:30, 20] = 100  # a wall with a gap at the top
    cm = inflate(OccupancyGrid(data, RES, (0.0, 0.0)), 0.05)
    d = path_distances(cm, (0.5, 0.5))
    straight = 1.0
    around = d[cm.grid.cell_of(1.5, 0.5)]
    assert around > straight + 1.0 and math.isfinite(around)


def test_bad_parameters_are_refused():
    with pytest.raises(InvalidInputError):
        frontiers(inflate(corridor(3.0), 0.2), (0.5, 0.75), goal_radius=0)


def test_a_small_unknown_pocket_is_not_worth_a_trip_a_closed_room_is():
    data = np.zeros((60, 80), np.int8)  # 4 m x 3 m, all seen
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[10:20, 10:22] = -1  # under a table: 0.6 m x 0.5 m unknown
    data[10:20, 10] = 100  # (its legs and back seen, the front open)
    cm = inflate(OccupancyGrid(data, RES, (0.0, 0.0)), 0.2)
    assert next_frontier(cm, (3.0, 2.0)) is None
    assert next_frontier(cm, (3.0, 2.0), min_unknown=0.1) is not None  # a big enough pocket
    # a room never looked into (1.5 m x 1.5 m behind a door) is explored
    data[28:59, 48:79] = -1
    data[28, 48:79] = 100
    data[28, 55:63] = 0  # its door, open
    f = next_frontier(inflate(OccupancyGrid(data, RES, (0.0, 0.0)), 0.2), (3.0, 0.5))
    assert f is not None and f.middle[1] == pytest.approx(1.42, abs=0.1) and 2.7 < f.middle[0] < 3.2


def test_a_goal_leaves_the_robot_room_to_turn_where_the_frontier_allows():
    # a 3 m x 2.5 m room, seen; in its top wall a slot narrower than the robot (0.35 m,
    # between a wardrobe and a wall stub) onto a space never seen
    data = np.full((80, 60), -1, np.int8)
    data[:50, :] = 0
    data[0, :] = data[:50, 0] = data[:50, -1] = 100
    data[49:51, :] = 100
    data[49:60, 28:35] = 0  # the slot, seen into
    data[49:60, 27] = data[49:60, 35] = 100  # its sides
    cm = inflate(OccupancyGrid(data, RES, (0.0, 0.0)), 0.2)
    f = next_frontier(cm, (1.5, 1.0))
    assert f is not None and f.goal is not None and f.middle[1] > 2.5
    goal_cell = cm.grid.cell_of(*f.goal[:2])
    assert cm.clearance[goal_cell] >= 0.2 + 0.1 - 1e-9
    # without the margin the goal is the nearest cell the robot may stand on, on the
    # inflation's edge
    tight = next_frontier(cm, (1.5, 1.0), goal_margin=0.0)
    assert tight is not None and tight.goal is not None
    assert cm.clearance[cm.grid.cell_of(*tight.goal[:2])] < 0.25
