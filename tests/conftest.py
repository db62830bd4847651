"""Shared fixtures: a virtual-clock runtime per test, and a way to run code as an actor."""
from __future__ import annotations

import itertools
import os
import threading
from typing import Any, Callable

import pytest

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

from bt_engine import Runtime  # noqa: E402

_probe_ids = itertools.count()


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
