"""Search locations and the floor they leave unseen (actors/search.py), on a hand-made
two-room map with a base that goes where it is told."""

from __future__ import annotations

import math

import numpy as np
import pytest

from actors.search import Search, SearchExhausted
from bt_engine import ActorError, SubSystem, actor
from planning.grid import OccupancyGrid, inflate
from planning.viewpoints import viewpoints
from tests.conftest import run_in_actor


def two_rooms():
    """8 m x 4 m, split at x = 4 m by a wall with a 1 m door at y 1.5..2.5 (5 cm cells)."""
    data = np.zeros((80, 160), np.int8)
    data[0, :] = data[-1, :] = data[:, 0] = data[:, -1] = 100
    data[:, 79:81] = 100
    data[30:50, 79:81] = 0
    return inflate(OccupancyGrid(data, 0.05, (0.0, 0.0)), 0.2)


class _Base(SubSystem):
    """The navigation and perception actors a search asks, on ``costmap``: ``goto``
    teleports, the camera sees nothing; each place turned at is remembered."""

    def __init__(self, costmap):
        super().__init__()
        self.costmap = costmap
        self.pose = (1.0, 1.0, 0.0)
        self.looked_from: list[tuple[float, float]] = []

    @actor
    def get_pose(self) -> tuple:
        return self.pose

    @actor
    def clearance(self, x: float, y: float) -> float:
        row, col = self.costmap.grid.cell_of(x, y)
        return float(self.costmap.clearance[row, col]) if self.costmap.grid.contains(row, col) else 0.0

    @actor
    def goto(self, x: float, y: float, theta: float) -> tuple:
        self.pose = (x, y, theta)
        return self.pose

    @actor
    def search_views(self, view_range: float = 2.5, seen_from: list | None = None) -> list:
        return [
            list(p)
            for p in viewpoints(
                self.costmap, self.pose[:2], view_range=view_range, seen_from=[tuple(p) for p in seen_from or ()]
            )
        ]

    @actor
    def mini_turn(self, angle: float) -> None:
        if not self.looked_from or self.looked_from[-1] != self.pose[:2]:
            self.looked_from.append(self.pose[:2])

    @actor
    def object_glance(self) -> list:
        return []


@pytest.fixture
def base_and_search(rt):
    base = rt.add_subsystem("base", _Base, two_rooms())
    return base, rt.add_subsystem("search", Search)


def test_a_patrol_visits_exactly_the_locations_it_was_given(rt, base_and_search):
    base, search = base_and_search
    with pytest.raises(ActorError) as e:
        run_in_actor(rt, lambda: search.patrol([[1.0, 2.0], [2.5, 2.0]], turns=1))
    assert isinstance(e.value.root_cause, SearchExhausted)
    assert "visited 2 search locations" in str(e.value.root_cause)
    assert base.looked_from == [(1.0, 2.0), (2.5, 2.0)]


def test_a_survey_of_one_room_also_looks_from_the_map_places_that_see_the_other(rt, base_and_search):
    base, search = base_and_search
    assert run_in_actor(rt, lambda: search.survey([[2.0, 2.0]], views=2)) == []
    assert base.looked_from[0] == (2.0, 2.0)
    assert any(x > 4.5 for x, _ in base.looked_from), base.looked_from  # the other room
    # given everything already, nothing more is added
    base.looked_from.clear()
    everywhere = viewpoints(two_rooms(), (1.0, 1.0))
    run_in_actor(rt, lambda: search.survey([list(p) for p in everywhere], views=2))
    assert [tuple(map(float, p)) for p in base.looked_from] == [tuple(p) for p in everywhere]


def test_a_patrol_asked_to_cover_the_map_goes_on_after_its_locations(rt, base_and_search):
    base, search = base_and_search
    with pytest.raises(ActorError, match=r"visited \d+ search locations") as e:
        run_in_actor(rt, lambda: search.patrol([[2.0, 2.0]], turns=1, cover_map=True))
    visited = int(str(e.value.root_cause).split()[1])
    assert visited > 1 and len(base.looked_from) == visited
    assert any(x > 4.5 for x, _ in base.looked_from)
    assert math.isclose(base.looked_from[0][0], 2.0)
