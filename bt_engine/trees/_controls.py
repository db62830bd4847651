"""Control nodes beyond py_trees' own, for trees written for BehaviorTree.CPP and Nav2.

Each is a py_trees composite or decorator with the semantics of its BehaviorTree.CPP /
Nav2 namesake (see docs/missions.md): ``resume_sequence`` (SequenceWithMemory),
``pipeline_sequence``, ``if_then_else``, ``while_do_else``, ``recovery``
(RecoveryNode), a ``parallel`` that counts successes and failures, ``rate_controller``
and ``run_once``. Like the rest of the tree layer they never block and never read the
wall clock: time comes from the runtime clock, and a node that waits asks for a tick
at its deadline (``ctx.wake`` through ``rt.call_later``).
"""

from __future__ import annotations

from typing import Any, Generator, Iterator

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from ._behaviours import RunContext, _number
from ._model import RunOnceThen

__all__ = [
    "CountingParallel",
    "IfThenElseNode",
    "PipelineSequenceNode",
    "RateControllerNode",
    "RecoveryNode",
    "ResumeSequenceNode",
    "RunOnceNode",
    "WhileDoElseNode",
]


#: a control's logic: yields what its children yield, returns its status
Step = Generator[Behaviour, None, Status]


def _tick(child: Behaviour) -> Step:
    """Tick one child (yielding what it yields); the generator returns its status."""
    yield from child.tick()
    return child.status


def _halt(child: Behaviour) -> None:
    if child.status is not Status.INVALID:
        child.stop(Status.INVALID)


def _param(value: Any, ctx: RunContext, what: str, *, integer: bool, minimum: float) -> tuple[Any, str | None]:
    """A literal-or-reference parameter, read now; (value, None) or (None, error)."""
    return _number(value, ctx, what, integer, minimum=minimum)


class _Control(py_trees.composites.Composite):
    """A composite whose logic is one generator, :meth:`step`, returning the status.

    ``start`` runs when the node is ticked while not RUNNING (a fresh start).
    """

    def tick(self) -> Iterator[Behaviour]:
        if self.status is not Status.RUNNING:
            self.start()
        status = yield from self.step()
        if status is Status.RUNNING:
            self.status = status
        else:
            self.stop(status)
        yield self

    def start(self) -> None:
        for child in self.children:
            _halt(child)

    def step(self) -> Step:  # pragma: no cover - abstract
        raise NotImplementedError
        yield

    def halt_children(self) -> None:
        """Halt the running children; finished ones keep their status, so that a failure
        can still be traced to the child that failed."""
        for child in self.children:
            if child.status is Status.RUNNING:
                child.stop(Status.INVALID)


class ResumeSequenceNode(_Control):
    """``resume_sequence``: after a failure the next start resumes at the failed child
    (BehaviorTree.CPP's SequenceWithMemory); after a success it starts over."""

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name, children)
        self.index = 0

    def start(self) -> None:
        for child in self.children[self.index :]:
            _halt(child)

    def step(self) -> Step:
        while self.index < len(self.children):
            child = self.children[self.index]
            self.current_child = child
            status = yield from _tick(child)
            if status is not Status.SUCCESS:
                return status  # RUNNING, or FAILURE with the index kept
            self.index += 1
        self.index = 0
        return Status.SUCCESS


class PipelineSequenceNode(_Control):
    """``pipeline_sequence`` (Nav2): every tick, tick the children from the first up to
    the furthest reached; earlier ones keep running (or restart) alongside it."""

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name, children)
        self.furthest = 0

    def start(self) -> None:
        super().start()
        self.furthest = 0

    def step(self) -> Step:
        for i, child in enumerate(self.children):
            self.current_child = child
            status = yield from _tick(child)
            if status is Status.FAILURE:
                self.halt_children()
                return Status.FAILURE
            if status is Status.RUNNING and i >= self.furthest:
                self.furthest = i
                return Status.RUNNING
        self.halt_children()
        return Status.SUCCESS


class IfThenElseNode(_Control):
    """``if_then_else``: the first child chooses, once, the second (success) or the
    third (failure; without one, the node fails)."""

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name, children)
        self.branch = 0  # 0: the condition is still deciding

    def start(self) -> None:
        super().start()
        self.branch = 0

    def step(self) -> Step:
        if self.branch == 0:
            self.current_child = self.children[0]
            status = yield from _tick(self.children[0])
            if status is Status.RUNNING:
                return status
            if status is Status.SUCCESS:
                self.branch = 1
            elif len(self.children) == 3:
                self.branch = 2
            else:
                return Status.FAILURE
        self.current_child = self.children[self.branch]
        return (yield from _tick(self.children[self.branch]))


class WhileDoElseNode(_Control):
    """``while_do_else``: the first child is ticked every tick; its success runs the
    second child, its failure the third (or fails); switching halts the other branch."""

    def step(self) -> Step:
        condition = self.children[0]
        self.current_child = condition
        status = yield from _tick(condition)
        if status is Status.RUNNING:
            return status
        if status is Status.SUCCESS:
            branch, other = 1, 2
        elif len(self.children) == 3:
            branch, other = 2, 1
        else:
            _halt(self.children[1])
            return Status.FAILURE
        if other < len(self.children):
            _halt(self.children[other])
        self.current_child = self.children[branch]
        return (yield from _tick(self.children[branch]))


