"""Faults a real robot has, injected on the robot side (``actorbt robot --fault ...``).

    scan-drop=0.1       lose 10 % of the /scan messages
    scan-delay=0.1      deliver /scan 0.1 s late (stamps unchanged, as a loaded link)
    camera-drop=0.1     lose 10 % of each camera topic's messages (colour, depth, info
                        independently, so pairs break as they do over Wi-Fi)
    camera-delay=0.1    deliver the camera's messages 0.1 s late
    arm-abort=2         the arm controller aborts the 2nd arm goal half way
                        (PATH_TOLERANCE_VIOLATED, as when the arm is blocked); a list
                        ``arm-abort=2,5`` aborts several
    restart=60          at 60 s the robot's drivers and the navstack go down and come back
                        ``restart-for`` (default 3) s later with no state: topics vanish,
                        goals abort, the localiser starts again (the physical world stays)

Losses are drawn from the world seed's own stream, so a fault run can be repeated.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

from bt_engine.errors import ActorbtError


class FaultError(ActorbtError, ValueError):
    """A --fault that does not parse."""


@dataclass
class Faults:
    """What to break, and when (seconds on the runtime clock from the start)."""

    scan_drop: float = 0.0
    scan_delay: float = 0.0
    camera_drop: float = 0.0
    camera_delay: float = 0.0
    arm_abort: set = field(default_factory=set)
    restart: float | None = None
    restart_for: float = 3.0

    def any(self) -> bool:
        return bool(
            self.scan_drop
            or self.scan_delay
            or self.camera_drop
            or self.camera_delay
            or self.arm_abort
            or self.restart is not None
        )

    def describe(self) -> str:
        parts = [
            f"{name.replace('_', '-')}={value}"
            for name, value in vars(self).items()
            if value not in (0.0, None, set()) and name != "restart_for"
        ]
        if self.restart is not None:
            parts.append(f"restart-for={self.restart_for}")
        return ", ".join(parts) or "none"


_NUMBERS = {
    "scan-drop": (0.0, 1.0),
    "camera-drop": (0.0, 1.0),
    "scan-delay": (0.0, 10.0),
    "camera-delay": (0.0, 10.0),
    "restart": (0.0, 1e9),
    "restart-for": (0.0, 600.0),
}


def parse_faults(items: list[str] | None) -> Faults:
    """``["scan-drop=0.1", "arm-abort=2"]`` -> :class:`Faults`; a clear error otherwise."""
    faults = Faults()
    for item in items or ():
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep:
            raise FaultError(f"--fault {item!r}: expected NAME=VALUE, e.g. scan-drop=0.1")
        if name == "arm-abort":
            try:
                faults.arm_abort |= {int(v) for v in value.split(",")}
            except ValueError:
                raise FaultError(f"--fault {item!r}: expected goal numbers, e.g. arm-abort=2 or 2,5") from None
            if min(faults.arm_abort) < 1:
                raise FaultError(f"--fault {item!r}: goals are numbered from 1")
            continue
        if name not in _NUMBERS:
            known = ", ".join(sorted([*_NUMBERS, "arm-abort"]))
            raise FaultError(f"--fault {item!r}: unknown fault {name!r} (known: {known})")
        try:
            number = float(value)
        except ValueError:
            raise FaultError(f"--fault {item!r}: {value!r} is not a number") from None
        low, high = _NUMBERS[name]
        if not low <= number <= high:
            raise FaultError(f"--fault {item!r}: expected {low:g} .. {high:g}")
        setattr(faults, name.replace("-", "_"), number)
    return faults


class FaultyPublisher:
    """A publisher that loses a share of the messages and delivers the rest late, on the
    runtime's timers (so the order of what is delivered is kept)."""

    def __init__(self, publisher, runtime, drop: float, delay: float, rng: random.Random):
        self.topic = getattr(publisher, "topic", "")
        self._pub, self._rt = publisher, runtime
        self._drop, self._delay, self._rng = drop, delay, rng
        self.dropped = self.sent = 0

    def close(self) -> None:
        close = getattr(self._pub, "close", None)
        if close is not None:
            close()

    def publish(self, msg) -> None:
        if self._drop and self._rng.random() < self._drop:
            self.dropped += 1
            return
        self.sent += 1
        if self._delay > 0:
            self._rt.call_later(self._delay, self._pub.publish, msg)
        else:
            self._pub.publish(msg)


def faulty(publisher, runtime, drop: float, delay: float, rng: random.Random):
    """``publisher`` itself when there is nothing to break, else a :class:`FaultyPublisher`."""
    if not drop and not delay:
        return publisher
    return FaultyPublisher(publisher, runtime, drop, delay, rng)
