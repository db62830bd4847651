"""Shared fixtures: a virtual-clock runtime per test, and a way to run code as an actor.
Before the session, Fast DDS shared-memory segments left by killed processes are removed."""

from __future__ import annotations

import fcntl
import glob
import hashlib
import itertools
import os
import signal
import threading
from typing import Any, Callable

import pytest

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
# Under pytest-xdist (make test) each worker talks ROS on a domain of its own: the same
# topic and action names in two workers' tests, or in another run's on this machine,
# would otherwise reach each other. A run's workers share its id; domains 100-231.
_WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
if _WORKER.startswith("gw"):
    _run = int(hashlib.sha1(os.environ.get("PYTEST_XDIST_TESTRUNUID", "").encode()).hexdigest(), 16)
    _workers = max(1, int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")))
    os.environ["ROS_DOMAIN_ID"] = str(100 + (_run % max(1, 132 // _workers)) * _workers + int(_WORKER[2:]))
# A suite started in the background by a non-interactive shell inherits SIGINT ignored, and
# so would the commands the Ctrl-C tests start (an ignored signal stays ignored across
# exec): take the default back, so that they see the Ctrl-C they are sent.
signal.signal(signal.SIGINT, signal.default_int_handler)

from bt_engine import Runtime  # noqa: E402

_probe_ids = itertools.count()


def _shm_in_use() -> set[str]:
    """The /dev/shm files some process has mapped or open (from /proc)."""
    used = set()
    for maps in glob.glob("/proc/[0-9]*/maps"):
        try:
            with open(maps) as f:
                used.update(line.split(None, 5)[5].strip() for line in f if "/dev/shm/" in line)
        except (OSError, IndexError):
            continue
    for fd in glob.glob("/proc/[0-9]*/fd/*"):
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("/dev/shm/"):
            used.add(target)
    return used


def remove_stale_dds_segments(shm: str = "/dev/shm") -> list[str]:
    """Delete the Fast DDS segments no live process uses (mapped, open or locked). A
    process killed mid-test leaves its segments behind, and the next participants then
    start an extra watcher thread (which the shutdown tests, counting threads, would
    see). Returns the segments removed."""
    used = _shm_in_use()
    removed = []
    for segment in glob.glob(os.path.join(shm, "fastrtps_*")):
        if segment.endswith("_el") or segment in used or segment + "_el" in used:
            continue
        lock = segment + "_el"
        if os.path.exists(lock):
            try:
                fd = os.open(lock, os.O_RDWR)
            except OSError:
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue  # a live participant holds it
            finally:
                os.close(fd)
        for path in (segment, lock):
            try:
                os.unlink(path)
            except OSError:
                pass
        removed.append(segment)
    return removed


def pytest_sessionstart(session) -> None:
    remove_stale_dds_segments()


# The end-to-end runs of minutes each: the documents' examples and the rehearsal against the
# robot side. Under `--dist loadfile` a file stays in one worker, and the documents' runs
# alone (one file) kept one worker busy for 12 minutes while the other sat idle. So each of
# these is a unit of work of its own, and they start first (longest processing time first);
# `make test` keeps xdist from reordering the units by their number of tests.
LONG_RUNS = ("tests/test_docs_run.py::test_the_documented_examples_run[", "tests/test_rehearsal.py::")


def _long_run(nodeid: str) -> bool:
    return nodeid.startswith(LONG_RUNS)


def pytest_collection_modifyitems(items) -> None:
    items.sort(key=lambda item: not _long_run(item.nodeid))  # stable: the rest keep their order


def pytest_xdist_auto_num_workers(config) -> int:
    # One worker more than the cores: the documents' runs drive the robot on the wall clock
    # and mostly wait (README's: 100 s of CPU in 244 s); a third worker fills that time
    # (the suite on 2 cores: 674 s with two workers, 509 s with three).
    return len(os.sched_getaffinity(0)) + 1


def pytest_xdist_make_scheduler(config, log):
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class LongRunsApart(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return nodeid if _long_run(nodeid) else super()._split_scope(nodeid)

    return LongRunsApart(config, log)


@pytest.fixture
def rt():
    runtime = Runtime(clock="virtual")
    yield runtime
    runtime.close()


def started_since(before: set[threading.Thread]) -> list[str]:
    """The names of the threads alive now that were not in ``before``: what a test left
    running. (A thread of an earlier test that ends meanwhile is not this test's leak, and
    a new thread may reuse a dead one's ident: compare the Thread objects.)"""
    return [t.name for t in threading.enumerate() if t not in before]


def run_in_actor(rt: Runtime, fn: Callable[[], Any]) -> Any:
    """Run ``fn`` as the body of a temporary sync actor (so it may block on the hub)."""
    name = f"_probe{next(_probe_ids)}"
    rt.run_on_hub(rt.root.add_actor, name, fn)
    return rt.call(name)


def live_threads() -> set[str]:
    return {t.name for t in threading.enumerate()}


def place_robot(sim, start: tuple) -> None:
    """Before a runtime's episode starts: put the simulated robot at ``start`` (x, y, yaw),
    its odometry and gyro reset there, and make it the world's start pose (where the episode tells
    the localiser the robot is)."""
    from common.quiet_pybullet import pybullet as p

    def place():
        p.resetBasePositionAndOrientation(
            sim.robot.body,
            [start[0], start[1], 0.0],
            p.getQuaternionFromEuler([0, 0, start[2]]),
            physicsClientId=sim.cid,
        )
        p.resetBaseVelocity(sim.robot.body, [0, 0, 0], [0, 0, 0], physicsClientId=sim.cid)
        js = sim.robot.joint_states()[0]
        sim.odometry.reset(js[0], js[1], start[2])
        sim.gyro.reset()

    sim._on_hub_call(place)
    sim.spec.robot_start = start


@pytest.fixture
def w(tmp_path):
    """A tick-table rig (tests/tick_world.py) on a manual clock."""
    from bt_engine.trees.testing import ManualClock
    from tick_world import World

    clock = ManualClock()
    rt = Runtime(clock=clock)
    yield World(rt, clock, tmp_path)
    rt.close()
