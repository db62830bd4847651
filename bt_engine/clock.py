"""Runtime clocks. Every engine timestamp, sleep and deadline reads one of these."""
from __future__ import annotations

import time


class Clock:
    """Seconds since the runtime started, on either real or virtual time."""

    #: True when time jumps to the next timer instead of passing in real time.
    virtual: bool = False

    def now(self) -> float:  # pragma: no cover - interface
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

    A three-minute mission thus runs as fast as the CPU allows, and a run is
    deterministic because nothing depends on real time.
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
    from .errors import BadModeError
    raise BadModeError(f"unknown clock {spec!r}; expected 'virtual' or 'wall'")
