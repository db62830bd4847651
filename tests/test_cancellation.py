"""Cancellation at every blocking primitive, and nothing left behind afterwards."""

from __future__ import annotations

import threading

import pytest

from bt_engine import ActorCancelled, Cancelled, Runtime, Signal, SubSystem, TxnState, actor
from tests.conftest import run_in_actor, started_since


class Blockers(SubSystem):
    """Actors that block in each primitive and record where Cancelled reached them."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("seen", [])
        self.set_value("closed", [])
        self.signal = Signal(self.runtime)
        self.release = threading.Event()  # frees the offloaded worker

    def _seen(self, where: str) -> None:
        self.get_value("seen").append(where)

    @actor
    def in_sleep(self):
        try:
            self.run_actor("sleep", 100)
        except Cancelled:
            self._seen("sleep")
            raise

    @actor
    def in_child_call(self):
        try:
            self.run_actor("in_sleep")
        except Cancelled:
            self._seen("child_call")
            raise

    @actor("slow_async", "async", hub_only=True)  # completes on a runtime timer
    def slow_async(self, done):
        timer = self.runtime.call_later(100, done, "late")

        def close():
            timer.cancel()
            self.get_value("closed").append("slow_async")

        return close

    @actor
    def in_async_wait(self):
        try:
            self.run_actor("slow_async")
        except Cancelled:
            self._seen("async_wait")
            raise

    @actor("quiet_stream", "multi", hub_only=True)
    def quiet_stream(self, emit):
        return lambda: self.get_value("closed").append("quiet_stream")

    @actor
    def in_iterator_next(self):
        try:
            with self.run_actor_mode("quiet_stream", "iterator") as it:
                next(it)
        except Cancelled:
            self._seen("iterator_next")
            raise

    @actor
    def in_signal_wait(self):
        try:
            self.signal.wait(100)
        except Cancelled:
            self._seen("signal")
            raise

    @actor
    def in_offload(self):
        try:
            self.runtime.offload(self.release.wait, 5.0)
        except Cancelled:
            self._seen("offload")
            raise

    @actor
    def catches_exception(self):
        try:
            self.run_actor("sleep", 100)
        except Exception:  # must not swallow Cancelled
            self._seen("swallowed")
        return "finished"


PRIMITIVES = {
    "in_sleep": ["sleep"],
    "in_child_call": ["sleep", "child_call"],
    "in_async_wait": ["async_wait"],
    "in_iterator_next": ["iterator_next"],
    "in_signal_wait": ["signal"],
    "in_offload": ["offload"],
}


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_cancel_reaches_the_blocking_point_and_leaks_nothing(name):
    threads_before = set(threading.enumerate())
    rt = Runtime()
    b = rt.add_subsystem("b", Blockers)
    got = []

    def body():
        txn = rt.start(name, on_done=got.append)
        # virtual time stands still while offloaded work runs, so do not wait for it
        rt.sleep(0.0 if name == "in_offload" else 1.0)
        assert txn.state is TxnState.RUNNING
        txn.cancel("test says stop")
        b.release.set()  # the offloaded worker may end; virtual time waits for it
        rt.sleep(0.001)
        return txn

    txn = run_in_actor(rt, body)
    assert b.get_value("seen") == PRIMITIVES[name]
    assert txn.state is TxnState.CANCELLED and txn.reason == "test says stop"
    assert len(got) == 1 and not got[0] and got[0].cancelled
    if name == "in_async_wait":
        assert b.get_value("closed") == ["slow_async"]
    if name == "in_iterator_next":
        assert b.get_value("closed") == ["quiet_stream"]
    assert rt.stats() == {"transactions": 0, "tasks": 0}
    rt.close()
    assert started_since(threads_before) == []


def test_except_exception_does_not_swallow_cancelled(rt):
    b = rt.add_subsystem("b", Blockers)

    def body():
        txn = rt.start("catches_exception")
        rt.sleep(1)
        txn.cancel()
        rt.sleep(1)
        return txn

    txn = run_in_actor(rt, body)
    assert txn.state is TxnState.CANCELLED
    assert b.get_value("seen") == []


def test_cancelling_a_parent_cancels_children_first(rt):
    order = []

    class Tree(SubSystem):
        @actor
        def parent(self):
            self.run_actor_mode("child", "async", None, "a")
            self.run_actor_mode("child", "async", None, "b")
            try:
                self.run_actor("sleep", 100)
            except Cancelled:
                order.append("parent")
                raise

        @actor
        def child(self, tag):
            try:
                self.run_actor("sleep", 100)
            except Cancelled:
                order.append(f"child {tag}")
                raise

    rt.add_subsystem("t", Tree)

    def body():
        txn = rt.start("parent")
        rt.sleep(1)
        assert len(txn.children) == 3  # two async children and its own sleep
        txn.cancel("stop all")
        rt.sleep(1)

    run_in_actor(rt, body)
    assert order == ["child a", "child b", "parent"]
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_cancelled_child_gives_caller_actor_cancelled(rt):
    class S(SubSystem):
        @actor
        def waiter(self):
            try:
                self.run_actor("sleep", 10)
            except ActorCancelled as e:
                return f"child cancelled: {e.reason}"

    rt.add_subsystem("s", S)

    def body():
        txn = rt.start("waiter")
        rt.sleep(1)
        [child] = txn.children.values()
        child.cancel("only the child")
        rt.sleep(1)
        return txn.result

    assert run_in_actor(rt, body) == "child cancelled: only the child"


def test_a_finished_parent_cancels_leftover_children(rt):
    class S(SubSystem):
        @actor
        def leaves_work_behind(self):
            self.run_actor_mode("sleep", "async", None, 100)
            return "done"

    rt.add_subsystem("s", S)
    assert rt.call("leaves_work_behind") == "done"
    rt.call("sleep", 1)
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_ten_thousand_concurrent_transactions(rt):
    def body():
        txns = [rt.start("sleep", 1.0) for _ in range(10_000)]
        rt.sleep(0.5)
        live = len(rt.transactions())
        rt.sleep(1.0)
        return live, all(t.state is TxnState.DONE for t in txns)

    live, all_done = run_in_actor(rt, body)
    assert live >= 10_000 and all_done
    assert rt.stats() == {"transactions": 0, "tasks": 0}


def test_close_cancels_live_work_and_joins_threads():
    before = set(threading.enumerate())
    rt = Runtime()
    rt.start("sleep", 1000)
    rt.close()
    assert rt.stats()["transactions"] == 0
    assert started_since(before) == []
