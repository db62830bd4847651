"""navstack.escape: leaving a start that the inflated map says the robot may not stand on."""

from __future__ import annotations

import math

import numpy as np

from navstack.escape import plan_out_of, way_out
from planning.base_planner import GridPlanner
from planning.failure import FailureReason
from planning.grid import OccupancyGrid, inflate


def test_a_start_inside_the_inflation_leaves_through_the_nearest_free_cell():
    data = np.zeros((40, 60), dtype=np.int8)  # 3 m x 2 m of floor, 5 cm cells
    data[:, 30] = 100  # a wall across the middle, x = 1.5 m
    data[28:, 30] = 0  # with a door at its top (y >= 1.4 m)
    planner = GridPlanner(inflate(OccupancyGrid(data, 0.05, (0.0, 0.0)), 0.20))
    start, goal = (1.35, 0.5), (2.5, 0.5)  # 0.15 m from the wall: inside the inflation
    assert planner.plan(start, goal).failure is FailureReason.START_INVALID
    path = plan_out_of(planner, start, goal, escape_distance=0.3)
    assert path is not None and path.ok
    assert path.waypoints[0] == start and path.waypoints[-1] == goal
    via = path.waypoints[1]
    assert 0.05 < math.dist(start, via) <= 0.3 and via[0] < start[0]  # away from the wall
    # nothing free within reach: no way out
    assert plan_out_of(planner, start, goal, escape_distance=0.04) is None


def _nook() -> tuple[GridPlanner, tuple, tuple]:
    """A room (y < 1.5 m) with a dead-end nook 0.35 m wide and 1 m deep off it: narrower
    than the robot's inflation, so all of the nook is inside it. The robot stands 0.7 m
    deep in it."""
    data = np.zeros((60, 60), dtype=np.int8)  # 3 m x 3 m, 5 cm cells
    data[30:, :] = 100
    data[30:50, 27:34] = 0  # the nook: x 1.35 .. 1.70 m, y 1.5 .. 2.5 m
    planner = GridPlanner(inflate(OccupancyGrid(data, 0.05, (0.0, 0.0)), 0.20))
    return planner, (1.525, 2.2), (1.5, 0.5)


def test_a_robot_deep_in_a_nook_leaves_the_way_it_came():
    planner, start, goal = _nook()
    assert planner.plan(start, goal).failure is FailureReason.START_INVALID
    assert plan_out_of(planner, start, goal, escape_distance=0.3) is None  # no free cell within reach
    path = plan_out_of(planner, start, goal, escape_distance=0.3, winding=1.5)
    assert path is not None and path.ok
    assert path.waypoints[0] == start and path.waypoints[-1] == goal
    cm = planner.costmap
    start_clear = cm.clearance[int(start[1] / 0.05), int(start[0] / 0.05)]
    for x, y in path.waypoints:
        assert cm.clearance[int(y / 0.05), int(x / 0.05)] >= start_clear - 0.05 - 1e-9  # no tighter than it came
    # the way out runs down the nook, not through its walls
    leaving = [p for p in path.waypoints if p[1] > 1.4]
    assert all(1.35 < x < 1.70 for x, _ in leaving)


def test_a_nook_deeper_than_the_winding_allowed_has_no_way_out():
    planner, start, goal = _nook()
    assert way_out(planner, start, winding=0.4) == []
    assert plan_out_of(planner, start, goal, escape_distance=0.3, winding=0.4) is None


def test_the_ways_out_are_shortest_first_and_distinct():
    planner, start, _ = _nook()
    ways = way_out(planner, start, winding=3.0)
    assert ways
    lengths = [sum(math.dist(a, b) for a, b in zip(w, w[1:])) for w in ways]
    assert all(a <= b + 1e-9 for a, b in zip(lengths, lengths[1:]))
    ends = [w[-1] for w in ways]
    assert all(math.dist(a, b) >= 0.5 - 1e-9 for i, a in enumerate(ends) for b in ends[i + 1 :])
