"""The first examples of actors, one of each kind, as a SubSystem: a starting point for new actors."""

from __future__ import annotations

from typing import Iterator

from bt_engine import SubSystem, actor


class Tutorial(SubSystem):
    """Small actors that show each kind; used by the demo tree and the shell."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("greeting", "hello")

    @actor(read_only=True)
    def sample_actor(self, mes: str) -> str:
        """Print ``mes`` and return it (the simplest actor there is).

        Args:
            mes: the text to print
        """
        print(mes)
        return mes

    @actor(read_only=True)
    def greet(self, name: str = "world") -> str:
        """Return a greeting, using the subsystem's persistent ``greeting`` value.

        Args:
            name: who to greet
        """
        return f"{self.get_value('greeting')}, {name}"

    @actor("countdown", "multi", hub_only=True, read_only=True)
    def countdown(self, emit, start: int = 3, period: float = 1.0):
        """Emit start, start-1, ..., 1 every ``period`` [s], then end (an emit-style stream).

        ``hub_only``: it emits from a runtime timer, never from another thread, so the
        virtual clock may jump while it runs.

        Args:
            start: the first value, counted down to 1
            period: time between values [s]
        """
        state = {"n": start}

        def tick() -> None:
            emit(state["n"])
            state["n"] -= 1
            if state["n"] <= 0:
                timer.cancel()
                emit.end()

        timer = self.runtime.call_every(period, tick)
        return timer.cancel

    @actor(read_only=True)
    def count(self, n: int = 3, period: float = 1.0) -> Iterator[int]:
        """Yield 0..n-1, sleeping ``period`` [s] on the runtime clock between values
        (a generator stream).

        Args:
            n: how many values
            period: time between values [s]
        """
        for i in range(n):
            yield i
            self.run_actor("sleep", period)
