"""Nothing outlives its owner: random halts of running trees, and runtimes made and
closed again and again, leave no transactions, tasks (greenlets), threads, file
descriptors, blackboard entries or memory behind."""

from __future__ import annotations

import gc
import os
import random
import textwrap
import threading
import time
import weakref
from pathlib import Path

import py_trees

from bt_engine import Runtime, SubSystem, actor
from bt_engine.trees import register_tree_folder, tree_host
from tests.conftest import started_since

BUSY_TREES = {
    "busy": """
        name: busy
        inputs: {seconds: {type: float, default: 0.3}}
        root:
          parallel:
            policy: success_on_all
            children:
              - sequence:
                  - {do: work, with: {seconds: "{seconds}"}}
                  - retry: {times: 3, child: {do: pulse}}
                  - {do: offloaded}
              - timeout: {seconds: 2, child: {do: first_tick}}
              - repeat: {times: 3, child: {do: inner}}
              - {wait: 0.2}
        """,
    "inner": """
        name: inner
        root:
          sequence:
            - {do: gen_first}
            - {do: sleep, with: {seconds: 0.05}}
        """,
}


class Workers(SubSystem):
    """Actors of every kind, all completing on the hub (plus one offload)."""

    @actor
    def work(self, seconds: float) -> str:
        self.run_actor("sleep", seconds)
        return "worked"

    @actor("pulse", "async", hub_only=True)
    def pulse(self, done):
        return self.runtime.call_later(0.05, done, 1).cancel

    @actor("ticks", "multi", hub_only=True)
    def ticks(self, emit):
        return self.runtime.call_every(0.02, emit, 1).cancel

    @actor
    def first_tick(self) -> int:
        with self.run_actor_mode("ticks", "iterator") as it:
            return next(it)

    @actor
    def gen(self):
        while True:
            self.run_actor("sleep", 0.01)
            yield 1

    @actor
    def gen_first(self) -> int:
        return self.run_actor("gen")

    @actor
    def offloaded(self) -> float:
        return self.runtime.offload(time.sleep, 0.0005) or 0.0


#: what the halter starts: actor, arguments, how long it runs [s] when left alone
CALLS = [
    ("busy", {"seconds": 0.5}, 0.5),
    ("inner", {}, 0.06),
    ("work", {"seconds": 0.3}, 0.3),
    ("first_tick", {}, 0.02),
]


def write_trees(folder: Path) -> Path:
    for name, body in BUSY_TREES.items():
        (folder / f"{name}.yaml").write_text(textwrap.dedent(body))
    return folder


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def actorbt_blackboard_keys() -> set[str]:
    """py_trees' blackboard is one per process: with several test files in one worker,
    what earlier files' trees left there is not this test's to judge."""
    return {k for k in py_trees.blackboard.Blackboard.storage if k.startswith("/actorbt/")}


def test_a_thousand_random_halts_leave_nothing_behind(tmp_path):
    folder = write_trees(tmp_path)
    threads_before = set(threading.enumerate())
    fds_before = open_fds()
    keys_before = actorbt_blackboard_keys()
    rng = random.Random(7)
    with Runtime() as rt:
        rt.add_subsystem("w", Workers)
        host = register_tree_folder(rt, folder)
        assert rt.call("busy") == {}  # runs to the end when left alone

        class Halter(SubSystem):
            @actor
            def halt_many(self, n: int) -> int:
                halted = 0
                for _ in range(n):
                    name, kwargs, lasts = rng.choice(CALLS)
                    txn = self.start(name, **kwargs)
                    self.run_actor("sleep", rng.uniform(0.0, lasts))
                    halted += not txn.done
                    txn.cancel("random halt")
                    self.run_actor("sleep", 0)  # let the halt unwind
                return halted

        rt.add_subsystem("h", Halter)
        halted = rt.call("halt_many", 1000)
        assert halted > 900  # nearly all were halted while running
        deadline = time.monotonic() + 5
        while rt.stats() != {"transactions": 0, "tasks": 0} and time.monotonic() < deadline:
            time.sleep(0.005)
        assert rt.stats() == {"transactions": 0, "tasks": 0}
        assert host.live_runs() == []
        assert actorbt_blackboard_keys() - keys_before == set()
        assert rt.hub.foreign_pending == 0 and rt.hub.outside_pending == 0
    assert started_since(threads_before) == []
    assert open_fds() == fds_before


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_two_hundred_runtimes_with_trees_are_freed(tmp_path):
    folder = write_trees(tmp_path)
    refs: list[weakref.ref] = []

    def cycle() -> None:
        rt = Runtime()
        rt.add_subsystem("w", Workers)
        register_tree_folder(rt, folder)
        assert rt.call("inner") == {}
        assert tree_host(rt) is not None
        rt.close()
        refs.append(weakref.ref(rt))

    for _ in range(20):  # warm up: imports, caches, first allocations
        cycle()
    gc.collect()
    before = rss_bytes()
    for _ in range(200):
        cycle()
    gc.collect()
    grown = rss_bytes() - before
    assert sum(r() is not None for r in refs) == 0, "closed runtimes are still referenced"
    assert grown <= 5 * 2**20, f"RSS grew {grown / 2**20:.1f} MB over 200 runtimes"
