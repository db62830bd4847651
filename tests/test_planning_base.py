"""planning.grid and planning.base_planner: inflation and grid search with smoothing."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from planning import (
    FailureReason,
    GridPlanner,
    InvalidInputError,
    NoPathError,
    OccupancyGrid,
    inflate,
    plan_base_path,
)

RES = 0.05
RADIUS = 0.2


def wall_with_door(door: bool = True) -> OccupancyGrid:
    """An 8 m x 6 m flat with its origin at (-1, -1): a 10 cm wall at
    x = 3.0..3.1 m splits it into two rooms, with a 0.8 m door at y = 2.2..3.0 m;
    a 1 m x 0.5 m table stands in the right room at x = 5..6, y = 1.5..2.0 m."""
    h, w = int(6 / RES), int(8 / RES)
    d = np.zeros((h, w), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    d[:, 80:82] = 100  # x = 3.0 .. 3.1 in map coordinates
    if door:
        d[64:80, 80:82] = 0  # the door
    d[50:60, 120:140] = 100  # the table
    return OccupancyGrid(d, RES, (-1.0, -1.0))


def _segment_is_clear(costmap, a, b) -> float:
    """Smallest clearance along a -> b sampled every 5 mm [m]."""
    grid = costmap.grid
    n = int(math.ceil(math.dist(a, b) / 0.005)) + 1
    worst = math.inf
    for t in np.linspace(0, 1, n):
        x, y = a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t
        r, c = grid.cell_of(x, y)
        assert grid.contains(r, c)
        worst = min(worst, float(costmap.clearance[r, c]))
    return worst


def test_inflation_marks_cells_too_close_to_obstacles():
    grid = wall_with_door()
    cm = inflate(grid, RADIUS)
    assert cm.lethal[grid.data >= 65].all()
    r, c = grid.cell_of(1.0, 1.0)  # room centre
    assert not cm.lethal[r, c] and cm.cost[r, c] == 0.0
    r, c = grid.cell_of(2.95, 1.0)  # 5 cm from the wall
    assert cm.lethal[r, c]
    r, c = grid.cell_of(2.7, 1.0)  # 25-30 cm from the wall: free but costly
    assert not cm.lethal[r, c] and 0.0 < cm.cost[r, c] < 1.0
    assert np.all(cm.clearance[~cm.lethal] >= RADIUS)


def test_path_through_the_door_is_collision_free_and_smoothed():
    grid = wall_with_door()
    planner = GridPlanner(inflate(grid, RADIUS))
    start, goal = (0.5, 0.5), (5.5, 0.5)
    path = planner.plan(start, goal)
    assert path.ok, path.message
    assert path.waypoints[0] == start and path.waypoints[-1] == goal
    assert 3 <= len(path.waypoints) < 12
    assert path.length <= path.raw_length + 1e-9
    assert path.length > math.dist(start, goal)  # the wall forces a detour
    assert path.min_clearance >= RADIUS
    for a, b in zip(path.waypoints[:-1], path.waypoints[1:]):
        assert _segment_is_clear(planner.costmap, a, b) >= RADIUS
    # it crosses the wall through the door, near its middle
    crossings = [(a, b) for a, b in zip(path.waypoints[:-1], path.waypoints[1:]) if (a[0] - 3.05) * (b[0] - 3.05) < 0]
    assert len(crossings) == 1
    (ax, ay), (bx, by) = crossings[0]
    y_at_wall = ay + (by - ay) * (3.05 - ax) / (bx - ax)
    assert abs(y_at_wall - 2.6) < 0.15
    assert path.planning_time < 0.5


def test_blocked_door_is_a_clean_failure():
    path = plan_base_path(wall_with_door(door=False), (0.5, 0.5), (5.5, 0.5), robot_radius=RADIUS)
    assert not path.ok and path.waypoints == ()
    assert path.failure is FailureReason.NO_PATH
    assert "not connected" in path.message
    with pytest.raises(NoPathError):
        path.raise_for_failure()


def test_door_too_narrow_for_a_fat_robot():
    path = plan_base_path(wall_with_door(), (0.5, 0.5), (5.5, 0.5), robot_radius=0.45)
    assert path.failure is FailureReason.NO_PATH


def test_bad_start_and_goal_are_reported():
    grid = wall_with_door()
    planner = GridPlanner(inflate(grid, RADIUS))
    assert planner.plan((3.05, 1.0), (5.5, 0.5)).failure is FailureReason.START_INVALID  # in the wall
    outside = planner.plan((0.5, 0.5), (50.0, 0.5))
    assert outside.failure is FailureReason.GOAL_INVALID and "outside the map" in outside.message
    near_table = planner.plan((0.5, 0.5), (4.95, 1.75))  # 5 cm beside the table
    assert near_table.failure is FailureReason.GOAL_INVALID and "robot radius" in near_table.message
    assert planner.plan(("a", 1), (1, 1)).failure is FailureReason.INVALID_INPUT


def test_unknown_space_blocks_unless_allowed():
    grid = wall_with_door()
    d = grid.data.copy()
    d[:, 60:70] = -1  # an unexplored band across the left room
    unknown = OccupancyGrid(d, RES, grid.origin)
    assert plan_base_path(unknown, (0.5, 0.5), (5.5, 0.5), robot_radius=RADIUS).failure is FailureReason.NO_PATH
    goal_unknown = plan_base_path(unknown, (0.5, 0.5), (2.25, 0.5), robot_radius=RADIUS)
    assert goal_unknown.failure is FailureReason.GOAL_INVALID and "unknown" in goal_unknown.message
    allowed = plan_base_path(unknown, (0.5, 0.5), (5.5, 0.5), robot_radius=RADIUS, unknown_is_obstacle=False)
    assert allowed.ok, allowed.message


def test_grid_from_a_nav_msgs_like_message():
    grid = wall_with_door()
    h, w = grid.shape
    msg = SimpleNamespace(
        info=SimpleNamespace(
            resolution=RES,
            width=w,
            height=h,
            origin=SimpleNamespace(
                position=SimpleNamespace(x=-1.0, y=-1.0, z=0.0),
                orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
        ),
        data=grid.data.reshape(-1).tolist(),
    )
    again = OccupancyGrid.from_msg(msg)
    assert np.array_equal(again.data, grid.data) and again.origin == grid.origin
    msg.info.origin.orientation = SimpleNamespace(x=0.0, y=0.0, z=0.3827, w=0.9239)
    with pytest.raises(InvalidInputError, match="rotated"):
        OccupancyGrid.from_msg(msg)
    with pytest.raises(InvalidInputError):
        OccupancyGrid(np.zeros(5), RES)
    with pytest.raises(InvalidInputError):
        inflate(grid, -1.0)
