"""Searching: drive through search locations looking around, and watch the camera.

The mission runs ``patrol`` and ``watch`` in parallel; the first sighting ends the search
(the tree halts the patrol, which stops the base).
"""

from __future__ import annotations

import logging
import math
import statistics
from typing import Callable

from bt_engine import ActorbtError, ActorError, SubSystem, actor

from .perception_detect import base_height

log = logging.getLogger("actors.search")

#: a "category" meaning any category the perception knows
ANY = ("any", "mixed", "", None)
LOOK_STEP = math.radians(80)  # turn per look, about the camera's field of view [rad]
LOOK_PAUSE = 0.6  # time to hold still at each look [s]
HAND_RANGE = 0.45  # detections closer than this may be in the gripper [m]
WAYPOINT_CLEARANCE = 0.25  # room a search location needs for the base [m] (navigation
# plans with a 0.20 m robot radius)
MAX_SHIFT = 1.0  # how far a blocked search location may be moved [m]
SIDESTEP = 0.45  # where to look from when the navigation refuses a location [m]
SAME_OBJECT = 0.20  # survey sightings closer than this are one object [m]
REJECTED_RADIUS = 0.2  # sightings this near a rejected one are passed over [m]
LOOKS_PER_TURN = 2  # frames a survey takes at each of its views


def in_own_hand(detection: dict) -> bool:
    """An object right in front of the camera and off the floor is the one being held."""
    return detection.get("distance", 1.0) < HAND_RANGE and detection.get("z", 0.0) > 0.03


def group_sightings(sightings: list[dict], gate: float = SAME_OBJECT) -> list[dict]:
    """One entry per object from sightings of many: a sighting within ``gate`` of a
    group's first one joins it; a group's position is the median of its category's
    sightings, its category the majority (ties: the most confident), and so its pose
    (upright, lying, tilted) and the yaw and axis of its most confident sighting in that
    pose: one far sighting's lean is often noise. Most-seen first."""
    groups: list[list[dict]] = []
    for s in sightings:
        for g in groups:
            if math.dist((s["x"], s["y"]), (g[0]["x"], g[0]["y"])) <= gate:
                g.append(s)
                break
        else:
            groups.append([s])
    out = []
    for g in groups:
        cats = [s["category"] for s in g]
        category = max(set(cats), key=lambda c: (cats.count(c), max(s["confidence"] for s in g if s["category"] == c)))
        mine = [s for s in g if s["category"] == category]
        best = max(mine, key=lambda s: s["confidence"])
        obj = {"category": category, "sightings": len(mine), "confidence": best["confidence"]}
        for k in ("x", "y"):
            obj[k] = float(statistics.median(s[k] for s in mine))
        obj["z"] = base_height(mine)
        poses = [s.get("pose") for s in mine]
        pose = max(set(poses), key=lambda p: (poses.count(p), max(s["confidence"] for s in mine if s.get("pose") == p)))
        posed = max((s for s in mine if s.get("pose") == pose), key=lambda s: s["confidence"])
        for k in ("yaw", "pose", "axis_base", "axis_dir"):
            if posed.get(k) is not None:
                obj[k] = posed[k]
        out.append(obj)
    out.sort(key=lambda o: -o["sightings"])
    return out


class SearchExhausted(ActorbtError):
    """Every search location was visited and nothing was seen."""


