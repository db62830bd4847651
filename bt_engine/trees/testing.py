"""Test doubles for the tree layer: a resolver over plain functions, and scripted actors.

Kept in one place (like py_trees_ros' ``mock/``) so tests and the bad-mission corpus
share one fake catalogue.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any, Callable

from ..actor import actor
from ..clock import Clock
from ..errors import Cancelled, UnknownActorError
from ..subsystem import SubSystem

__all__ = [
    "DEMO_BEHAVIOURS",
    "FakeActor",
    "FakeResolver",
    "ManualClock",
    "ScriptedActors",
    "demo_resolver",
]

#: Behaviour names the bad-mission corpus is checked against.
DEMO_BEHAVIOURS: tuple[str, ...] = ("Blinker",)


@dataclass(frozen=True)
class FakeActor:
    """The resolver's view of one actor (same attributes as the runtime's ActorRef)."""

    path: str
    signature: inspect.Signature
    is_tree: bool = False
    doc: str | None = None
    kind: str = "sync"
    fn: Callable[..., Any] | None = None


class FakeResolver:
    """``name -> FakeActor`` over plain functions; unknown names raise
    :class:`~bt_engine.errors.UnknownActorError` with close matches, as ``rt.root.resolve`` does.

    Example::

        def navigate(target: str, speed: float = 0.5) -> bool: ...
        resolve = FakeResolver(navigate=navigate)
        resolve("navigate").signature      # (target: str, speed: float = 0.5) -> bool
    """

    def __init__(self, **functions: Callable[..., Any]) -> None:
        self.actors = {
            name: FakeActor(name, inspect.signature(fn), doc=inspect.getdoc(fn), fn=fn)
            for name, fn in functions.items()
        }

    def __call__(self, name: str) -> FakeActor:
        try:
            return self.actors[name]
        except KeyError:
            raise UnknownActorError(name, self.actors) from None

    def __contains__(self, name: object) -> bool:
        return name in self.actors


def demo_resolver() -> FakeResolver:
    """The fake catalogue ``tests/bad_missions/`` is checked against (see its README)."""

    def sleep(seconds: float) -> None:
        """Pass time on the runtime clock."""

    def navigate(target: str, speed: float = 0.5) -> bool:
        """Drive the base to a named place."""
        return True

    def watch() -> dict:
        """Look for an object; returns {category, pose}."""
        return {}

    def open_gripper() -> None:
        """Open the gripper."""

    def pick(target: dict, category: str = "can") -> dict:
        """Pick the target; returns the grasp."""
        return {}

    def count_objects(room: str) -> int:
        """How many objects are visible in a room."""
        return 0

    def say(text: str) -> None:
        """Log a line."""

    return FakeResolver(
        sleep=sleep,
        navigate=navigate,
        watch=watch,
        open_gripper=open_gripper,
        pick=pick,
        count_objects=count_objects,
        say=say,
    )


class ScriptedActors(SubSystem):
    """Actors a test drives by hand, for tick-by-tick tables.

    * ``act(tag)`` (async) runs until the test calls :meth:`finish` or :meth:`fail`;
      a cancel is recorded in ``cancelled``.
    * ``block(tag, seconds)`` (sync) sleeps on the runtime clock; a ``Cancelled`` that
      reaches its blocking point is recorded in ``cancelled``.
    * ``echo(value)`` (sync) returns its argument at once.
    * ``flaky(tag, failures)`` (sync) returns False ``failures`` times, then True.

    ``started`` lists the tags in the order the actors were started. :meth:`finish` and
    :meth:`fail` must run on the hub (``rt.run_on_hub``).
    """

    def __init__(self) -> None:
        super().__init__()
        self.pending: dict[str, Any] = {}
        self.started: list[str] = []
        self.cancelled: list[str] = []

    @actor("act", "async")
    def act(self, done: Any, tag: str) -> Callable[[], None]:
        """Run until the test finishes it."""
        self.started.append(tag)
        self.pending[tag] = done

        def close() -> None:
            self.cancelled.append(tag)
            self.pending.pop(tag, None)

        return close

    @actor
    def block(self, tag: str, seconds: float = 1000.0) -> str:
        """Sleep ``seconds`` [s]; record a cancellation."""
        self.started.append(tag)
        try:
            self.runtime.sleep(seconds)
        except Cancelled:
            self.cancelled.append(tag)
            raise
        return tag

    @actor
    def echo(self, value: Any = None) -> Any:
        """Return ``value``."""
        return value

    @actor
    def flaky(self, tag: str, failures: int = 1) -> bool:
        """Return False the first ``failures`` times for ``tag``, then True."""
        self.started.append(tag)
        return self.started.count(tag) > failures

    def finish(self, tag: str, result: Any = True) -> None:
        """Complete ``act(tag)`` with ``result`` (hub thread)."""
        self.pending.pop(tag)(result)

    def fail(self, tag: str, error: BaseException | None = None) -> None:
        """Fail ``act(tag)`` with ``error`` (hub thread)."""
        self.pending.pop(tag).fail(error or RuntimeError(f"{tag} failed"))


class ManualClock(Clock):
    """A clock that moves only when the test advances it.

    Under the virtual clock, time jumps whenever the hub has nothing to do, which is
    also while a test thinks between two ticks. Tick tables with deadlines use this
    clock instead: ``clock.advance(rt, 4.9)``.
    """

    virtual = False  # the hub sleeps until the next timer instead of jumping

    def __init__(self) -> None:
        self._now = 0.0

    def now(self) -> float:
        return self._now

    def advance(self, rt: Any, seconds: float) -> None:
        """Move time forward by ``seconds`` [s] and let due timers fire."""
        self._now += seconds
        rt.run_on_hub(lambda: None)  # wake the hub so it looks at its timers
