"""Search viewpoints on hand-made grids: every room gets a view, walls block the view."""

import numpy as np
import pytest

from planning import InvalidInputError, OccupancyGrid, inflate
from planning.viewpoints import viewpoints

RES = 0.05


def two_rooms(door: bool = True) -> OccupancyGrid:
    """8 m x 4 m, split at x = 4 m by a wall with (optionally) a 1 m door at y 1.5..2.5."""
    data = np.zeros((80, 160), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[:, 79:81] = 100
    if door:
        data[30:50, 79:81] = 0
    return OccupancyGrid(data, RES, (0.0, 0.0))


def test_each_room_is_seen_from_a_place_inside_it():
    views = viewpoints(inflate(two_rooms(), 0.2), (1.0, 1.0), view_range=2.5)
    assert any(x < 4.0 for x, _ in views) and any(x > 4.0 for x, _ in views)
    assert views[0][0] < 4.0  # the tour starts in the robot's room
    cm = inflate(two_rooms(), 0.2)
    for x, y in views:  # every place is one the base may stand on
        assert not cm.lethal[cm.grid.cell_of(x, y)]


def test_a_room_behind_a_closed_wall_is_not_visited():
    views = viewpoints(inflate(two_rooms(door=False), 0.2), (1.0, 1.0), view_range=2.5)
    assert views and all(x < 4.0 for x, _ in views)


def test_a_longer_view_range_needs_fewer_places():
    cm = inflate(two_rooms(), 0.2)
    assert len(viewpoints(cm, (1.0, 1.0), view_range=4.0)) < len(viewpoints(cm, (1.0, 1.0), view_range=1.5))


def test_places_already_looked_from_leave_only_the_rest_to_cover():
    """Given the left room's places as looked from, the rest are in the right room (or its
    doorway); given the places for both rooms, none are left."""
    cm = inflate(two_rooms(), 0.2)
    everything = viewpoints(cm, (1.0, 1.0), view_range=2.5)
    left = [(x, y) for x, y in everything if x < 4.0]
    rest = viewpoints(cm, (1.0, 1.0), view_range=2.5, seen_from=left)
    assert rest and all(x >= 4.0 for x, _ in rest), rest
    assert viewpoints(cm, (1.0, 1.0), view_range=2.5, seen_from=everything) == []


def test_a_start_inside_a_wall_uses_the_nearest_free_space():
    views = viewpoints(inflate(two_rooms(), 0.2), (0.0, 0.0))
    assert views


def test_bad_parameters_are_refused():
    with pytest.raises(InvalidInputError):
        viewpoints(inflate(two_rooms(), 0.2), (1.0, 1.0), view_range=0)
