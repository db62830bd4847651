"""Transactions: one per actor call, in a parent/child tree.

Cancelling a transaction cancels its children first, then raises ``Cancelled`` at the
next blocking point of its task (sync-style actors) or calls its closer (async and
stream actors). A transaction that finishes cancels whatever children it left running,
so no work outlives its owner.
"""

from __future__ import annotations

import enum
import itertools
import logging
from typing import TYPE_CHECKING, Any, Callable

from .clock import Clock
from .errors import Cancelled, Failure

if TYPE_CHECKING:
    from .hub import Hub, Task, TimerHandle
    from .modes import Mode

log = logging.getLogger("actorbt")


class TxnState(enum.Enum):
    """Where a transaction is in its life."""

    RUNNING = "running"
    """Started and not finished."""
    DONE = "done"
    """Finished with a result."""
    FAILED = "failed"
    """Finished with an exception."""
    CANCELLED = "cancelled"
    """Cancelled (by a caller, a parent, or a deadline)."""


class TransactionTable:
    """The live transactions of one runtime, and what every transaction needs from it:
    the hub, the clock and the trace recorder.

    ``recorder`` is None or an object with ``call_started(txn)`` and
    ``call_finished(txn)`` (the trace layer installs one).
    """

    def __init__(self, hub: "Hub", clock: Clock) -> None:
        self.hub = hub
        self.clock = clock
        self.live: dict[int, Transaction] = {}
        self.recorder: Any = None
        self._ids = itertools.count(1)

    def next_id(self) -> int:
        return next(self._ids)

    def roots(self) -> list["Transaction"]:
        """Live transactions without a parent, oldest first."""
        return [t for t in self.live.values() if t.parent is None]


class Transaction:
    """One call of one actor.

    Attributes: ``id``; ``path`` (actor path); ``parent``; ``mode`` (a Mode); ``started``
    and ``deadline`` [s, runtime clock]; ``state``; ``result``; ``error``; ``reason``
    (why it was cancelled); ``timed_out``.
    """

    __slots__ = (
        "id",
        "path",
        "parent",
        "mode",
        "started",
        "deadline",
        "state",
        "children",
        "task",
        "closer",
        "reason",
        "result",
        "error",
        "timed_out",
        "table",
        "_listeners",
        "_deadline_timer",
        "scope",
        "args",
        "__weakref__",
    )

    def __init__(
        self,
        table: TransactionTable,
        path: str,
        parent: "Transaction | None",
        mode: Mode,
        scope: Any = None,
        task: "Task | None" = None,
        args: tuple = (),
    ) -> None:
        self.id = table.next_id()
        self.table = table
        self.path = path
        self.parent = parent
        self.mode = mode
        self.scope = scope
        self.task = task
        self.args = args
        self.started = table.clock.now()
        self.deadline: float | None = None
        self.state = TxnState.RUNNING
        self.children: dict[int, Transaction] = {}
        self.closer: Callable[[], Any] | None = None
        self.reason: str | None = None
        self.result: Any = None
        self.error: BaseException | None = None
        self.timed_out = False
        self._listeners: list | None = None
        self._deadline_timer: TimerHandle | None = None
        table.live[self.id] = self
        if parent is not None:
            parent.children[self.id] = self
        if table.recorder is not None:
            table.recorder.call_started(self)

    # -- queries ----------------------------------------------------------------------
    @property
    def done(self) -> bool:
        """True once the transaction has finished, in any state."""
        return self.state is not TxnState.RUNNING

    @property
    def cancelled(self) -> bool:
        return self.state is TxnState.CANCELLED

    def outcome(self) -> Any:
        """The result, or a :class:`Failure` carrying the error."""
        if self.state is TxnState.DONE:
            return self.result
        return Failure(self.error if self.error is not None else Cancelled(self, self.reason or ""), self)

    def __repr__(self) -> str:
        return f"<Transaction {self.id} {self.path} {self.mode.value} {self.state.value}>"

    # -- control ----------------------------------------------------------------------
    def set_deadline(self, seconds: float) -> None:
        """Cancel this transaction (as timed out) after ``seconds`` on the runtime clock."""
        self.deadline = self.table.clock.now() + seconds
        self._deadline_timer = self.table.hub.call_at(self.deadline, self._expire)

    def _expire(self) -> None:
        if self.state is TxnState.RUNNING:
            self.timed_out = True
            self.cancel("deadline passed")

    def cancel(self, reason: str = "cancelled by caller") -> None:
        """Cancel this transaction and, first, all of its children. Thread-safe."""
        hub = self.table.hub
        if not hub.in_hub_thread():
            hub.call_soon_threadsafe(self.cancel, reason)
            return
        if self.state is not TxnState.RUNNING or self.reason is not None:
            return
        self.reason = reason
        for child in list(self.children.values()):
            child.cancel(reason)
        if self.task is not None:
            self.task.deliver_cancel(Cancelled(self, reason))
            return
        closer, self.closer = self.closer, None
        if closer is not None:
            try:
                closer()
            except Exception:
                log.exception("closer of %s raised", self.path)
        self.finish(TxnState.CANCELLED, error=Cancelled(self, reason))

    def add_done_callback(self, fn: Callable[["Transaction"], Any]) -> None:
        """Call ``fn(txn)`` on the hub when the transaction finishes (at once if it has)."""
        if self.state is not TxnState.RUNNING:
            fn(self)
            return
        if self._listeners is None:
            self._listeners = []
        self._listeners.append(fn)

    def finish(self, state: TxnState, result: Any = None, error: BaseException | None = None) -> None:
        """Record the outcome, release the children and notify listeners. Hub only."""
        if self.state is not TxnState.RUNNING:
            return
        self.state = state
        self.result = result
        self.error = error
        if self._deadline_timer is not None:
            self._deadline_timer.cancel()
        table = self.table
        table.live.pop(self.id, None)
        if self.parent is not None:
            self.parent.children.pop(self.id, None)
        if self.children:
            for child in list(self.children.values()):
                child.cancel(f"parent {self.path} finished")
        if table.recorder is not None:
            table.recorder.call_finished(self)
        listeners, self._listeners = self._listeners, None
        if listeners:
            for fn in listeners:
                try:
                    fn(self)
                except Exception:
                    log.exception("done-callback of %s raised", self.path)
