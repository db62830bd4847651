"""Work completed from another thread, on both clocks: every call mode x every actor kind.

Each actor here finishes only when a plain thread (``threading.Timer`` or a driver
thread) hands the value back, as a ROS callback or a device driver would. Deadlines are
far longer than the thread needs, so every call must complete on either clock: the
virtual clock may not jump past a deadline while such work is pending (the rule in
``bt_engine.clock.VirtualClock``).
"""

from __future__ import annotations

import threading
import time

import pytest

from bt_engine import Failure, Runtime, SubSystem, Transaction, actor
from tests.conftest import run_in_actor

DELAY = 0.03  # how long the foreign thread takes [s, wall]
DEADLINE = 1.0  # every deadline in these tests [s, runtime clock]


class Foreign(SubSystem):
    """One actor of each kind, all fed by threads."""

    @actor("async_kind", "async")
    def async_kind(self, done, x: int):
        t = threading.Timer(DELAY, done, args=(x,))
        t.start()
        return t.cancel

    @actor("emit_kind", "multi")
    def emit_kind(self, emit, x: int):
        stop = threading.Event()

        def driver() -> None:
            while not stop.wait(DELAY):
                emit(x)

        threading.Thread(target=driver, daemon=True).start()
        return stop.set

    @actor
    def sync_kind(self, x: int):
        return self.run_actor("async_kind", x)

    @actor
    def gen_kind(self, x: int):
        while True:
            yield self.run_actor("async_kind", x)


KINDS = ["sync_kind", "async_kind", "emit_kind", "gen_kind"]
CLOCKS = ["virtual", "wall"]


@pytest.fixture(params=CLOCKS)
def frt(request):
    with Runtime(clock=request.param) as rt:
        rt.add_subsystem("f", Foreign)
        yield rt


def _wait_for(cond, seconds: float = 5.0) -> None:
    t0 = time.monotonic()
    while not cond():
        assert time.monotonic() - t0 < seconds, "timed out waiting"
        time.sleep(0.005)


def _no_leftovers(rt: Runtime) -> None:
    _wait_for(lambda: rt.run_on_hub(lambda: not rt.transactions()))
    assert rt.hub.foreign_pending == 0


@pytest.mark.parametrize("kind", KINDS)
def test_sync_mode(frt, kind):
    assert frt.run_actor(kind, 7) == 7
    assert run_in_actor(frt, lambda: frt.root.run_actor(kind, 8)) == 8
    _no_leftovers(frt)


@pytest.mark.parametrize("kind", KINDS)
def test_timed_mode_completes_before_its_deadline(frt, kind):
    assert frt.run_actor_mode(kind, "timed", DEADLINE, 3) == 3
    assert frt.call(kind, 4, timeout=DEADLINE) == 4
    assert run_in_actor(frt, lambda: frt.root.call(kind, 5, timeout=DEADLINE)) == 5
    assert frt.now() < DEADLINE
    _no_leftovers(frt)


@pytest.mark.parametrize("kind", KINDS)
def test_async_mode(frt, kind):
    got: list = []
    txn = frt.run_actor_mode(kind, "async", got.append, 6)
    assert isinstance(txn, Transaction)
    _wait_for(lambda: got)
    assert got == [6]
    _no_leftovers(frt)


@pytest.mark.parametrize("kind", KINDS)
def test_multi_mode(frt, kind):
    got: list = []
    txn = frt.run_actor_mode(kind, "multi", got.append, 2)
    _wait_for(lambda: len(got) >= 3)
    txn.cancel("enough")
    _no_leftovers(frt)
    assert got[:3] == [2, 2, 2] and not any(isinstance(v, Failure) for v in got)


@pytest.mark.parametrize("kind", KINDS)
def test_iterator_mode(frt, kind):
    def take_three():
        with frt.root.run_actor_mode(kind, "iterator", 1) as it:
            return [next(it) for _ in range(3)]

    assert run_in_actor(frt, take_three) == [1, 1, 1]
    with frt.run_actor_mode(kind, "iterator", 1) as it:  # from this (outside) thread
        assert [next(it) for _ in range(2)] == [1, 1]
    _no_leftovers(frt)


@pytest.mark.parametrize("kind", KINDS)
def test_timed_iterator_mode_yields_before_its_deadline(frt, kind):
    seconds = 0.3

    def collect():
        with frt.root.run_actor_mode(kind, "timed_iterator", seconds, 9) as it:
            return list(it)

    values = run_in_actor(frt, collect)
    assert values and set(values) == {9}
    with frt.stream(kind, 9, timeout=seconds) as it:
        assert next(it) == 9
    _no_leftovers(frt)


def test_virtual_time_keeps_pace_with_wall_time_while_foreign_work_is_pending():
    """The clock rule, measured: a 0.2 s thread under a 10 s deadline finishes at about
    0.2 s of virtual time, not 10 s, and hub-only work afterwards jumps again."""

    class Slow(SubSystem):
        @actor("slow", "async")
        def slow(self, done):
            t = threading.Timer(0.2, done, args=("ok",))
            t.start()
            return t.cancel

    with Runtime() as rt:
        rt.add_subsystem("s", Slow)
        assert rt.call("slow", timeout=10.0) == "ok"
        assert 0.15 <= rt.now() < 2.0
        t0 = time.perf_counter()
        rt.call("sleep", 3600)
        assert time.perf_counter() - t0 < 1.0


def test_a_foreign_actor_that_never_answers_still_times_out():
    class Silent(SubSystem):
        @actor("silent", "async")
        def silent(self, done):
            return lambda: None

    from bt_engine import ActorTimeout

    with Runtime() as rt:
        rt.add_subsystem("s", Silent)
        t0 = time.perf_counter()
        with pytest.raises(ActorTimeout):
            rt.call("silent", timeout=0.2)
        assert 0.15 < time.perf_counter() - t0 < 5.0
        assert rt.hub.foreign_pending == 0
