"""The tidy-up's bookkeeping (actors/tidy.py) and the survey's grouping (actors/search.py),
with stand-in robot actors: what is tidied in which order, and what the report says."""

from __future__ import annotations

import pytest

from actors.search import group_sightings
from actors.tidy import Tidy
from bt_engine import ActorbtError, Runtime, SubSystem, actor


def sighting(category, x, y, confidence=0.9, **kw):
    return {"category": category, "x": x, "y": y, "z": 0.0, "confidence": confidence, **kw}


def test_sightings_of_one_object_are_one_entry():
    found = group_sightings(
        [
            sighting("can", 1.00, 2.00),
            sighting("can", 1.05, 2.02),
            sighting("bottle", 1.02, 1.98, 0.4),  # a doubtful look at the can
            sighting("carton", 3.0, 1.0, yaw=0.5),
        ]
    )
    assert [(o["category"], o["sightings"]) for o in found] == [("can", 2), ("carton", 1)]
    assert found[0]["x"] == pytest.approx(1.025) and found[1]["yaw"] == 0.5


def test_a_survey_puts_an_objects_base_where_the_looks_that_see_most_of_it_do():
    found = group_sightings(
        [
            sighting("bottle", 5.30, 3.80, z=0.25, height=0.21),
            sighting("bottle", 5.29, 3.80, z=0.39, height=0.05),
            sighting("bottle", 5.29, 3.79, z=0.38, height=0.06),
        ]
    )
    assert found[0]["z"] == pytest.approx(0.25)


def test_a_surveyed_objects_pose_is_the_one_most_of_its_sightings_show():
    """One far look's noisy axis calls an upright bottle leaning; three others do not."""
    lean = {"pose": "tilted", "yaw": -0.86, "axis_dir": [0.18, -0.20, 0.96]}
    found = group_sightings(
        [
            sighting("bottle", 7.91, 7.44, 0.95, **lean),
            sighting("bottle", 7.92, 7.45, 0.80, pose="upright", yaw=0.1),
            sighting("bottle", 7.90, 7.43, 0.85, pose="upright", yaw=0.2),
            sighting("bottle", 7.91, 7.45, 0.70, pose="upright"),
        ]
    )
    assert found[0]["pose"] == "upright" and found[0]["yaw"] == 0.2 and "axis_dir" not in found[0]
    assert found[0]["confidence"] == 0.95
    tie = group_sightings(
        [sighting("bottle", 7.91, 7.44, 0.95, **lean), sighting("bottle", 7.92, 7.45, 0.80, pose="upright")]
    )
    assert tie[0]["pose"] == "tilted" and tie[0]["yaw"] == -0.86


class FakeRobot(SubSystem):
    """Catches succeed except for bottles; carrying records where things went."""

    calls: list = []

    def _log(self, *what) -> None:
        FakeRobot.calls.append(what)

    @actor
    def get_pose(self) -> tuple:
        return (0.0, 0.0, 0.0)

    @actor
    def bt_catch(self, target: dict) -> dict:
        if target["category"] == "bottle":
            raise ActorbtError("bottle grasp missed: fingers closed at 0 mm")
        self._log("catch", target["category"])
        return {"grasp": {}}

    @actor
    def bt_carry(self, place: dict) -> dict:
        self._log("carry", place["name"])
        return {"placed": {"x": place["x"], "y": place["y"]}}

    @actor
    def open(self) -> None:
        self._log("open")

    @actor
    def home(self) -> None:
        self._log("home")


PLACES = {"pallet": {"name": "pallet", "x": 7.0, "y": 6.0}, "bin": {"name": "bin", "x": 1.0, "y": 7.0}}


def test_each_object_goes_where_its_category_belongs_and_failures_are_reported():
    FakeRobot.calls = []
    with Runtime() as rt:
        rt.add_subsystem("robot", FakeRobot)
        rt.add_subsystem("tidy", Tidy)
        objects = [sighting("carton", 3.0, 0.0), sighting("can", 1.0, 0.0), sighting("bottle", 2.0, 0.0)]
        assert rt.call("tidy_start", objects) == 3
        belongs = {"can": "bin", "carton": "recycling", "default": "pallet"}  # no "recycling" here
        order = []
        while (target := rt.call("tidy_next")) is not False:
            order.append(target["category"])
            rt.call("tidy_one", target, PLACES, belongs)
        assert order == ["can", "bottle", "carton"]  # nearest first
        report = rt.call("tidy_report")
        assert [(r["category"], r["outcome"], r["place"]) for r in report] == [
            ("can", "placed", "bin"),
            ("bottle", "failed", "pallet"),
            ("carton", "placed", "pallet"),
        ]
        assert "grasp missed" in report[1]["reason"]
        assert FakeRobot.calls == [
            ("catch", "can"),
            ("carry", "bin"),
            ("open",),
            ("home",),
            ("catch", "carton"),
            ("carry", "pallet"),
        ]  # hand emptied after the miss
