"""The base classes of controls and decorators written in Python (plugins).

A plugin is a py_trees composite (:class:`ControlNode`) or decorator
(:class:`DecoratorNode`) whose logic is four plain methods, called on the hub in the
tree's own greenlet:

- ``on_create()``: once, when the run builds the tree (state that outlives a halt).
- ``on_start()``: when the node starts anew: ticked while idle (never ticked, or
  halted) or after it failed. A node that succeeded and is ticked again (a pipeline
  ticks its finished children) carries on, as BehaviorTree.CPP's active nodes do.
- ``on_tick() -> Status``: every tick. Tick children with :meth:`tick_child` (it returns
  the child's status) and halt them with :meth:`halt_child`; return RUNNING, SUCCESS or
  FAILURE. When the node finishes, children still running are halted for it.
- ``on_halt()``: the node was halted (its parent moved on, the tree was cancelled).

Ports are read with :meth:`input` (literal, blackboard key, default; an unset port
raises :class:`~._plugins.PortUnsetError`, which fails the node with that message)
and written with :meth:`output`. Actors are called with :meth:`start_actor` (in the
background: the tree is ticked when the answer comes) or :meth:`ask` (the tick waits
for the answer, as ``condition:`` leaves do). These calls are the tree's own: they show
in traces, a replay answers them from the recording, and they are cancelled whenever
the node stops, so a halted node leaves no transaction behind. Time is the runtime
clock (:meth:`now`); :meth:`wake_in` asks for a tick later.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterator

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from ..errors import ActorbtError
from ..signal import Signal
from ..transaction import TxnState
from ._behaviours import RunContext
from ._model import Do, PluginNode, Ref
from ._plugins import UNSET, InputPort, PluginSpec, PortUnsetError

__all__ = ["ActorCall", "ControlNode", "DecoratorNode", "PluginCallError"]


class PluginCallError(ActorbtError):
    """An actor a plugin node asked (:meth:`ControlNode.ask`) failed or returned False."""


@dataclass(frozen=True)
class _CallSite:
    """Who made an actor call, as traces and replay see it (what an actor leaf offers)."""

    path: str
    node: Do
    actor_path: str
    actor_kind: str


class ActorCall:
    """An actor call a plugin node started; it is cancelled when the node stops."""

    def __init__(self, actor: str, txn: Any) -> None:
        self.actor = actor
        self.txn = txn

    @property
    def done(self) -> bool:
        return bool(self.txn.done)

    @property
    def succeeded(self) -> bool:
        """Done, returned, and not ``False`` (the rule of ``do:`` leaves)."""
        return self.done and self.txn.state is TxnState.DONE and self.txn.result is not False

    @property
    def value(self) -> Any:
        """What the actor returned (``None`` until it has)."""
        return self.txn.result if self.done and self.txn.state is TxnState.DONE else None

    @property
    def problem(self) -> str:
        """Why it did not succeed, in words ("" while running or after a success)."""
        if not self.done or self.succeeded:
            return ""
        if self.txn.state is TxnState.DONE:
            return f"{self.actor} returned False"
        if self.txn.state is TxnState.CANCELLED:
            return f"{self.actor} cancelled: {self.txn.reason}"
        return f"{self.actor} failed: {type(self.txn.error).__name__}: {self.txn.error}"


class _PluginMixin:
    """What controls and decorators share: ports, actor calls, timers, the hooks."""

    ctx: RunContext
    node: PluginNode
    path: str
    spec: PluginSpec
    feedback_message: str
    status: Status

    def _plugin_init(self, ctx: RunContext, node: PluginNode, path: str, spec: PluginSpec) -> None:
        self.ctx = ctx
        self.node = node
        self.path = path
        self.spec = spec
        self._calls: list[ActorCall] = []
        self._timers: list[Any] = []
        self._visited: list[Behaviour] = []

    # ------------------------------------------------------------ hooks for subclasses

    def on_create(self) -> None:
        """Once, when the tree is built."""

    def on_start(self) -> None:
        """When the node starts anew (idle or failed), before ``on_tick``."""

    def on_tick(self) -> Status:  # pragma: no cover - abstract
        """Every tick: the node's status."""
        raise NotImplementedError

    def on_halt(self) -> None:
        """When halted while running."""

    # ------------------------------------------------------------ ports

    def input(self, name: str) -> Any:
        """The value of input port ``name`` now: the mission's literal, the blackboard
        value of its reference, or the port's default.

        Raises:
            PortUnsetError: nothing gives the port a value (no default, or its reference
                reads a key that is not set).
        """
        port = self.spec.inputs.get(name)
        if port is None:
            raise KeyError(f"{self.spec.name} declares no input port {name!r}")
        if name in self.node.ports:
            value = self.node.ports[name]
        elif port.default is UNSET:
            raise PortUnsetError(
                f"port {name!r} of {self.spec.name} is not set: the mission gives it no value and it has no default"
            )
        else:
            value = _default_value(port)
        try:
            return _resolve(value, self.ctx)
        except KeyError as exc:
            raise PortUnsetError(f"port {name!r} of {self.spec.name}: {exc.args[0]}") from None

    def has_input(self, name: str) -> bool:
        """Whether input port ``name`` has a value now (see :meth:`input`)."""
        try:
            self.input(name)
        except PortUnsetError:
            return False
        return True

    def output(self, name: str, value: Any) -> bool:
        """Write output port ``name`` to the key the mission maps it to; False when the
        mission maps it to none (the value goes nowhere, as in BehaviorTree.CPP)."""
        if name not in self.spec.outputs:
            raise KeyError(f"{self.spec.name} declares no output port {name!r}")
        key = self.node.outs.get(name)
        if key is None:
            return False
        self.ctx.bb.set(key, value)
        return True

    # ------------------------------------------------------------ time

    def now(self) -> float:
        """The runtime clock [s]."""
        return float(self.ctx.rt.now())

    def wake_in(self, seconds: float) -> None:
        """Ask for a tick ``seconds`` from now (cancelled when the node is halted)."""
        self._timers.append(self.ctx.rt.call_later(max(0.0, seconds), self.ctx.wake))

    # ------------------------------------------------------------ actors

    def start_actor(self, actor: str, *args: Any, **kwargs: Any) -> ActorCall:
        """Start ``actor`` in the background; the tree is ticked when it answers.

        Raises:
            ActorbtError: the actor is unknown or the arguments do not fit it.
        """
        return self._start(actor, args, kwargs, wakes_tree=True)

    def _start(self, actor: str, args: tuple, kwargs: dict, wakes_tree: bool) -> ActorCall:
        path, kind = self.ctx.actor_target(actor)
        site = _CallSite(self.path, Do(pos=self.node.pos, actor=actor), path, kind)
        call: ActorCall | None = None

        def done(_outcome: Any) -> None:
            if wakes_tree and call is not None and call in self._calls:
                self.ctx.wake()

        call = ActorCall(actor, self.ctx.start_actor(site, args, kwargs, done))
        self._calls.append(call)
        return call

    def ask(self, actor: str, *args: Any, **kwargs: Any) -> Any:
        """Call ``actor`` and wait for its answer within this tick; returns its value.

        Raises:
            PluginCallError: it failed, was cancelled, or returned False.
            ActorbtError: the actor is unknown or the arguments do not fit it.
        """
        # the answer is read in this tick: a tick more would only ask again (and again)
        call = self._start(actor, args, kwargs, wakes_tree=False)
        if not call.done:
            answered = Signal(self.ctx.rt)
            call.txn.add_done_callback(lambda _txn: answered.set())
            answered.wait()
        self._calls.remove(call)
        if not call.succeeded:
            raise PluginCallError(call.problem)
        return call.value

    def _release(self, halted: bool) -> None:
        """Cancel the calls the node still has under way, and when it is halted its
        timers too (a node that succeeded may want a tick later: a pipeline ticks it
        again, and the period it waits for should be over by then)."""
        calls, self._calls = self._calls, []
        for call in calls:
            if not call.done:
                call.txn.cancel(self.ctx.halt_reason(self.path))
        if halted:
            timers, self._timers = self._timers, []
            for timer in timers:
                timer.cancel()

    def _starting(self) -> bool:
        """Whether this tick starts the node anew: it is idle (never ticked, or halted)
        or it failed. A node that succeeded and is ticked again (a pipeline ticks its
        finished children) carries on, as BehaviorTree.CPP's active nodes do."""
        return self.status in (Status.INVALID, Status.FAILURE)

    def _step(self, starting: bool) -> Status:
        """``on_start`` when starting, then ``on_tick``; an unset port or a failed call
        fails the node with its message."""
        try:
            if starting:
                self.on_start()
            return self.on_tick()
        except (PortUnsetError, PluginCallError) as exc:
            self.feedback_message = str(exc)
            return Status.FAILURE

    def _tick_child(self, child: Behaviour) -> Status:
        for visited in child.tick():
            self._visited.append(visited)
        return child.status


