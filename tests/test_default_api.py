"""The module-level API (ros_actor's names) over the default runtime (bt_engine.default)."""

from __future__ import annotations

import pathlib
import subprocess
import sys

import pytest

import bt_engine
from bt_engine import (
    Runtime,
    SubSystem,
    actor,
    close_default_runtime,
    default_runtime,
    register_subsystem,
    run_actor,
    run_actor_async,
    run_actor_mode,
    set_default_runtime,
)

PROGRAM = pathlib.Path(__file__).parent / "programs" / "seed_pic_find.py"


@pytest.mark.parametrize("clock", ["virtual", "wall"])
def test_a_ros_actor_style_program_runs_on_the_default_runtime(clock):
    out = subprocess.run([sys.executable, str(PROGRAM), clock], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("found=(22, 13) frame=(24, 32, 3) async=(24, 32, 3)")
    assert "Traceback" not in out.stderr


class Greeter(SubSystem):
    @actor
    def hello(self, name: str = "world") -> str:
        return f"hello {name}"

    @actor
    def nested(self) -> str:
        # module-level calls inside an actor act on the runtime running it
        return run_actor("hello", "from inside")


@pytest.fixture
def fresh_default():
    close_default_runtime()
    yield
    close_default_runtime()


def test_the_default_runtime_is_made_on_first_use_and_remade_after_close(fresh_default):
    register_subsystem("g", Greeter)
    first = default_runtime()
    assert run_actor("hello") == "hello world"
    assert run_actor_mode("hello", "timed", 1.0, "ada") == "hello ada"
    got: list = []
    run_actor_async("hello", got.append, "bob")
    run_actor("sleep", 0.1)
    assert got == ["hello bob"]
    assert bt_engine.check_actor("g.hello") and not bt_engine.check_actor("nope")
    close_default_runtime()
    assert first.closed
    assert default_runtime() is not first


def test_inside_an_actor_the_module_api_uses_that_actors_runtime(fresh_default):
    with Runtime() as rt:
        rt.add_subsystem("g", Greeter)
        assert rt.call("nested") == "hello from inside"
    assert bt_engine.default._default is None  # no default runtime was made


def test_an_explicit_default_runtime_is_used(fresh_default):
    rt = Runtime(clock="wall")
    set_default_runtime(rt)
    register_subsystem("g", Greeter)
    assert rt.call("hello") == "hello world"
    close_default_runtime()
    assert rt.closed


def test_values_at_the_root(fresh_default):
    bt_engine.set_value("speed", 0.3)
    assert bt_engine.get_value("speed") == 0.3
    assert bt_engine.get_value("missing") is None


def test_ros_actor_forms_subnet_constructor_close_pairs_and_mode_words(rt):
    from bt_engine import SubNet

    closed: list = []

    class Net(SubNet):
        def __init__(self, subsystem):  # ros_actor's SubNet(subsystem)
            super().__init__(subsystem)
            self.owner = subsystem

        @actor("ticks", "multi", hub_only=True)
        def ticks(self, emit):
            timer = self.owner.runtime.call_every(0.1, lambda: emit(1))
            # ros_actor returns [('close', fn(transaction))] rather than a closer
            return [("close", lambda tran: (timer.cancel(), closed.append(tran.path)))]

    class Sys(SubSystem):
        def __init__(self, name, parent):
            super().__init__(name, parent)
            self.add_network(Net)

    s = rt.add_subsystem("s", Sys)
    assert s.path == "s"
    with rt.run_actor_mode("ticks", "timed_iterator", 0.35) as it:
        assert list(it) == [1, 1, 1]
    assert closed == ["s.ticks"]
    assert rt.run_actor_mode("ticks", "timed_sync", 1.0) == 1
