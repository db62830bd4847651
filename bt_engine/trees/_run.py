"""One run of a mission on py_trees: building the tree, the event-driven tick loop,
halting, and what observers (progress display, trace recorder) are told.

Ticks are event-driven. A tick happens when an actor transaction finishes, when a
deadline (``wait``, ``timeout``) falls due, when a decorator restarts its child, or
after ``max_period`` seconds at most. A tree waiting on a long actor costs no CPU.
All tree code runs on the hub thread.
"""

from __future__ import annotations

import inspect
from typing import Any, Callable, Iterator, Mapping, Protocol

import py_trees
from py_trees.common import Status

from ..signal import Signal
from ._behaviours import (
    ActorLeaf,
    CallSite,
    CheckLeaf,
    ConditionLeaf,
    RepeatNode,
    RetryNode,
    SetLeaf,
    TimeoutNode,
    WaitLeaf,
)
from ._blackboard import RunBlackboard
from ._controls import (
    CountingParallel,
    IfThenElseNode,
    PipelineSequenceNode,
    RateControllerNode,
    RecoveryNode,
    ResumeSequenceNode,
    RunOnceNode,
    WhileDoElseNode,
)
from ._errors import TreeFailure
from ._plugins import PluginSpec
from ._model import (
    Check,
    Condition,
    Do,
    ForceFailure,
    ForceSuccess,
    IfThenElse,
    Invert,
    Mission,
    Node,
    Parallel,
    ParallelPolicy,
    PipelineSequence,
    PluginNode,
    RateController,
    ReactiveSelector,
    ReactiveSequence,
    Recovery,
    Repeat,
    ResumeSequence,
    Retry,
    RunOnce,
    Selector,
    Sequence,
    SetValues,
    Timeout,
    UseBehaviour,
    Wait,
    WhileDoElse,
    children_of,
    resolve_value,
    walk,
)

__all__ = ["RunHost", "TreeObserver", "TreeRun", "node_path", "written_keys"]


