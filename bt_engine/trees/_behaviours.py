"""The py_trees behaviours missions are made of.

Following py_trees' lifecycle (``demos/action.py``): a leaf does no work itself. The
actor leaf *starts* its actor in ``initialise``, *polls* the transaction in ``update``
and *cancels* it in ``terminate`` when halted. Time-based nodes read the runtime clock
and schedule a wake-up at their deadline, so the tick loop needs no polling.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator, Protocol

import py_trees
from py_trees.common import Status

from ..errors import ActorbtError
from ..signal import Signal
from ..transaction import TxnState
from ._errors import CheckEvaluationError, out_of_range
from ._expr import evaluate
from ._model import Check, Do, Ref, SetValues, refs_in, resolve_value
from ._blackboard import RunBlackboard

__all__ = [
    "ActorLeaf",
    "CallSite",
    "CheckLeaf",
    "ConditionLeaf",
    "RepeatNode",
    "RetryNode",
    "RunContext",
    "SetLeaf",
    "TimeoutNode",
    "WaitLeaf",
]


class CallSite(Protocol):
    """Who calls an actor, as traces and replay name it: an actor leaf, or a plugin
    node's call (``_plugin_nodes``)."""

    @property
    def path(self) -> str: ...

    @property
    def node(self) -> Do: ...

    @property
    def actor_path(self) -> str: ...

    @property
    def actor_kind(self) -> str: ...


class RunContext(Protocol):
    """What behaviours need from the run they belong to (see ``_run.TreeRun``)."""

    rt: Any
    bb: RunBlackboard

    def wake(self) -> None:
        """Ask for a tick soon (something changed)."""

    def start_actor(self, leaf: CallSite, args: tuple, kwargs: dict, on_done: Callable[[Any], None]) -> Any:
        """Start the leaf's actor asynchronously; returns its Transaction."""

    def halt_reason(self, node_path: str) -> str:
        """Why a halted node's transaction is being cancelled."""

    def actor_target(self, name: str) -> tuple[str, str]:
        """The path a call of actor ``name`` starts, and the actor's kind."""


def _read(value: Any, ctx: RunContext) -> Any:
    return resolve_value(value, ctx.bb.get)


def _outside_limits(ctx: RunContext, path: str, name: str, args: tuple, kwargs: dict) -> str | None:
    """Why the values an actor is called with break the limits it declares
    (``@actor(limits=...)``), or None; None also where the actor is not known here (a
    replay answers calls from its recording)."""
    try:
        ref = ctx.rt.resolve(path)
        limits = ref.safety.limits
        bound = ref.signature.bind(*args, **kwargs) if limits else None
    except (ActorbtError, LookupError, AttributeError, TypeError):
        return None
    if bound is None:
        return None
    for pname, value in bound.arguments.items():
        if pname not in limits:
            continue
        kind = ref.signature.parameters[pname].kind
        for v in value if kind is kind.VAR_POSITIONAL else (value,):
            problem = out_of_range(f"argument {pname!r} of actor {name!r}", v, limits[pname])
            if problem is not None:
                return problem
    return None


class ActorLeaf(py_trees.behaviour.Behaviour):
    """``do: actor``: start the actor in ``initialise``, poll it in ``update``, cancel it
    in ``terminate`` when halted.

    Succeeds when the actor returns anything but ``False`` (the result goes to ``out:``);
    fails on ``False``, on an exception, or when the transaction was cancelled elsewhere.
    """

    #: the actor's end asks for a tick (the answer is news to the tree)
    wakes_tree = True

    def __init__(
        self, name: str, ctx: RunContext, node: Do, actor_path: str, actor_kind: str = "sync", path: str = ""
    ) -> None:
        super().__init__(name)
        self.ctx = ctx
        self.node = node
        self.actor_path = actor_path
        self.actor_kind = actor_kind
        self.path = path
        self.txn: Any = None
        self.error: str | None = None
        self._token: object | None = None
        self._reads_blackboard = any(any(refs_in(v)) for v in (*node.args, *node.kwargs.values()))

    def initialise(self) -> None:
        self.txn = None
        self.error = None
        self.feedback_message = ""
        node = self.node
        try:
            args = tuple(_read(a, self.ctx) for a in node.args)
            kwargs = {k: _read(v, self.ctx) for k, v in node.kwargs.items()}
        except KeyError as exc:
            self.error = f"cannot call {node.actor}: {exc.args[0]}"
            return
        if self._reads_blackboard:
            # literals were checked against the actor's limits at load; values read now, here
            self.error = _outside_limits(self.ctx, self.actor_path, node.actor, args, kwargs)
            if self.error is not None:
                return
        token = self._token = object()

        def done(_outcome: Any) -> None:
            if self._token is token and self.wakes_tree:  # not halted meanwhile
                self.ctx.wake()

        try:
            self.txn = self.ctx.start_actor(self, args, kwargs, done)
        except ActorbtError as exc:
            self.error = str(exc)
            return
        self.feedback_message = f"running {self.actor_path} (transaction {self.txn.id})"

    def update(self) -> Status:
        if self.error is not None:
            self.feedback_message = self.error
            return Status.FAILURE
        txn = self.txn
        if not txn.done:
            return Status.RUNNING
        self._token = None
        if txn.state is TxnState.DONE:
            if txn.result is False:
                self.feedback_message = f"{self.actor_path} returned False"
                return Status.FAILURE
            if self.node.out is not None:
                self.ctx.bb.set(self.node.out, txn.result)
            self.feedback_message = f"{self.actor_path} done"
            return Status.SUCCESS
        if txn.state is TxnState.CANCELLED:
            self.feedback_message = f"{self.actor_path} cancelled: {txn.reason}"
        else:
            error = txn.error
            self.feedback_message = f"{self.actor_path} failed: {type(error).__name__}: {error}"
        return Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.INVALID and self.txn is not None and not self.txn.done:
            self._token = None
            self.txn.cancel(self.ctx.halt_reason(self.path))


