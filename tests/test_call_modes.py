"""Every cell of the mode x kind matrix (docs/architecture.md, "The life of a call"), on the virtual clock."""

from __future__ import annotations

import pytest

from bt_engine import ActorTimeout, Failure, Runtime, SubSystem, Transaction, TxnState, actor
from tests.conftest import run_in_actor

STEP = 0.1  # every kind produces one value per STEP seconds


class Kinds(SubSystem):
    """One actor of each kind. Each value is (x, invocation or emission number)."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("n", 0)
        self.set_value("closed", 0)

    def _next(self) -> int:
        n = self.get_value("n") + 1
        self.set_value("n", n)
        return n

    @actor
    def sync_kind(self, x: int):
        self.run_actor("sleep", STEP)
        return (x, self._next())

    @actor("async_kind", "async", hub_only=True)  # completes on a runtime timer
    def async_kind(self, done, x: int):
        timer = self.runtime.call_later(STEP, lambda: done((x, self._next())))
        return timer.cancel

    @actor("emit_kind", "multi", hub_only=True)
    def emit_kind(self, emit, x: int):
        timer = self.runtime.call_every(STEP, lambda: emit((x, self._next())))

        def close() -> None:
            timer.cancel()
            self.set_value("closed", self.get_value("closed") + 1)

        return close

    @actor
    def gen_kind(self, x: int):
        try:
            while True:
                self.run_actor("sleep", STEP)
                yield (x, self._next())
        finally:
            self.set_value("closed", self.get_value("closed") + 1)


KINDS = ["sync_kind", "async_kind", "emit_kind", "gen_kind"]
STREAMS = {"emit_kind", "gen_kind"}


@pytest.fixture
def kinds(rt: Runtime) -> SubSystem:
    return rt.add_subsystem("k", Kinds)


def _closed(sub: SubSystem) -> int:
    return sub.get_value("closed")


@pytest.mark.parametrize("name", KINDS)
def test_sync_mode_returns_first_result(rt, kinds, name):
    assert rt.call(name, 7) == (7, 1)
    assert rt.now() == pytest.approx(STEP)
    if name in STREAMS:
        assert _closed(kinds) == 1, "a stream called in sync mode is closed after one value"
    assert rt.stats() == {"transactions": 0, "tasks": 0}


@pytest.mark.parametrize("name", KINDS)
def test_sync_mode_from_an_actor(rt, kinds, name):
    assert run_in_actor(rt, lambda: kinds.run_actor(name, 3)) == (3, 1)


@pytest.mark.parametrize("name", KINDS)
def test_async_mode_calls_back_once(rt, kinds, name):
    got = []

    def body():
        txn = kinds.run_actor_mode(name, "async", got.append, 5)
        assert isinstance(txn, Transaction)
        kinds.run_actor("sleep", 1.0)
        return txn

    txn = run_in_actor(rt, body)
    assert got == [(5, 1)]
    assert txn.state is TxnState.DONE


@pytest.mark.parametrize("name", KINDS)
def test_multi_mode_calls_back_per_value_until_cancelled(rt, kinds, name):
    got = []

    def body():
        txn = kinds.run_actor_mode(name, "multi", got.append, 2)
        kinds.run_actor("sleep", 3.5 * STEP)
        txn.cancel("enough")
        kinds.run_actor("sleep", 5 * STEP)
        return txn

    txn = run_in_actor(rt, body)
    assert got == [(2, 1), (2, 2), (2, 3)]
    assert txn.state is TxnState.CANCELLED
    if name in STREAMS:
        assert _closed(kinds) == 1
    assert rt.stats() == {"transactions": 0, "tasks": 0}


@pytest.mark.parametrize("name", KINDS)
def test_iterator_mode_yields_repeated_values_and_closes(rt, kinds, name):
    def body():
        out = []
        with kinds.run_actor_mode(name, "iterator", 4) as it:
            for v in it:
                out.append(v)
                if len(out) == 3:
                    break
        return out

    assert run_in_actor(rt, body) == [(4, 1), (4, 2), (4, 3)]
    if name in STREAMS:
        assert _closed(kinds) == 1
    assert rt.stats() == {"transactions": 0, "tasks": 0}


@pytest.mark.parametrize("name", KINDS)
def test_timed_iterator_ends_at_the_deadline(rt, kinds, name):
    def body():
        t0 = rt.now()
        with kinds.run_actor_mode(name, "timed_iterator", 3.5 * STEP, 1) as it:
            values = list(it)
        return values, rt.now() - t0

    values, elapsed = run_in_actor(rt, body)
    assert values == [(1, 1), (1, 2), (1, 3)]
    assert elapsed == pytest.approx(3.5 * STEP)
    assert rt.stats() == {"transactions": 0, "tasks": 0}


@pytest.mark.parametrize("name", KINDS)
def test_timed_mode_raises_actor_timeout_instantly(rt, kinds, name):
    with pytest.raises(ActorTimeout):
        rt.run_actor_mode(name, "timed", STEP / 2, 1)
    assert rt.now() == pytest.approx(STEP / 2)
    assert rt.run_actor_mode(name, "timed", 2 * STEP, 1) == (1, 1)


@pytest.mark.parametrize("name", KINDS)
def test_keyword_api(rt, kinds, name):
    assert rt.call(name, 1, timeout=1.0) == (1, 1)
    results = []
    txn = rt.start(name, 2, on_done=results.append)
    assert isinstance(txn, Transaction)
    rt.call("sleep", 1.0)
    assert results == [(2, 2)]
    with rt.stream(name, 3, timeout=2.5 * STEP) as it:
        assert list(it) == [(3, 3), (3, 4)]


def test_run_actor_async_is_async_mode(rt, kinds):
    got = []
    run_in_actor(rt, lambda: (kinds.run_actor_async("sync_kind", got.append, 9), kinds.run_actor("sleep", 1)))
    assert got == [(9, 1)]


def test_failure_reaches_async_callback(rt):
    class Bad(SubSystem):
        @actor
        def boom(self):
            raise ValueError("bad value")

    rt.add_subsystem("b", Bad)
    got = []
    run_in_actor(rt, lambda: (rt.start("boom", on_done=got.append), rt.sleep(0.1)))
    assert len(got) == 1 and isinstance(got[0], Failure) and not got[0]
    assert isinstance(got[0].exception.__cause__, ValueError)
