"""Runtime clocks. Every engine timestamp, sleep and deadline reads one of these."""

from __future__ import annotations

import os
import time

from .errors import BadModeError

#: this module's import time: the start of the process where /proc cannot tell
_IMPORTED = time.monotonic()


class Clock:
    """Seconds since the runtime started, on either real or virtual time."""

    #: True when time jumps to the next timer instead of passing in real time.
    virtual: bool = False

    def now(self) -> float:  # pragma: no cover - interface
        raise NotImplementedError

    def advance_to(self, t: float) -> None:  # pragma: no cover - interface
        """Move time forward to ``t`` [s]: what the hub does to a ``virtual`` clock."""
        raise NotImplementedError


class WallClock(Clock):
    """Real time (monotonic), starting at 0 when created."""

    virtual = False

    def __init__(self) -> None:
        self._t0 = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._t0


class VirtualClock(Clock):
    """Simulated time: the hub advances it to the next timer when every task waits.

    A three-minute mission thus runs as fast as the CPU allows, and a run of work that
    lives on the hub is deterministic because nothing depends on real time.

    **The rule** (the one place it is stated; the hub implements it):

    1. Time moves only while some transaction is live, nothing is ready to run and
       nothing posted from another thread is waiting: then it jumps to the next timer.
    2. While work started by an actor may still complete from another thread (an
       async or stream implementation not declared ``hub_only``, such as a driver
       thread, a ROS callback or a ``threading.Timer`` calling ``done``), time
       advances no faster than wall time, measured from when the latest such work
       started. So a deadline of D seconds never passes before that work has had D
       seconds of real time to complete.
    3. While an offload runs, or an outside thread consumes an iterator item, time
       stands still.
    """

    virtual = True

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)

    def now(self) -> float:
        return self._now

    def advance_to(self, t: float) -> None:
        """Move time forward to ``t`` [s] (never backwards). Only the hub calls this."""
        if t > self._now:
            self._now = t


def make_clock(spec: "str | Clock | None") -> Clock:
    """A clock from ``"virtual"``, ``"wall"``, a Clock, or None (virtual)."""
    if isinstance(spec, Clock):
        return spec
    if spec in (None, "virtual"):
        return VirtualClock()
    if spec == "wall":
        return WallClock()
    raise BadModeError(f"unknown clock {spec!r}; expected 'virtual' or 'wall'")


def process_uptime() -> float:
    """Seconds of wall time since this process started (from /proc on Linux; else since
    this module was imported): how long a command took to be ready."""
    try:
        with open("/proc/self/stat") as f:
            fields = f.read().rpartition(")")[2].split()
        with open("/proc/uptime") as f:
            up = float(f.read().split()[0])
        return max(0.0, up - int(fields[19]) / os.sysconf("SC_CLK_TCK"))
    except (OSError, ValueError, IndexError, AttributeError):
        return time.monotonic() - _IMPORTED
