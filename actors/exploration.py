"""Exploring: drive to the frontiers of the map being built until none is left.

The map comes from whatever publishes ``/map`` while the robot maps (navstack's mapper in
the simulator, slam_toolbox on a robot); the robot's pose from tf; the driving is the
navigation's ``goto``. Nothing here knows how the map is made.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from bt_engine import ActorbtError, ActorError, SubSystem, actor
from planning import OccupancyGrid, inflate
from planning.frontiers import next_frontier, path_distances

from .navigation import ROBOT_RADIUS

log = logging.getLogger("actors.exploration")

MAP_WAIT = 10.0  # [s] for the first /map
SETTLE = 1.0  # [s] after each goal, so the map takes in the new scans
LOOK_AROUND = 3  # turns of a third of a circle each: a look all round


class ExplorationError(ActorbtError):
    """The exploration could not start (no map) or ran out of time."""


class Exploration(SubSystem):
    """Frontier exploration built from the navigation actors and ``/map``."""

    def _map(self) -> OccupancyGrid:
        try:
            return OccupancyGrid.from_msg(self.run_actor_mode("map", "timed", MAP_WAIT))
        except ActorbtError as e:
            raise ExplorationError(f"no map on /map to explore ({e}); is a mapper running?") from None

    @actor(moves=True, limits={"max_time": (0.0, None), "max_goals": (1, None)})
    def explore(self, max_time: float = 900.0, min_frontier: float = 0.3, max_goals: int = 200) -> dict:
        """Drive to the nearest worthwhile frontier of the map, again and again, until the
        map has none the base can reach. A goal is not tried twice: one the base could not
        reach, or one whose frontier stayed (a gap the laser cannot see through), is
        avoided from then on.

        Args:
            max_time: give up after this long [s] (ExplorationError)
            min_frontier: frontiers shorter than this are not worth a trip [m]
            max_goals: give up after this many goals (ExplorationError)

        Returns:
            finished (True), goals (reached), failed (goals not reached), seconds (the
            time it took)
        """
        start = self.runtime.now()
        failed: list[tuple[float, float, float]] = []
        visited: list[tuple[float, float, float]] = []
        looked_around = False
        while True:
            elapsed = self.runtime.now() - start
            if elapsed > max_time or len(visited) + len(failed) >= max_goals:
                raise ExplorationError(
                    f"exploration unfinished after {elapsed:.0f} s and "
                    f"{len(visited) + len(failed)} goals ({len(failed)} not reached)"
                )
            x, y, _ = self.run_actor("get_pose")
            costmap = inflate(self._map(), ROBOT_RADIUS)
            if not np.isfinite(path_distances(costmap, (x, y))).any():
                # a map too young to show free floor around the robot: wait for more scans
                if elapsed > MAP_WAIT:
                    raise ExplorationError("the map shows no free floor around the robot")
                self.run_actor("sleep", SETTLE)
                continue
            frontier = next_frontier(costmap, (x, y), avoid=failed + visited, min_size=min_frontier)
            if frontier is None and not looked_around:
                # No frontier it can reach from here: on a young map (the first scans from
                # the start) the free floor is a sliver the inflation closes, and an opening
                # may lie behind the robot. Look all round once before calling it done.
                self._look_around()
                looked_around = True
                continue
            if frontier is None:
                return {
                    "finished": True,
                    "goals": len(visited),
                    "failed": len(failed),
                    "seconds": round(self.runtime.now() - start, 1),
                }
            goal = frontier.goal
            assert goal is not None  # next_frontier passes over frontiers without a goal
            gx, gy, gyaw = goal
            log.info(
                "frontier of %d cells at (%.2f, %.2f): going to (%.2f, %.2f)", frontier.size, *frontier.middle, gx, gy
            )
            try:
                self.run_actor("goto", gx, gy, gyaw)
                visited.append(goal)
                looked_around = False
            except ActorError as e:
                log.info("frontier goal (%.2f, %.2f) not reached: %s", gx, gy, e.root_cause)
                failed.append(goal)
            self.run_actor("sleep", SETTLE)

    def _look_around(self) -> None:
        """Turn a full circle in place, in thirds, letting the map take in the scans. A
        turn that something blocks (the arm against a wall beside the robot) is not the end
        of the exploration: the robot looks round the other way instead, and goes on with
        what it saw either way."""
        log.info("no frontier within reach: looking all round")
        for direction in (1.0, -1.0):
            try:
                for _ in range(LOOK_AROUND):
                    self.run_actor("mini_turn", direction * 2 * math.pi / LOOK_AROUND)
                break
            except ActorError as e:
                log.info("the look round is blocked turning %s: %s", "left" if direction > 0 else "right", e.root_cause)
        self.run_actor("sleep", SETTLE)
