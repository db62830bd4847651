"""A level-triggered flag that actors can wait on (used by the tree tick loop)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .hub import Waiter

if TYPE_CHECKING:
    from .runtime import Runtime


class Signal:
    """``set()`` from any hub code; ``wait(timeout)`` blocks the calling actor until set.

    ``wait`` returns True when the signal was set and False on timeout [s, runtime
    clock]. The flag stays set until ``clear()``.
    """

    __slots__ = ("_rt", "_set", "_waiters")

    def __init__(self, rt: Runtime) -> None:
        """``rt``: the Runtime (its hub and clock)."""
        self._rt = rt
        self._set = False
        self._waiters: list[Waiter] = []

    def is_set(self) -> bool:
        return self._set

    def set(self) -> None:
        hub = self._rt.hub
        if not hub.in_hub_thread():
            hub.call_soon_threadsafe(self.set)
            return
        self._set = True
        waiters, self._waiters = self._waiters, []
        for w in waiters:
            w.wake(True)

    def clear(self) -> None:
        self._set = False

    def wait(self, timeout: float | None = None) -> bool:
        if self._set:
            return True
        hub = self._rt.hub
        task = hub.require_task("Signal.wait")
        w = Waiter(task)
        self._waiters.append(w)
        timer = None
        if timeout is not None:
            timer = hub.call_at(self._rt.clock.now() + timeout, w.wake, False)
        try:
            return bool(w.wait())
        finally:
            if timer is not None:
                timer.cancel()
            if w in self._waiters:
                self._waiters.remove(w)