def _default_value(port: InputPort) -> Any:
    """A port's default as a mission value: ``"{key}"`` reads that key."""
    default = port.default
    if isinstance(default, str) and default.startswith("{") and default.endswith("}") and len(default) > 2:
        key, *fields = default[1:-1].split(".")
        from ._errors import Pos

        return Ref(key, tuple(fields), Pos("<default>", 1, 1))
    return default


def _resolve(value: Any, ctx: RunContext) -> Any:
    from ._model import resolve_value

    return resolve_value(value, ctx.bb.get)


class ControlNode(_PluginMixin, py_trees.composites.Composite):
    """The base of a control written in Python (see the module docstring); mark the
    subclass with :func:`~._plugins.control_node`."""

    def __init__(
        self, name: str, ctx: RunContext, node: PluginNode, path: str, spec: PluginSpec, children: list[Behaviour]
    ) -> None:
        py_trees.composites.Composite.__init__(self, name, children)
        self._plugin_init(ctx, node, path, spec)
        self.on_create()

    def tick_child(self, child: Behaviour | int) -> Status:
        """Tick one child (or the child at that index) and return its status."""
        behaviour = self.children[child] if isinstance(child, int) else child
        self.current_child = behaviour
        return self._tick_child(behaviour)

    def halt_child(self, child: Behaviour | int) -> None:
        """Halt one child (or the child at that index) if it is not idle."""
        behaviour = self.children[child] if isinstance(child, int) else child
        if behaviour.status is not Status.INVALID:
            behaviour.stop(Status.INVALID)

    def halt_children(self) -> None:
        """Halt every child that is not idle."""
        for child in self.children:
            self.halt_child(child)

    def tick(self) -> Iterator[Behaviour]:
        starting = self._starting()
        if starting:
            self.halt_children()
        self._visited = []
        status = self._step(starting)
        yield from self._visited
        self._visited = []
        if status is Status.RUNNING:
            self.status = status
        else:
            for child in self.children:  # what is still running is the node's to stop
                if child.status is Status.RUNNING:
                    child.stop(Status.INVALID)
            self.stop(status)
        yield self

    def terminate(self, new_status: Status) -> None:
        self._release(halted=new_status is Status.INVALID)
        if new_status is Status.INVALID:
            self.on_halt()