def _preorder(b: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    yield b
    for child in b.children:
        yield from _preorder(child)


class TreeObserver:
    """Receives what happens in tree runs; override what you need (all no-ops here).

    Runs nest (a tree calling a tree): ``run.parent`` and ``run.depth`` say where.
    """

    def run_started(self, run: TreeRun) -> None:
        """A run was built and is about to tick for the first time."""

    def tick(self, run: TreeRun) -> None:
        """Tick number ``run.ticks`` is about to happen."""

    def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
        """After a tick: node ``path`` went from ``old`` to ``new`` (tree order)."""

    def tick_finished(self, run: TreeRun) -> None:
        """Tick ``run.ticks`` is over and its status changes were reported."""

    def actor_started(self, run: TreeRun, leaf: CallSite, args: tuple, kwargs: dict, txn: Any) -> None:
        """An actor leaf (``leaf.path``, ``leaf.node.actor``) started transaction ``txn``."""

    def actor_finished(self, run: TreeRun, leaf: CallSite, txn: Any) -> None:
        """That transaction finished (``txn.state``, ``txn.result``, ``txn.error``)."""

    def blackboard_write(self, run: TreeRun, key: str, value: Any) -> None:
        """``key`` was written (inputs seeding included)."""

    def run_finished(self, run: TreeRun, status: Status, outcome: Any) -> None:
        """The run ended: SUCCESS with the outputs, FAILURE with a TreeFailure, or
        INVALID with the exception that halted it (cancellation)."""


class RunHost(Protocol):
    """What a run needs from the host that made it (:class:`~bt_engine.trees.TreeHost`,
    or the replay host)."""

    rt: Any
    observers: list[TreeObserver]

    @property
    def behaviours(self) -> Mapping[str, Callable[..., py_trees.behaviour.Behaviour]]: ...

    def next_run_id(self) -> int: ...

    def period_for(self, mission: Mission) -> float | None: ...

    def actor_target(self, name: str) -> tuple[str, str]: ...

    def start_actor(
        self, run: "TreeRun", leaf: CallSite, args: tuple, kwargs: dict, on_done: Callable[[Any], None]
    ) -> Any: ...

    def node_plugin(self, name: str) -> PluginSpec: ...

    def run_closed(self, run: "TreeRun") -> None: ...


def written_keys(mission: Mission) -> set[str]:
    """Every blackboard key a mission may hold: inputs and everything it writes."""
    keys = {spec.name for spec in mission.inputs}
    for node in walk(mission.root):
        if isinstance(node, Do) and node.out is not None:
            keys.add(node.out)
        elif isinstance(node, SetValues):
            keys.update(node.values)
        elif isinstance(node, UseBehaviour):
            keys.update(node.writes)
        elif isinstance(node, PluginNode):
            keys.update(node.outs.values())
    return keys


def node_path(parent: str, label: str, taken: set[str]) -> str:
    """A node's path, as traces and observers name it: labels joined by '/', a '/' in a
    label written '|', a label repeated among siblings (``taken``) numbered '#2', '#3'..."""
    label = label.replace("/", "|")
    name, n = label, 2
    while name in taken:
        name, n = f"{label}#{n}", n + 1
    taken.add(name)
    return f"{parent}/{name}" if parent else name


class TreeRun:
    """One execution of a mission: its py_trees tree, blackboard and tick loop.

    Build one with :meth:`TreeHost.prepare`; then either call :meth:`run` from an actor
    (that is what the tree-as-actor does) or drive it tick by tick with :meth:`tick` on
    the hub (tests).

    Attributes:
        id: unique among the runs of its host.
        mission: what runs.
        parent: the run whose ``do:`` called this one, if any; ``depth`` counts them.
        ticks: ticks so far.
        status: the root's status after the last tick.
        root: the py_trees root behaviour.
        paths: node path of every behaviour (``sequence/retry x3/pick``).
    """

    def __init__(
        self, host: RunHost, mission: Mission, inputs: Mapping[str, Any], parent: TreeRun | None = None
    ) -> None:
        self.host = host
        self.rt = host.rt
        self.mission = mission
        self.parent = parent
        self.depth: int = 0 if parent is None else parent.depth + 1
        self.id = host.next_run_id()
        self.txn_id: int | None = None  # the transaction running it, when run as an actor
        self.ticks = 0
        self.status = Status.INVALID
        self.observers = list(host.observers)
        self.signal = Signal(self.rt)
        self.max_period = host.period_for(mission)
        self._halt_reason: str | None = None
        self._closed = False
        self.bb = RunBlackboard(
            mission.name, written_keys(mission), on_write=self._on_write if self.observers else None
        )
        self.inputs = dict(inputs)
        self.paths: dict[py_trees.behaviour.Behaviour, str] = {}
        self.nodes: dict[py_trees.behaviour.Behaviour, Node] = {}
        try:
            for key, value in self.inputs.items():
                self.bb.set(key, value)
            self.root = self._build(mission.root, "")
        except BaseException:
            self.bb.close()
            raise
        # Tree order (pre-order), for reports that read top-down.
        self.paths = {b: self.paths[b] for b in _preorder(self.root) if b in self.paths}
        self._last = {b: Status.INVALID for b in self.paths}

    # ------------------------------------------------------------ RunContext for behaviours

    def wake(self) -> None:
        """Ask for a tick soon."""
        self.signal.set()

    def start_actor(self, leaf: CallSite, args: tuple, kwargs: dict, on_done: Callable[[Any], None]) -> Any:
        txn = self.host.start_actor(self, leaf, args, kwargs, on_done)
        if self.observers:
            self._notify("actor_started", leaf, args, kwargs, txn)
            txn.add_done_callback(lambda t: self._notify("actor_finished", leaf, t))
        return txn

    def actor_target(self, name: str) -> tuple[str, str]:
        return self.host.actor_target(name)

    def halt_reason(self, node_path: str) -> str:
        if self._halt_reason is not None:
            return self._halt_reason
        return f"tree {self.mission.name}: node {node_path} halted"

    # ------------------------------------------------------------ building

    def _path(self, parent: str, label: str, taken: set[str]) -> str:
        return node_path(parent, label, taken)

    def _build(self, node: Node, path: str) -> py_trees.behaviour.Behaviour:
        return self._make(node, path or self._path("", node.label, set()))

    def _make(self, node: Node, path: str) -> py_trees.behaviour.Behaviour:
        taken: set[str] = set()
        kids = [self._make(child, self._path(path, child.label, taken)) for child in children_of(node)]
        label = path.rsplit("/", 1)[-1]
        b: py_trees.behaviour.Behaviour
        if isinstance(node, PluginNode):
            spec = self.host.node_plugin(node.plugin)
            if spec.cls is None:
                raise TypeError(
                    f"{node.kind} {node.plugin!r} is declared but not implemented: write it (see "
                    "docs/missions.md, 'Controls and decorators in Python')"
                )
            b = spec.cls(label, self, node, path, spec, kids)
        elif isinstance(node, Do):
            leaf_class = ConditionLeaf if isinstance(node, Condition) else ActorLeaf
            b = leaf_class(label, self, node, *self.host.actor_target(node.actor), path=path)
        elif isinstance(node, SetValues):
            b = SetLeaf(label, self, node)
        elif isinstance(node, Check):
            b = CheckLeaf(label, self, node)
        elif isinstance(node, Wait):
            b = WaitLeaf(label, self, node.seconds)
        elif isinstance(node, UseBehaviour):
            b = self._behaviour(node, label)
        elif isinstance(node, ReactiveSequence):
            b = py_trees.composites.Sequence(label, memory=False, children=kids)
        elif isinstance(node, Sequence):
            b = py_trees.composites.Sequence(label, memory=True, children=kids)
        elif isinstance(node, ReactiveSelector):
            b = py_trees.composites.Selector(label, memory=False, children=kids)
        elif isinstance(node, Selector):
            b = py_trees.composites.Selector(label, memory=True, children=kids)
        elif isinstance(node, Parallel) and node.counted:
            b = CountingParallel(label, kids, node.success_count or -1, node.failure_count or 1)
        elif isinstance(node, Parallel):
            b = py_trees.composites.Parallel(label, policy=self._policy(node, kids), children=kids)
        elif isinstance(node, ResumeSequence):
            b = ResumeSequenceNode(label, kids)
        elif isinstance(node, PipelineSequence):
            b = PipelineSequenceNode(label, kids)
        elif isinstance(node, IfThenElse):
            b = IfThenElseNode(label, kids)
        elif isinstance(node, WhileDoElse):
            b = WhileDoElseNode(label, kids)
        elif isinstance(node, Recovery):
            b = RecoveryNode(label, self, kids, node.retries)
        elif isinstance(node, RateController):
            b = RateControllerNode(label, self, kids[0], node.hz)
        elif isinstance(node, RunOnce):
            b = RunOnceNode(label, kids[0], node.then)
        elif isinstance(node, Retry):
            b = RetryNode(label, self, kids[0], node.times)
        elif isinstance(node, Repeat):
            b = RepeatNode(label, self, kids[0], node.times)
        elif isinstance(node, Timeout):
            b = TimeoutNode(label, self, kids[0], node.seconds)
        elif isinstance(node, Invert):
            b = py_trees.decorators.Inverter(label, kids[0])
        elif isinstance(node, ForceSuccess):
            b = py_trees.decorators.FailureIsSuccess(label, kids[0])
        elif isinstance(node, ForceFailure):
            b = py_trees.decorators.SuccessIsFailure(label, kids[0])
        else:  # pragma: no cover - the parser makes no other nodes
            raise TypeError(f"no behaviour for {type(node).__name__}")
        self.paths[b] = path
        self.nodes[b] = node
        return b

    @staticmethod
    def _policy(node: Parallel, kids: list[py_trees.behaviour.Behaviour]) -> Any:
        if node.policy is ParallelPolicy.SUCCESS_ON_ONE:
            return py_trees.common.ParallelPolicy.SuccessOnOne()
        if node.policy is ParallelPolicy.SUCCESS_ON_SELECTED:
            by_name = {child.name: kid for child, kid in zip(node.children, kids) if child.name is not None}
            return py_trees.common.ParallelPolicy.SuccessOnSelected(
                children=[by_name[name] for name in node.selected], synchronise=True
            )
        return py_trees.common.ParallelPolicy.SuccessOnAll(synchronise=True)

    def _behaviour(self, node: UseBehaviour, label: str) -> py_trees.behaviour.Behaviour:
        factory = self.host.behaviours[node.behaviour]
        kwargs = {k: resolve_value(v, self.bb.get) for k, v in node.kwargs.items()}
        params: Mapping[str, inspect.Parameter]
        try:
            params = inspect.signature(factory).parameters
        except (TypeError, ValueError):
            params = {}
        if "blackboard_namespace" in params:
            kwargs["blackboard_namespace"] = self.bb.namespace
        if "name" in params:
            kwargs.setdefault("name", label)
        behaviour = factory(**kwargs)
        if not isinstance(behaviour, py_trees.behaviour.Behaviour):
            raise TypeError(
                f"behaviour {node.behaviour!r} made {type(behaviour).__name__}, expected a py_trees Behaviour"
            )
        behaviour.name = label
        return behaviour

    # ------------------------------------------------------------ running

    def _notify(self, event: str, *args: Any) -> None:
        for observer in self.observers:
            getattr(observer, event)(self, *args)

    def _on_write(self, key: str, value: Any) -> None:
        self._notify("blackboard_write", key, value)

    def tick(self) -> Status:
        """Tick the tree once (hub thread only) and return the root's status."""
        self.ticks += 1
        if self.observers:
            self._notify("tick")
        self.root.tick_once()
        self.status = self.root.status
        if self.observers:
            self._report_changes()
            self._notify("tick_finished")
        return self.status

    def _report_changes(self) -> None:
        """The status changes of the last tick in the order they happened: a node that
        started before its children, one that ended after them."""
        last = self._last
        changes: dict[py_trees.behaviour.Behaviour, tuple[Status, Status]] = {}
        for behaviour in self.paths:
            new = behaviour.status
            if new is not last[behaviour]:
                changes[behaviour] = (last[behaviour], new)
                last[behaviour] = new
        if changes:
            self._report_in_order(self.root, changes)

    def _report_in_order(
        self, b: py_trees.behaviour.Behaviour, changes: dict[py_trees.behaviour.Behaviour, tuple[Status, Status]]
    ) -> None:
        change = changes.get(b)
        started = change is not None and change[1] is Status.RUNNING
        if change is not None and started:
            self._notify("status_changed", self.paths[b], *change)
        for child in b.children:
            self._report_in_order(child, changes)
        if change is not None and not started:
            self._notify("status_changed", self.paths[b], *change)

    def statuses(self) -> dict[str, Status]:
        """Every node's status by path, in tree order."""
        return {path: b.status for b, path in self.paths.items()}

    def tip_path(self) -> str | None:
        """Path of the deepest running node (the 'active node'), if any."""
        tip = self.root.tip()
        while tip is not None and tip not in self.paths:  # a behaviour's internals
            tip = tip.parent
        return self.paths.get(tip) if tip is not None else None

    def run(self) -> dict[str, Any]:
        """Tick until the root finishes; must be called from an actor (it blocks).

        Returns:
            the outputs, ``{name: value}`` (``None`` for an output never written).

        Raises:
            TreeFailure: the root failed.
            Cancelled: the calling transaction was cancelled; the tree is halted first.
        """
        rt = self.rt
        self._notify("run_started")
        try:
            while True:
                self.signal.clear()
                if self.tick() is not Status.RUNNING:
                    break
                if self.signal.is_set():
                    rt.sleep(0)  # re-tick at once, but let other tasks run first
                else:
                    self.signal.wait(self.max_period)
        except BaseException as exc:
            reason = getattr(exc, "reason", None) or type(exc).__name__
            self.halt(f"tree {self.mission.name} stopped: {reason}")
            self._notify("run_finished", Status.INVALID, exc)
            self.close()
            raise
        try:
            if self.status is Status.SUCCESS:
                outputs = self.outputs()
                self._notify("run_finished", Status.SUCCESS, outputs)
                return outputs
            failure = self.failure()
            self._notify("run_finished", Status.FAILURE, failure)
            raise failure
        finally:
            self.close()

    def outputs(self) -> dict[str, Any]:
        """The declared outputs as they are on the blackboard now."""
        return {spec.name: (self.bb.get(spec.name) if spec.name in self.bb else None) for spec in self.mission.outputs}

    def failure(self) -> TreeFailure:
        """Why the root failed: the deepest failed node and its feedback."""
        node = self.root
        while True:
            failed = [c for c in node.children if c.status is Status.FAILURE]
            if not failed:
                break
            node = failed[-1]
        return TreeFailure(self.mission.name, self.paths.get(node, node.name), node.feedback_message)

    def halt(self, reason: str | None = None) -> None:
        """Stop every running node; actor leaves cancel their transactions with ``reason``."""
        if reason is not None:
            self._halt_reason = reason
        self.root.stop(Status.INVALID)
        if self.observers:
            self._report_changes()

    def close(self) -> None:
        """Halt what still runs and remove the run's blackboard namespace."""
        if self._closed:
            return
        self._closed = True
        if self.root.status is Status.RUNNING:
            self.halt()
        self.bb.close()
        self.host.run_closed(self)