class ConditionLeaf(ActorLeaf):
    """``condition: actor``: like ``do:``, but the tick waits for the actor's answer, so
    the node succeeds or fails in the tick that reached it and is never RUNNING.

    The wait blocks the tree's own greenlet only; the actors that other leaves started
    keep running meanwhile. Cancelling the tree raises ``Cancelled`` out of the wait, and
    the tree's halt then cancels the actor.
    """

    # the answer is read in the tick that waited for it; a tick more would ask again, and
    # a condition that is always asked would keep a reactive tree ticking in a loop
    wakes_tree = False

    def update(self) -> Status:
        txn = self.txn
        if self.error is None and not txn.done:
            answered = Signal(self.ctx.rt)
            txn.add_done_callback(lambda _txn: answered.set())
            answered.wait()
        return super().update()


class SetLeaf(py_trees.behaviour.Behaviour):
    """``set: {key: value}``: write, then succeed. Fails if a reference is unset."""

    def __init__(self, name: str, ctx: RunContext, node: SetValues) -> None:
        super().__init__(name)
        self.ctx = ctx
        self.values = tuple(node.values.items())

    def update(self) -> Status:
        try:
            resolved = [(key, _read(value, self.ctx)) for key, value in self.values]
        except KeyError as exc:
            self.feedback_message = f"cannot set: {exc.args[0]}"
            return Status.FAILURE
        for key, value in resolved:
            self.ctx.bb.set(key, value)
        return Status.SUCCESS


class CheckLeaf(py_trees.behaviour.Behaviour):
    """``check: expr``: success if it holds, failure if not or if it cannot be evaluated."""

    def __init__(self, name: str, ctx: RunContext, node: Check) -> None:
        super().__init__(name)
        self.ctx = ctx
        self.expr = node.expr
        self.source = node.source

    def update(self) -> Status:
        try:
            holds = evaluate(self.expr, self.ctx.bb.get)
        except CheckEvaluationError as exc:
            self.feedback_message = f"{self.source}: {exc}"
            return Status.FAILURE
        self.feedback_message = f"{self.source}: {'true' if holds else 'false'}"
        return Status.SUCCESS if holds else Status.FAILURE


def _number(
    value: Any, ctx: RunContext, what: str, integer: bool, allow_none: bool = False, minimum: float | None = None
) -> tuple[Any, str | None]:
    """Resolve a literal-or-reference parameter; (value, None) or (None, error). It must
    be at least ``minimum`` (default: 1 for an integer, 0 for a number)."""
    if isinstance(value, Ref):
        try:
            value = value.read(ctx.bb.get)
        except KeyError as exc:
            return None, f"{what}: {exc.args[0]}"
    ok = (int,) if integer else (int, float)
    if value is None and allow_none:
        return None, None
    low = (1 if integer else 0) if minimum is None else minimum
    if isinstance(value, bool) or not isinstance(value, ok) or value < low:
        return None, f"{what} is {value!r}, expected {'an integer' if integer else 'a number'} >= {low:g}"
    return value, None