class DecoratorNode(_PluginMixin, py_trees.decorators.Decorator):
    """The base of a decorator written in Python (see the module docstring); mark the
    subclass with :func:`~._plugins.decorator_node`. Its child is ``self.decorated``."""

    def __init__(
        self, name: str, ctx: RunContext, node: PluginNode, path: str, spec: PluginSpec, children: list[Behaviour]
    ) -> None:
        py_trees.decorators.Decorator.__init__(self, child=children[0], name=name)
        self._plugin_init(ctx, node, path, spec)
        self.on_create()

    @property
    def child(self) -> Behaviour:
        return self.decorated

    def tick_child(self) -> Status:
        """Tick the child and return its status."""
        return self._tick_child(self.decorated)

    def halt_child(self) -> None:
        """Halt the child if it is not idle."""
        if self.decorated.status is not Status.INVALID:
            self.decorated.stop(Status.INVALID)

    def tick(self) -> Iterator[Behaviour]:
        starting = self._starting()
        self._visited = []
        status = self._step(starting)
        yield from self._visited
        self._visited = []
        if status is Status.RUNNING:
            self.status = status
        else:
            self.stop(status)  # a running child is halted by py_trees' Decorator.stop
        yield self

    def update(self) -> Status:  # unused: tick() decides
        return self.status

    def terminate(self, new_status: Status) -> None:
        self._release(halted=new_status is Status.INVALID)
        if new_status is Status.INVALID:
            self.on_halt()
