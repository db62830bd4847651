"""Virtual and wall clocks, timeouts, determinism."""

from __future__ import annotations

import time

import pytest

from bt_engine import ActorTimeout, Runtime, SubSystem, actor
from tests.conftest import run_in_actor


def test_virtual_sleep_takes_no_wall_time(rt):
    t0 = time.perf_counter()
    rt.call("sleep", 3600)
    assert rt.now() == pytest.approx(3600)
    assert time.perf_counter() - t0 < 1.0


def test_timeout_fires_instantly_under_virtual_clock(rt):
    t0 = time.perf_counter()
    with pytest.raises(ActorTimeout) as e:
        rt.call("sleep", 600, timeout=300)
    assert rt.now() == pytest.approx(300)
    assert "within 300 s" in str(e.value)
    assert time.perf_counter() - t0 < 1.0


def test_wall_clock_sleeps_in_real_time():
    with Runtime(clock="wall") as rt:
        t0 = time.perf_counter()
        rt.call("sleep", 0.05)
        assert 0.04 < time.perf_counter() - t0 < 1.0


def test_periodic_timers_alone_do_not_advance_virtual_time(rt):
    ticks = []
    rt.call_every(0.01, lambda: ticks.append(rt.now()))
    time.sleep(0.05)
    assert ticks == [] and rt.now() == 0.0
    rt.call("sleep", 0.1)
    assert len(ticks) == 10


def _program(log):
    class Chatty(SubSystem):
        @actor
        def worker(self, name: str, period: float):
            for i in range(5):
                self.run_actor("sleep", period)
                log.append((round(self.runtime.now(), 9), name, i))

        @actor
        def main(self):
            txns = [
                self.run_actor_mode("worker", "async", None, n, p)
                for n, p in [("a", 0.3), ("b", 0.2), ("c", 0.3), ("d", 0.1)]
            ]
            self.run_actor("sleep", 5)
            return [t.state.value for t in txns]

    with Runtime() as rt:
        rt.add_subsystem("c", Chatty)
        return rt.call("main")


def test_same_program_twice_gives_identical_event_order():
    a, b = [], []
    _program(a)
    _program(b)
    assert a == b and len(a) == 20
    # ties resolve in the order the timers were set: a and c set theirs at 0.3 s, b at 0.4 s
    assert [e[1] for e in a if e[0] == 0.6] == ["a", "c", "b"]
    times = [e[0] for e in a]
    assert times == sorted(times)


def test_sleep_actor_is_on_the_root(rt):
    assert rt.resolve("sleep").path == "sleep"
    assert run_in_actor(rt, lambda: (rt.call("sleep", 2), rt.now())[1]) == pytest.approx(2)
