"""The callables handed to async and stream implementations: ``done`` and ``emit``.

Both may be called from any thread: off the hub they hop onto it.
"""

from __future__ import annotations

from typing import Any, Callable

from .hub import Hub
from .transaction import Transaction, TxnState


class Done:
    """``done(result)`` for an async-kind actor; ``done.fail(exc)`` reports an error.

    Only the first call counts. Safe from any thread.
    """

    __slots__ = ("txn", "on_result", "used")

    def __init__(self, txn: Transaction, on_result: Callable[[Any], None] | None = None) -> None:
        self.txn = txn
        self.on_result = on_result
        self.used = False

    def __call__(self, result: Any = None) -> None:
        hub = self.txn.table.hub
        if not hub.in_hub_thread():
            hub.call_soon_threadsafe(self, result)
            return
        if self.used or self.txn.done:
            return
        self.used = True
        if self.on_result is not None:
            self.on_result(result)
        else:
            self.txn.finish(TxnState.DONE, result)

    def fail(self, exc: BaseException) -> None:
        hub = self.txn.table.hub
        if not hub.in_hub_thread():
            hub.call_soon_threadsafe(self.fail, exc)
            return
        if self.used or self.txn.done:
            return
        self.used = True
        self.txn.finish(TxnState.FAILED, error=exc)


class Emitter:
    """``emit(value)`` for a stream actor; ``emit.end()`` ends the stream, and
    ``emit.end(exc)`` ends it with an error. Safe from any thread."""

    __slots__ = ("hub", "_push", "_end")

    def __init__(self, hub: Hub, push: Callable[[Any], None], end: Callable[[BaseException | None], None]) -> None:
        self.hub = hub
        self._push = push
        self._end = end

    def __call__(self, value: Any) -> None:
        if self.hub.in_hub_thread():
            self._push(value)
        else:
            self.hub.call_soon_threadsafe(self._push, value)

    def end(self, error: BaseException | None = None) -> None:
        if self.hub.in_hub_thread():
            self._end(error)
        else:
            self.hub.call_soon_threadsafe(self._end, error)