class WaitLeaf(py_trees.behaviour.Behaviour):
    """``wait: seconds``: running until the deadline on the runtime clock, then success."""

    def __init__(self, name: str, ctx: RunContext, seconds: Any) -> None:
        super().__init__(name)
        self.ctx = ctx
        self.seconds = seconds
        self.deadline = 0.0
        self.timer: Any = None
        self.error: str | None = None

    def initialise(self) -> None:
        seconds, self.error = _number(self.seconds, self.ctx, "wait seconds", integer=False)
        if self.error is None:
            self.deadline = self.ctx.rt.now() + seconds
            self.timer = self.ctx.rt.call_later(seconds, self.ctx.wake)

    def update(self) -> Status:
        if self.error is not None:
            self.feedback_message = self.error
            return Status.FAILURE
        remaining = self.deadline - self.ctx.rt.now()
        if remaining > 0:
            self.feedback_message = f"{remaining:.3g} s left"
            return Status.RUNNING
        return Status.SUCCESS

    def terminate(self, new_status: Status) -> None:
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None


class _ParamDecorator(py_trees.decorators.Decorator):
    """A decorator whose parameter is resolved in ``initialise``; a bad value fails it
    without starting the child."""

    error: str | None = None

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status is not Status.RUNNING:
            self.initialise()
            if self.error is not None:
                self.feedback_message = self.error
                self.stop(Status.FAILURE)
                yield self
                return
        yield from self.decorated.tick()
        new_status = self.update()
        if new_status is not Status.RUNNING:
            self.stop(new_status)
        self.status = new_status
        yield self


class TimeoutNode(_ParamDecorator):
    """``timeout``: fail, halting the child, once ``seconds`` have passed on the runtime
    clock since the child started. The child is not ticked after the deadline."""

    def __init__(self, name: str, ctx: RunContext, child: py_trees.behaviour.Behaviour, seconds: Any) -> None:
        super().__init__(name=name, child=child)
        self.ctx = ctx
        self.seconds = seconds  # a number or a blackboard reference
        self.resolved = 0.0  # the number it had when the child started [s]
        self.deadline = 0.0
        self.timer: Any = None
        self.error: str | None = None

    def initialise(self) -> None:
        seconds, self.error = _number(self.seconds, self.ctx, "timeout seconds", integer=False)
        if self.error is None:
            self.resolved = seconds
            self.deadline = self.ctx.rt.now() + seconds
            self.timer = self.ctx.rt.call_later(seconds, self.ctx.wake)

    def tick(self) -> Iterator[py_trees.behaviour.Behaviour]:
        if self.status is Status.RUNNING and self.ctx.rt.now() >= self.deadline:
            self.feedback_message = f"timed out after {self.resolved:g} s"
            self.stop(Status.FAILURE)  # halts the running child
            yield self
            return
        yield from super().tick()

    def update(self) -> Status:
        return self.decorated.status

    def terminate(self, new_status: Status) -> None:
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None


class RetryNode(_ParamDecorator):
    """``retry``: run the child until it succeeds, ``times`` attempts in all."""

    def __init__(self, name: str, ctx: RunContext, child: py_trees.behaviour.Behaviour, times: Any) -> None:
        super().__init__(name=name, child=child)
        self.ctx = ctx
        self.times = times
        self.limit = 1
        self.attempts = 0
        self.error: str | None = None

    def initialise(self) -> None:
        self.attempts = 0
        self.limit, self.error = _number(self.times, self.ctx, "retry times", integer=True, allow_none=True)

    def update(self) -> Status:
        status = self.decorated.status
        if status is Status.FAILURE:
            self.attempts += 1
            if self.limit is not None and self.attempts >= self.limit:
                self.feedback_message = f"failed {self.attempts} of {self.limit} attempts"
                return Status.FAILURE
            self.feedback_message = f"attempt {self.attempts + 1} of {self.limit or 'unlimited'}"
            self.ctx.wake()  # the child restarts on the next tick
            return Status.RUNNING
        return status


class RepeatNode(_ParamDecorator):
    """``repeat``: run the child until it has succeeded ``times`` times (or forever);
    fail as soon as it fails."""

    def __init__(self, name: str, ctx: RunContext, child: py_trees.behaviour.Behaviour, times: Any) -> None:
        super().__init__(name=name, child=child)
        self.ctx = ctx
        self.times = times
        self.limit: int | None = None
        self.successes = 0
        self.error: str | None = None

    def initialise(self) -> None:
        self.successes = 0
        self.limit, self.error = _number(self.times, self.ctx, "repeat times", integer=True, allow_none=True)

    def update(self) -> Status:
        status = self.decorated.status
        if status is Status.SUCCESS:
            self.successes += 1
            if self.limit is not None and self.successes >= self.limit:
                return Status.SUCCESS
            self.feedback_message = f"{self.successes} of {self.limit or 'forever'} done"
            self.ctx.wake()  # the child restarts on the next tick
            return Status.RUNNING
        return status
