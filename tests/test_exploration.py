"""The exploration actor (actors/exploration.py) on maps it is handed: with no frontier
within reach it looks all round once before it calls the house explored.

A first scan from the start can show a closed room: the doorway behind the robot, or the
free floor beyond it, is not on the map yet. Without the look round, the exploration
ended there at once and the mission searched a one-room map (bt_map_then_fetch, house
seed 4: two search locations, every search exhausted)."""

from __future__ import annotations

import math

import numpy as np
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg

from actors.exploration import LOOK_AROUND, Exploration
from actors.navigation import NavigationError
from bt_engine import Runtime, SubSystem, actor

RES = 0.05
ORIGIN = (-2.0, -2.0)
SIZE = 80  # cells: a 4 m square, the robot at its centre


def room(doorway: bool) -> np.ndarray:
    """A closed 3 m room in unknown space; with ``doorway``, a gap in its east wall and
    free floor seen through it."""
    data = np.full((SIZE, SIZE), -1, dtype=np.int8)
    data[10:70, 10:70] = 0
    data[10:70, 10] = data[10:70, 69] = 100
    data[10, 10:70] = data[69, 10:70] = 100
    if doorway:
        data[32:48, 69] = 0  # 0.8 m wide
        data[32:48, 70:74] = 0  # and a little floor beyond, then unknown
    return data


def grid_msg(data: np.ndarray) -> OccupancyGridMsg:
    msg = OccupancyGridMsg()
    msg.header.frame_id = "map"
    msg.info.resolution = RES
    msg.info.height, msg.info.width = data.shape
    msg.info.origin.position.x, msg.info.origin.position.y = ORIGIN
    msg.info.origin.orientation.w = 1.0
    msg.data = data.ravel().tolist()
    return msg


class Base(SubSystem):
    """The navigation actors the exploration uses, on a map the test publishes: turning
    shows the doorway (when ``reveal``), driving anywhere closes it off again."""

    def __init__(self, reveal: bool, blocked_left: bool = False) -> None:
        super().__init__()
        self.reveal = reveal
        self.blocked_left = blocked_left  # a wall stops every turn to the left
        self.turns: list[float] = []
        self.goals: list[tuple[float, float, float]] = []
        self.register_subscriber("map", OccupancyGridMsg, "/map", "latched")
        self.publisher = None

    def publish(self, doorway: bool) -> None:
        self.publisher.publish(grid_msg(room(doorway)))

    @actor
    def get_pose(self) -> tuple[float, float, float]:
        return (0.0, 0.0, 0.0)

    @actor
    def mini_turn(self, angle: float) -> float:
        if self.blocked_left and angle > 0:
            raise NavigationError("turn timed out 114.4 deg short")
        self.turns.append(angle)
        if self.reveal and len(self.turns) == LOOK_AROUND:
            self.publish(doorway=True)
        return 0.0

    @actor
    def goto(self, x: float, y: float, yaw: float) -> bool:
        self.goals.append((x, y, yaw))
        self.publish(doorway=False)  # seen through: nothing more there
        return True


def explore(reveal: bool, blocked_left: bool = False) -> tuple[dict, Base]:
    rt = Runtime(clock="virtual")
    try:
        base = rt.add_subsystem("base", Base, reveal, blocked_left)
        base.publisher = rt.bus.publisher("/map", OccupancyGridMsg, "latched")
        base.publish(doorway=False)
        rt.add_subsystem("exploration", Exploration)
        return rt.call("explore", max_time=300.0), base
    finally:
        rt.close()


def test_a_closed_room_on_a_young_map_is_looked_round_before_the_exploration_ends():
    result, base = explore(reveal=False)
    assert result["finished"] and result["goals"] == 0
    assert base.turns == [2 * math.pi / LOOK_AROUND] * LOOK_AROUND
    assert base.goals == []


def test_what_the_look_round_shows_is_explored():
    result, base = explore(reveal=True)
    assert result["finished"] and result["goals"] == 1
    ((x, y, _),) = base.goals
    assert x > 1.0 and abs(y) < 0.5, "the goal is at the doorway in the east wall"
    # one look round at the start, one after the goal (the map closed again)
    assert len(base.turns) == 2 * LOOK_AROUND


def test_a_look_round_blocked_one_way_looks_round_the_other():
    result, base = explore(reveal=True, blocked_left=True)
    assert result["finished"] and result["goals"] == 1
    assert base.turns[:LOOK_AROUND] == [-2 * math.pi / LOOK_AROUND] * LOOK_AROUND
