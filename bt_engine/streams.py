"""Callables handed to async and stream implementations, and the actor iterator.

``Done`` and ``Emitter`` may be called from any thread: off the hub they hop onto it.
"""
from __future__ import annotations

import collections
from typing import TYPE_CHECKING, Any, Callable

from .errors import ActorCancelled, ActorError, ActorTimeout, Cancelled
from .hub import Waiter
from .modes import Kind, Mode
from .transaction import Transaction, TxnState

if TYPE_CHECKING:
    from .actor import ActorRef
    from .runtime import Runtime


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
        hub = self.txn.rt.hub
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
        hub = self.txn.rt.hub
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

    __slots__ = ("rt", "_push", "_end")

    def __init__(self, rt: "Runtime", push: Callable[[Any], None],
                 end: Callable[[BaseException | None], None]) -> None:
        self.rt = rt
        self._push = push
        self._end = end

    def __call__(self, value: Any) -> None:
        if self.rt.hub.in_hub_thread():
            self._push(value)
        else:
            self.rt.hub.call_soon_threadsafe(self._push, value)

    def end(self, error: BaseException | None = None) -> None:
        if self.rt.hub.in_hub_thread():
            self._end(error)
        else:
            self.rt.hub.call_soon_threadsafe(self._end, error)


class ActorIterator:
    """The ``iterator`` and ``timed_iterator`` modes, consumed in the calling task.

    Sync and async actors are invoked again with the same arguments for every item; a
    stream's emitted values are buffered (the latest ``ref.buffer`` are kept). A deadline
    ends the iteration. Use it as a context manager: leaving the block closes the source.
    """

    def __init__(self, rt: "Runtime", ref: "ActorRef", args: tuple, kwargs: dict,
                 seconds: float | None) -> None:
        from .invoke import current_txn
        self.rt = rt
        self.ref = ref
        self.args = args
        self.kwargs = kwargs
        self.seconds = seconds
        self.task = rt.hub.require_task(f"iterating {ref.path}")
        ref.check_args(args, kwargs)
        mode = Mode.ITERATOR if seconds is None else Mode.TIMED_ITERATOR
        self.txn = Transaction(rt, ref.path, current_txn(rt), mode, ref.owner, None, args)
        self.txn.add_done_callback(self._on_finish)
        self._waiter: Waiter | None = None
        self._buffer: collections.deque | None = None
        self._gen = None
        if seconds is not None:
            self.txn.set_deadline(seconds)
        if ref.is_generator:
            self._gen = ref.fn(*args, **kwargs)
            self.txn.closer = self._gen.close
        elif ref.kind is Kind.STREAM:
            self._start_stream()

    # -- stream sources --------------------------------------------------------------
    def _start_stream(self) -> None:
        from .invoke import _start_emit_impl
        self._buffer = collections.deque(maxlen=max(1, self.ref.buffer))
        _start_emit_impl(self.ref, self.txn, self.args, self.kwargs, first_only=False,
                         on_value=self._push)

    def _push(self, value: Any) -> None:
        self._buffer.append(value)  # type: ignore[union-attr]
        if self._waiter is not None:
            self._waiter.wake()

    def _on_finish(self, txn: Transaction) -> None:
        if self._waiter is not None:
            self._waiter.wake()

    # -- iteration -------------------------------------------------------------------
    def __iter__(self) -> "ActorIterator":
        return self

    def __enter__(self) -> "ActorIterator":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        """Close the source; the transaction ends as done."""
        txn = self.txn
        if txn.done:
            return
        closer, txn.closer = txn.closer, None
        if closer is not None:
            closer()
        for child in list(txn.children.values()):
            child.cancel("iterator closed")
        txn.finish(TxnState.DONE, None)

    def _stopped(self) -> Any:
        """What ``next`` does once the transaction has finished."""
        txn = self.txn
        if self._buffer and txn.state is TxnState.DONE:
            return self._buffer.popleft()
        if txn.state is TxnState.FAILED:
            err = txn.error
            raise ActorError(txn.path, err) from err  # type: ignore[arg-type]
        if txn.state is TxnState.CANCELLED and not txn.timed_out:
            raise ActorCancelled(txn.path, txn.reason or "cancelled")
        raise StopIteration

    def __next__(self) -> Any:
        txn = self.txn
        if txn.done:
            return self._stopped()
        task = self.rt.hub.require_task(f"iterating {self.ref.path}")
        if self._buffer is not None:
            while not self._buffer:
                if txn.done:
                    return self._stopped()
                self._waiter = w = Waiter(task)
                try:
                    w.wait()
                finally:
                    self._waiter = None
            return self._buffer.popleft()
        try:
            if self._gen is not None:
                return self._next_from_generator(task)
            return self._invoke_once(task)
        except (ActorTimeout, ActorCancelled):
            if txn.done:
                return self._stopped()
            raise

    def _invoke_once(self, task: Any) -> Any:
        """One repeated invocation of a sync or async actor, as a child transaction."""
        from .invoke import _start_callback_impl, outcome_for_caller, run_body
        ref, txn = self.ref, self.txn
        if ref.kind is Kind.SYNC:
            child = Transaction(self.rt, ref.path, txn, Mode.SYNC, ref.owner, task, self.args)
            task.txns.append(txn)  # nested calls see the iterator as their parent
            try:
                return run_body(ref, child, task, self.args, self.kwargs)
            finally:
                task.txns.pop()
        child = Transaction(self.rt, ref.path, txn, Mode.SYNC, ref.owner, None, self.args)
        w = Waiter(task)
        child.add_done_callback(lambda t: w.wake())
        _start_callback_impl(ref, child, self.args, self.kwargs)
        try:
            w.wait()
        finally:
            if not child.done:
                child.cancel("caller cancelled")
        return outcome_for_caller(child)

    def _next_from_generator(self, task: Any) -> Any:
        txn = self.txn
        txn.task = task  # cancellation reaches the generator only while it runs
        task.txns.append(txn)
        try:
            task.raise_pending()
            return next(self._gen)  # type: ignore[arg-type]
        except StopIteration:
            txn.closer = None
            txn.finish(TxnState.DONE, None)
            raise
        except Cancelled as c:
            from .invoke import _drop_pending
            _drop_pending(task, txn)
            self._gen.close()  # type: ignore[union-attr]
            txn.finish(TxnState.CANCELLED, error=c)
            if c.transaction is txn:
                return self._stopped()
            raise
        except Exception as e:
            txn.finish(TxnState.FAILED, error=e)
            raise ActorError(txn.path, e) from e
        finally:
            task.txns.pop()
            txn.task = None
