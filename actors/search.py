"""Searching: drive through search locations looking around, and watch the camera.

The mission runs ``patrol`` and ``watch`` in parallel; the first sighting ends the search
(the tree halts the patrol, which stops the base).
"""
from __future__ import annotations

import logging
import math

from bt_engine import ActorbtError, ActorError, SubSystem, actor

log = logging.getLogger("actors.search")

#: a "category" meaning any category the perception knows
ANY = ("any", "mixed", "", None)
LOOK_STEP = math.radians(80)   # turn per look, about the camera's field of view [rad]
LOOK_PAUSE = 0.6               # time to hold still at each look [s]
HAND_RANGE = 0.45              # detections closer than this may be in the gripper [m]


def _in_own_hand(detection: dict) -> bool:
    """An object right in front of the camera and off the floor is the one being held."""
    return detection.get("distance", 1.0) < HAND_RANGE and detection.get("z", 0.0) > 0.03


class SearchExhausted(ActorbtError):
    """Every search location was visited and nothing was seen."""


class Search(SubSystem):
    """Search behaviour built from navigation and perception actors."""

    @actor
    def watch(self, category: str = "any") -> dict:
        """Watch the camera until an object of ``category`` ("any": any known category) is
        seen, and return its detection (map frame). Runs until found or cancelled.

        Args:
            category: the object category to watch for (can, bottle), or any
        """
        cat = None if category in ANY else category
        while True:
            found = self.run_actor("find_object", cat)
            if found and not _in_own_hand(found):
                return found

    @actor
    def look_around(self, turns: int = 4) -> None:
        """Turn on the spot in steps, pausing so the camera gets still frames.

        Args:
            turns: how many steps of about 80 degrees (the camera's field of view) to turn
        """
        for _ in range(max(1, turns)):
            self.run_actor("sleep", LOOK_PAUSE)
            self.run_actor("mini_turn", LOOK_STEP)

    @actor
    def patrol(self, locations: list, turns: int = 4) -> None:
        """Visit each (x, y) [m] of ``locations`` in turn and look around there. A place
        the base cannot reach (something stands on it, the way is blocked) is looked
        around from where the base stopped, if it got anywhere, and the patrol goes on.
        Fails with SearchExhausted after the last one: a patrol that ends has found nothing.

        Args:
            locations: the places to visit, each [x, y] in the map frame [m]; empty:
                places chosen from the map (search_views)
            turns: look_around steps at each place
        """
        if not locations:
            locations = self.run_actor("search_views")
            if not locations:
                raise SearchExhausted("no search locations given, and the map has no reachable free space")
        places = []
        for i, loc in enumerate(locations):
            try:
                places.append((float(loc[0]), float(loc[1])))
            except (TypeError, ValueError, IndexError):
                raise ActorbtError(f"search location {i} must be [x, y], got {loc!r}") from None
        missed = []
        for x, y in places:
            rx, ry, _ = self.run_actor("get_pose")
            try:
                self.run_actor("goto", x, y, math.atan2(y - ry, x - rx))
            except ActorError as e:
                missed.append(f"({x:.2f}, {y:.2f}): {e.root_cause}")
                log.info("search location (%.2f, %.2f) not reached: %s", x, y, e.root_cause)
                sx, sy, _ = self.run_actor("get_pose")
                if math.hypot(sx - rx, sy - ry) < 0.5:
                    continue                    # it did not get anywhere new
            self.run_actor("look_around", turns)
        raise SearchExhausted(f"visited {len(places)} search locations and saw nothing"
                              + (f"; {len(missed)} not reached: " + "; ".join(missed) if missed else ""))
