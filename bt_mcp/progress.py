"""Tree runs of one tool call: each node transition as a progress event, and the
call's trace (the trace recorder's events, kept in memory for ``get_trace``).

One :class:`RunWatcher` observes the runtime's tree host; a call registers its
transaction with :meth:`RunWatcher.watch` on the hub right after starting it (before
its task first runs), and the runs under that transaction (nested trees included) are
routed to it. Everything here runs on the hub thread, except ``CallWatch.events``
being read once the call ended.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

from py_trees.common import Status

from bt_engine.transaction import Transaction
from bt_engine.trees import CallSite, EventBuilder, TreeObserver, TreeRun

__all__ = ["CallWatch", "RunWatcher", "status_word", "MAX_TRACE_EVENTS"]

#: a trace longer than this keeps its first events and its last one (the outcome)
MAX_TRACE_EVENTS = 5000


def status_word(status: Status) -> str:
    """``running``, ``success``, ``failure``, or ``halted`` (back to INVALID)."""
    return "halted" if status is Status.INVALID else status.name.lower()


@dataclass
class CallWatch:
    """What one call wants to hear: ``on_transition(event)`` per node transition
    (``{"tree", "path", "status", "depth"}``), and the trace of its runs.

    Attributes:
        events: the trace events of the call's runs (``EventBuilder``'s format).
        dropped: how many events did not fit in :data:`MAX_TRACE_EVENTS`.
        ticks: ticks of the outermost run.
    """

    on_transition: Callable[[dict[str, Any]], None]
    events: list[dict[str, Any]] = field(default_factory=list)
    dropped: int = 0
    ticks: int = 0

    def __post_init__(self) -> None:
        self.builder = EventBuilder(self._keep)

    def _keep(self, event: dict[str, Any]) -> None:
        if len(self.events) < MAX_TRACE_EVENTS or event.get("type") == "end":
            self.events.append(event)
        else:
            self.dropped += 1


class RunWatcher(TreeObserver):
    """Routes the tree runs of watched transactions to their :class:`CallWatch`."""

    def __init__(self) -> None:
        self._calls: dict[int, CallWatch] = {}

    def watch(self, txn_id: int, call: CallWatch) -> None:
        self._calls[txn_id] = call

    def unwatch(self, txn_id: int) -> None:
        self._calls.pop(txn_id, None)

    def _call(self, run: TreeRun) -> CallWatch | None:
        top = run
        while top.parent is not None:
            top = top.parent
        return self._calls.get(top.txn_id) if top.txn_id is not None else None

    def _forward(self, event: str, run: TreeRun, *args: Any) -> CallWatch | None:
        call = self._call(run)
        if call is not None:
            getattr(call.builder, event)(run, *args)
        return call

    def run_started(self, run: TreeRun) -> None:
        self._forward("run_started", run)

    def tick(self, run: TreeRun) -> None:
        call = self._forward("tick", run)
        if call is not None and run.parent is None:
            call.ticks = run.ticks

    def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
        call = self._forward("status_changed", run, path, old, new)
        if call is not None and not (new is Status.INVALID and old is not Status.RUNNING):
            # (a reset of a finished node to INVALID is no transition worth reporting)
            call.on_transition({"tree": run.mission.name, "path": path, "status": status_word(new), "depth": run.depth})

    def actor_started(self, run: TreeRun, leaf: CallSite, args: tuple, kwargs: dict, txn: Transaction) -> None:
        self._forward("actor_started", run, leaf, args, kwargs, txn)

    def actor_finished(self, run: TreeRun, leaf: CallSite, txn: Transaction) -> None:
        self._forward("actor_finished", run, leaf, txn)

    def blackboard_write(self, run: TreeRun, key: str, value: Any) -> None:
        self._forward("blackboard_write", run, key, value)

    def run_finished(self, run: TreeRun, status: Status, outcome: Any) -> None:
        self._forward("run_finished", run, status, outcome)