class RecoveryNode(_Control):
    """``recovery`` (Nav2's RecoveryNode): the action; when it fails, the recovery,
    then the action again, ``retries`` times at most."""

    def __init__(self, name: str, ctx: RunContext, children: list[Behaviour], retries: Any) -> None:
        super().__init__(name, children)
        self.ctx = ctx
        self.retries = retries
        self.limit = 0
        self.done = 0
        self.current = 0
        self.error: str | None = None

    def start(self) -> None:
        super().start()
        self.done = 0
        self.current = 0
        self.limit, self.error = _param(self.retries, self.ctx, "recovery retries", integer=True, minimum=0)

    def step(self) -> Step:
        if self.error is not None:
            self.feedback_message = self.error
            return Status.FAILURE
        while True:
            child = self.children[self.current]
            self.current_child = child
            status = yield from _tick(child)
            if status is Status.RUNNING:
                return status
            if self.current == 0:
                if status is Status.SUCCESS:
                    self.feedback_message = f"succeeded after {self.done} recover{'y' if self.done == 1 else 'ies'}"
                    return status
                if self.done >= self.limit:
                    self.feedback_message = f"failed, {self.done} of {self.limit} recoveries used"
                    return status
                self.current = 1
            else:
                if status is Status.FAILURE:
                    self.feedback_message = "the recovery failed"
                    return status
                self.done += 1
                self.current = 0


class CountingParallel(_Control):
    """``parallel`` with ``success_count``/``failure_count`` (BehaviorTree.CPP's
    Parallel): ticks the children that have not finished; succeeds once
    ``success_count`` have succeeded, fails once ``failure_count`` have failed (or once
    success can no longer be reached), halting the others. A negative count is counted
    from the number of children: -1 means all."""

    def __init__(self, name: str, children: list[Behaviour], success_count: int, failure_count: int) -> None:
        super().__init__(name, children)
        n = len(children)
        self.success_needed = success_count if success_count > 0 else n + 1 + success_count
        self.failure_needed = failure_count if failure_count > 0 else n + 1 + failure_count
        self.finished: dict[Behaviour, Status] = {}

    def start(self) -> None:
        super().start()
        self.finished = {}

    def step(self) -> Step:
        n = len(self.children)
        for child in self.children:
            if child in self.finished:
                continue
            status = yield from _tick(child)
            if status is not Status.RUNNING:
                self.finished[child] = status
        successes = sum(1 for s in self.finished.values() if s is Status.SUCCESS)
        failures = len(self.finished) - successes
        self.feedback_message = f"{successes} succeeded, {failures} failed of {n}"
        if successes >= self.success_needed:
            self.halt_children()
            return Status.SUCCESS
        if failures >= self.failure_needed or n - failures < self.success_needed:
            self.halt_children()
            return Status.FAILURE
        return Status.RUNNING


class RateControllerNode(py_trees.decorators.Decorator):
    """``rate_controller`` (Nav2): tick the child at most ``hz`` times a second. After the
    child succeeds (the node succeeds), a tick before the period has passed answers
    RUNNING without ticking it and asks for a tick when the period is over."""

    def __init__(self, name: str, ctx: RunContext, child: Behaviour, hz: Any) -> None:
        super().__init__(name=name, child=child)
        self.ctx = ctx
        self.hz = hz
        self.period = 1.0  # [s]
        self.since = 0.0  # runtime-clock time the current period started [s]
        self.fresh = True  # the child is ticked whatever the time
        self.timer: Any = None
        self.error: str | None = None

    def tick(self) -> Iterator[Behaviour]:
        now = self.ctx.rt.now()
        if self.status not in (Status.RUNNING, Status.SUCCESS):  # started anew, not re-ticked after a success
            hz, self.error = _param(self.hz, self.ctx, "rate_controller hz", integer=False, minimum=0)
            if self.error is None and hz == 0:
                self.error = "rate_controller hz is 0, expected a number > 0"
            if self.error is not None:
                self.feedback_message = self.error
                self.stop(Status.FAILURE)
                yield self
                return
            self.period = 1.0 / hz
            self.since = now
            self.fresh = True
        self._cancel_timer()
        if self.fresh or self.decorated.status is Status.RUNNING or now - self.since >= self.period:
            self.fresh = False
            status = yield from _tick(self.decorated)
            if status is Status.RUNNING:
                self.status = status
            else:
                self.stop(status)
            if status is Status.SUCCESS:
                # A parent that ticks it again (a pipeline) should find the period over
                # even if nothing else happens meanwhile.
                self.since = now
                self.timer = self.ctx.rt.call_later(self.period, self.ctx.wake)
            yield self
            return
        wait = self.period - (now - self.since)
        self.feedback_message = f"next tick of the child in {wait:.3g} s"
        self.timer = self.ctx.rt.call_later(wait, self.ctx.wake)
        self.status = Status.RUNNING
        yield self

    def update(self) -> Status:  # unused: tick() decides
        return self.decorated.status

    def _cancel_timer(self) -> None:
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.INVALID:
            self._cancel_timer()


class RunOnceNode(py_trees.decorators.Decorator):
    """``run_once``: tick the child until it finishes, once per run; later ticks return
    ``then`` (the child's own status by default) without ticking it."""

    def __init__(self, name: str, child: Behaviour, then: RunOnceThen) -> None:
        super().__init__(name=name, child=child)
        self.then = then
        self.result: Status | None = None

    def tick(self) -> Iterator[Behaviour]:
        if self.result is not None:
            status = (
                self.result
                if self.then is RunOnceThen.SAME
                else (Status.SUCCESS if self.then is RunOnceThen.SUCCESS else Status.FAILURE)
            )
            self.feedback_message = "ran once already"
            self.stop(status)
            yield self
            return
        status = yield from _tick(self.decorated)
        if status is Status.RUNNING:
            self.status = status
        else:
            self.result = status
            self.stop(status)
        yield self

    def update(self) -> Status:  # unused: tick() decides
        return self.decorated.status
