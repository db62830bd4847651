"""Tidying up: put every object found where its category belongs.

The mission ``bt_tidy_up`` surveys the house (``survey``, in actors/search.py), then
takes the objects one by one (``tidy_next``) and has ``tidy_one`` catch each and carry it
to its category's place, recording what happened to it; ``tidy_report`` is the list.
"""

from __future__ import annotations

import logging
import math

from bt_engine import ActorError, Cancelled, SubSystem, actor

log = logging.getLogger("actors.tidy")

DEFAULT_PLACE = "default"


class Tidy(SubSystem):
    """The objects still to tidy, and what happened to those tidied."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("todo", [])
        self.set_value("report", [])

    @actor
    def tidy_start(self, objects: list) -> int:
        """Start a tidy-up of ``objects`` (as ``survey`` returns them); returns how many.

        Args:
            objects: the objects to tidy, each a dict with category, x, y (map frame [m])
        """
        self.set_value("todo", [dict(o) for o in objects])
        self.set_value("report", [])
        return len(objects)

    @actor
    def tidy_next(self) -> dict | bool:
        """The next object to tidy, taken off the list; False when none is left."""
        todo = list(self.get_value("todo"))
        if not todo:
            return False
        rx, ry, _ = self.run_actor("get_pose")
        todo.sort(key=lambda o: math.hypot(o["x"] - rx, o["y"] - ry))  # nearest first
        self.set_value("todo", todo[1:])
        return todo[0]

    @actor(moves=True)
    def tidy_one(self, target: dict, places: dict, belongs: dict) -> dict:
        """Catch ``target`` and carry it to the place its category belongs to; never
        fails: the outcome goes into the report (``placed`` or ``failed`` with the
        reason), and a failure leaves the hand empty and the arm folded.

        Args:
            target: the object, as survey reports it (category, x, y in the map frame [m])
            places: place surfaces by name, each {x, y, size_x, size_y, height} [m]
            belongs: place name by category; "default": for the others, and where the
                category's place is not among ``places``

        Returns:
            the report entry: category, x, y, place, outcome, and reason or placed
        """
        category = target.get("category", "")
        place_name = belongs.get(category)
        if place_name not in places:  # none named, or this world has no such place
            place_name = belongs.get(DEFAULT_PLACE)
        entry = {
            "category": category,
            "x": round(float(target["x"]), 3),
            "y": round(float(target["y"]), 3),
            "place": place_name,
        }
        try:
            if place_name not in places:
                raise LookupError(f"no place {place_name!r} for {category} (places: {', '.join(places)})")
            self.run_actor("bt_catch", target=target)
            carried = self.run_actor("bt_carry", place=places[place_name])
            entry.update(outcome="placed", placed=carried.get("placed"))
        except Cancelled:
            raise
        except (ActorError, LookupError) as e:
            cause = getattr(e, "root_cause", None) or e
            entry.update(outcome="failed", reason=str(cause))
            log.info("tidy: %s at (%.2f, %.2f) not tidied: %s", category, entry["x"], entry["y"], cause)
            self._empty_hand()
        self.set_value("report", self.get_value("report") + [entry])
        return entry

    def _empty_hand(self) -> None:
        """After a failure: let go of whatever is held and fold the arm (best effort)."""
        for name in ("open", "home"):
            try:
                self.run_actor(name)
            except ActorError as e:
                log.warning("tidy: %s after a failure failed: %s", name, e)

    @actor(read_only=True)
    def tidy_report(self) -> list:
        """What happened to each object of the tidy-up so far, in the order tidied."""
        return list(self.get_value("report"))
