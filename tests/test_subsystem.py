"""SubSystem, SubNet, values and name scoping."""

from __future__ import annotations

import pytest

from bt_engine import AmbiguousActorError, SubNet, SubSystem, UnknownActorError, actor


class Arm(SubSystem):
    @actor
    def home(self) -> str:
        return "arm home"

    @actor
    def status(self) -> str:
        return "arm ok"

    @actor
    def who_is_home(self) -> str:
        return self.run_actor("home")  # own scope first


class Base(SubSystem):
    def __init__(self, speed: float = 0.2) -> None:
        super().__init__()
        self.set_value("speed", speed)

    @actor
    def status(self) -> str:
        return "base ok"

    @actor
    def go(self) -> float:
        return self.get_value("speed")


class Extras(SubNet):
    @actor
    def wave(self) -> str:
        return f"wave at {self.get_value('speed')}"

    @actor
    def calls_sibling(self) -> str:
        return self.run_actor("go")


class Robot(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.add_subsystem("arm", Arm)
        self.add_subsystem("base", Base, speed=0.3)
        self.set_value("name", "tb3")

    @actor
    def home(self) -> str:
        return "robot home"

    @actor
    def arm_status(self) -> str:
        return self.run_actor("robot.arm.status")


@pytest.fixture
def robot(rt):
    r = rt.add_subsystem("robot", Robot)
    rt.run_on_hub(r._children["base"].add_network, Extras)
    return r


def test_relative_lookup_walks_up_and_down(rt, robot):
    assert rt.call("go") == 0.3  # unique below the root
    assert rt.call("who_is_home") == "arm home"  # own actor wins over the parent's
    assert rt.call("robot.home") == "robot home"


def test_dotted_names_are_absolute(rt, robot):
    assert rt.call("robot.arm.status") == "arm ok"
    assert rt.call("robot.base.status") == "base ok"
    assert rt.call("arm_status") == "arm ok"


def test_ambiguous_name_lists_both_paths(rt, robot):
    with pytest.raises(AmbiguousActorError) as e:
        rt.call("status")
    assert e.value.paths == ["robot.arm.status", "robot.base.status"]
    assert "robot.arm.status" in str(e.value) and "robot.base.status" in str(e.value)


def test_subnet_actors_live_in_their_subsystem(rt, robot):
    assert rt.resolve("wave").path == "robot.base.wave"
    assert rt.call("wave") == "wave at 0.3"
    assert rt.call("calls_sibling") == 0.3


def test_values_are_persistent_and_inherited(rt, robot):
    base = robot._children["base"]
    base.set_value("speed", 0.1)
    assert rt.call("go") == 0.1
    assert base.get_value("name") == "tb3"  # from the parent
    with pytest.raises(KeyError):
        base.get_value("nothing")
    assert base.get_value("nothing", None) is None


def test_check_actor_and_unknown(rt, robot):
    assert rt.check_actor("robot.arm.home")
    assert not rt.check_actor("status")  # ambiguous
    assert not rt.check_actor("fly")
    with pytest.raises(UnknownActorError):
        rt.call("robot.legs.walk")


def test_transactions_listing(rt, robot):
    from tests.conftest import run_in_actor

    def body():
        txn = rt.start("sleep", 10)
        live = rt.transactions()
        assert txn in live and robot.transactions() == live
        assert [t.path for t in live] == [live[0].path, "sleep"]  # the probe itself, then sleep
        txn.cancel()

    run_in_actor(rt, body)


def test_register_subsystem_alias_and_duplicates(rt):
    rt.register_subsystem("one", Arm)
    from bt_engine import ActorbtError

    with pytest.raises(ActorbtError):
        rt.add_subsystem("one", Arm)
    with pytest.raises(ActorbtError):
        rt.add_subsystem("two", object)  # type: ignore[arg-type]
