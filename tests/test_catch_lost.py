"""A failed grasp that leaves the object nowhere the look round sees (a slipping can rolls
off) is not retried at the same sighting (actors/catch.py ``lost_at``): the retry fails at
once, and the fetch searches afresh."""

from __future__ import annotations

import pytest

from bt_engine import ActorError

from tests.conftest import place_robot
from tests.localised_rig import localised_rig

START = (1.5, 2.0, 0.0)


def test_the_sighting_a_failed_grasp_lost_is_not_approached_again():
    def setup(sim):
        can = next(n for n in sim.object_names() if sim.object_category(n) == "can")
        state["can"] = can
        sim.set_object_pose(can, 2.5, 2.0)
        place_robot(sim, START)

    state: dict = {}
    with localised_rig("open_floor", 0, START, setup) as (rt, sim):
        found = rt.call("get_found", category="can")
        assert found, "the can in front of the robot is not seen"
        close = rt.call("approach_object", target=found)
        rt.call("open")
        # it rolls off out of sight before the fingers close
        sim.set_object_pose(state["can"], 2.5, -3.5)
        with pytest.raises(ActorError, match="grasp missed"):
            rt.call("pick", target=close)
        with pytest.raises(ActorError, match="any more"):
            rt.call("approach_object", target=found)
