"""Shared fixtures: a virtual-clock runtime per test, and a way to run code as an actor.
Before the session, Fast DDS shared-memory segments left by killed processes are removed."""
from __future__ import annotations

import fcntl
import glob
import itertools
import os
import threading
from typing import Any, Callable

import pytest

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

from bt_engine import Runtime  # noqa: E402

_probe_ids = itertools.count()


def remove_stale_dds_segments(shm: str = "/dev/shm") -> list[str]:
    """Delete the Fast DDS segments whose owner is gone: a live participant holds a lock on
    its segment's ``_el`` file. A process killed mid-test leaves its segments behind, and
    the next participants then start an extra watcher thread (which the shutdown tests,
    counting threads, would see). Returns the segments removed."""
    removed = []
    for lock in glob.glob(os.path.join(shm, "fastrtps_*_el")):
        try:
            fd = os.open(lock, os.O_RDWR)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            continue                                  # in use
        else:
            segment = lock[:-len("_el")]
            for path in (segment, lock):
                try:
                    os.unlink(path)
                except OSError:
                    pass
            removed.append(segment)
        finally:
            os.close(fd)
    return removed


def pytest_sessionstart(session) -> None:
    remove_stale_dds_segments()


@pytest.fixture
def rt():
    runtime = Runtime(clock="virtual")
    yield runtime
    runtime.close()


def run_in_actor(rt: Runtime, fn: Callable[[], Any]) -> Any:
    """Run ``fn`` as the body of a temporary sync actor (so it may block on the hub)."""
    name = f"_probe{next(_probe_ids)}"
    rt.run_on_hub(rt.root.add_actor, name, fn)
    return rt.call(name)


def live_threads() -> set[str]:
    return {t.name for t in threading.enumerate()}