class Search(SubSystem):
    """Search behaviour built from navigation and perception actors."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("rejected", [])  # (x, y, category) a closer look said were not

    @actor(read_only=True)
    def watch(self, category: str = "any") -> dict:
        """Watch the camera until an object of ``category`` ("any": any known category) is
        seen, and return its detection (map frame). Runs until found or cancelled.

        Args:
            category: the object category to watch for (a registered one: can, bottle,
                carton, ...), or any
        """
        cat = None if category in ANY else category
        while True:
            found = self.run_actor("find_object", cat)
            if found and not in_own_hand(found) and not self._rejected(found):
                return found

    @actor
    def reject_sighting(self, x: float, y: float, category: str) -> None:
        """Remember that what was seen at (x, y) is no ``category`` after all (a closer
        look saw something else there, or grasps there kept failing): ``watch`` passes
        over it from now on.

        Args:
            x: where it was seen, map frame [m]
            y: where it was seen, map frame [m]
            category: what it was taken for
        """
        self.set_value("rejected", [*self.get_value("rejected"), (float(x), float(y), category)])

    def _rejected(self, detection: dict) -> bool:
        return any(
            c == detection["category"] and math.hypot(detection["x"] - x, detection["y"] - y) < REJECTED_RADIUS
            for x, y, c in self.get_value("rejected")
        )

    @actor(moves=True, limits={"turns": (1, 8)})
    def look_around(self, turns: int = 4) -> None:
        """Turn on the spot in steps, pausing so the camera gets still frames.

        Args:
            turns: how many steps of about 80 degrees (the camera's field of view) to turn
        """
        for _ in range(max(1, turns)):
            self.run_actor("sleep", LOOK_PAUSE)
            self.run_actor("mini_turn", LOOK_STEP)

    def _free_spot_near(self, x: float, y: float) -> tuple[float, float] | None:
        """(x, y) itself if the base fits there, else the nearest spot within MAX_SHIFT
        where it does (rings of 10 cm, 16 directions), else None."""
        if self.run_actor("clearance", x, y) >= WAYPOINT_CLEARANCE:
            return x, y
        for k in range(1, int(round(MAX_SHIFT / 0.1)) + 1):
            r = 0.1 * k
            for j in range(16):
                a = j * math.pi / 8
                px, py = x + r * math.cos(a), y + r * math.sin(a)
                if self.run_actor("clearance", px, py) >= WAYPOINT_CLEARANCE:
                    return px, py
        return None

    def _goto_near(self, x: float, y: float, rx: float, ry: float) -> str | None:
        """Drive to (x, y) from (rx, ry); if the navigation fails (something the lidar
        sees stands there, the way is blocked), to one of a few spots around it, on the
        robot's side first (three tries at most). Returns None, or why it was not reached."""
        heading = math.atan2(y - ry, x - rx)
        try:
            self.run_actor("goto", x, y, heading)
            return None
        except ActorError as e:
            first = e.root_cause
        back = heading + math.pi  # the robot's side of the location first
        spots = [
            (x + SIDESTEP * math.cos(back + k * math.pi / 3), y + SIDESTEP * math.sin(back + k * math.pi / 3))
            for k in (0, 1, -1, 2, -2, 3)
        ]
        tries = 0
        for px, py in spots:
            if tries == 3 or self.run_actor("clearance", px, py) < WAYPOINT_CLEARANCE:
                continue
            tries += 1
            sx, sy, _ = self.run_actor("get_pose")
            try:
                self.run_actor("goto", px, py, math.atan2(py - sy, px - sx))
                log.info("search location (%.2f, %.2f) refused; looking from (%.2f, %.2f)", x, y, px, py)
                return None
            except ActorError:
                continue
        return str(first)

    def _visit(self, locations: list, at_each: Callable[[], None], cover_map: bool = False) -> tuple[list, list[str]]:
        """Drive to each location (moved or skipped when blocked; see ``patrol``) and call
        ``at_each`` there; with ``cover_map``, then also at places chosen from the map
        that see the floor those leave unseen. Returns the locations and the reasons of
        those not reached."""
        given = bool(locations)
        if not given:
            locations = self.run_actor("search_views")
            if not locations:
                raise SearchExhausted("no search locations given, and the map has no reachable free space")
        places = []
        for i, loc in enumerate(locations):
            try:
                places.append((float(loc[0]), float(loc[1])))
            except (TypeError, ValueError, IndexError):
                raise ActorbtError(f"search location {i} must be [x, y], got {loc!r}") from None
        missed: list[str] = []
        looked_from = self._look_from_each(places, at_each, missed)
        if cover_map and given:
            rest = [tuple(p) for p in self.run_actor("search_views", seen_from=looked_from)]
            if rest:
                log.info(
                    "search: %d more places from the map see the floor the %d locations did not", len(rest), len(places)
                )
                self._look_from_each(rest, at_each, missed)
                places += rest
        return places, missed

    def _look_from_each(
        self, places: list[tuple[float, float]], at_each: Callable[[], None], missed: list[str]
    ) -> list[list[float]]:
        """The visiting loop of ``_visit``: returns where the robot looked from; why a
        place was not reached goes into ``missed``."""
        looked_from = []
        for x0, y0 in places:
            spot = self._free_spot_near(x0, y0)
            if spot is None:
                missed.append(f"({x0:.2f}, {y0:.2f}): no room for the base within {MAX_SHIFT:.1f} m")
                log.info("search location (%.2f, %.2f) skipped: no room for the base near it", x0, y0)
                continue
            x, y = spot
            if (x, y) != (x0, y0):
                log.info("search location (%.2f, %.2f) is blocked; looking from (%.2f, %.2f)", x0, y0, x, y)
            rx, ry, _ = self.run_actor("get_pose")
            error = self._goto_near(x, y, rx, ry)
            if error is not None:
                missed.append(f"({x:.2f}, {y:.2f}): {error}")
                log.info("search location (%.2f, %.2f) not reached: %s", x, y, error)
                sx, sy, _ = self.run_actor("get_pose")
                if math.hypot(sx - rx, sy - ry) < 0.5:
                    continue  # it did not get anywhere new
            at_each()
            sx, sy, _ = self.run_actor("get_pose")
            looked_from.append([sx, sy])
        return looked_from

    @actor(moves=True, limits={"turns": (0, 8)})
    def patrol(self, locations: list, turns: int = 4, cover_map: bool = False) -> None:
        """Visit each (x, y) [m] of ``locations`` in turn and look around there. A place
        where the base does not fit (an object or furniture stands on it) is moved to the
        nearest spot within 1 m where it does, or skipped. A place the base cannot reach
        (the way is blocked) is looked around from where the base stopped, if it got
        anywhere, and the patrol goes on.
        Fails with SearchExhausted after the last one: a patrol that ends has found nothing.

        Args:
            locations: the places to visit, each [x, y] in the map frame [m]; empty:
                places chosen from the map (search_views)
            turns: look_around steps at each place
            cover_map: after the locations, also look around from places chosen from the
                map that see the floor they leave unseen (a hand-made list rarely sees
                every corner)
        """
        places, missed = self._visit(locations, lambda: self.run_actor("look_around", turns), cover_map)
        raise SearchExhausted(
            f"visited {len(places)} search locations and saw nothing"
            + (f"; {len(missed)} not reached: " + "; ".join(missed) if missed else "")
        )

    @actor(moves=True, limits={"views": (1, 16)})
    def survey(self, locations: list, views: int = 8, cover_map: bool = True) -> list:
        """Visit every search location (moved or skipped when blocked, as ``patrol``
        does), look all around at each, and return every object of a known category
        seen: [{category, x, y, z, sightings, confidence (, yaw)}] in the map frame,
        most-seen first. Unlike ``patrol`` with ``watch``, it does not stop at the first;
        and it looks only while standing still, so the views overlap (8 views of the
        camera's ~69 degrees cover the full turn with ~24 degrees to spare).

        Args:
            locations: the places to visit, each [x, y] in the map frame [m]; empty:
                places chosen from the map (search_views)
            views: how many views, evenly spaced over a full turn, at each place
            cover_map: after the locations, also look from places chosen from the map
                that see the floor they leave unseen (a tidy-up wants every object)
        """
        sightings: list[dict] = []
        step = 2 * math.pi / max(1, views)

        def look() -> None:
            for k in range(max(1, views)):
                if k:
                    self.run_actor("mini_turn", step)
                self.run_actor("sleep", LOOK_PAUSE)
                for _ in range(LOOKS_PER_TURN):
                    sightings.extend(
                        d for d in self.run_actor("object_glance") if d["category"] != "unknown" and not in_own_hand(d)
                    )

        self._visit(locations, look, cover_map)
        found = group_sightings(sightings)
        log.info("survey: %d objects from %d sightings", len(found), len(sightings))
        return found
