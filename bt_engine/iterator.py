"""The ``iterator`` and ``timed_iterator`` call modes, consumed in the calling task."""

from __future__ import annotations

import collections
from typing import Any, Generator

from .actor import ActorRef
from .errors import ActorCancelled, ActorTimeout, Cancelled
from .execution import arm_wait, current_txn, drop_pending, run_body, start_async_impl, start_stream_impl
from .hub import Task, Waiter
from .modes import Kind, Mode
from .outcome import caller_error, is_failure, result_or_raise
from .transaction import Transaction, TransactionTable, TxnState


class ActorIterator:
    """Iterate an actor in the calling task.

    Sync and async actors are invoked again with the same arguments for every item; a
    stream's emitted values are buffered (the latest ``ref.buffer`` are kept). A deadline
    ends the iteration. Without one, a stream's ``wait`` bounds each wait for the next
    item (ActorTimeout), however long the stream goes on. Use it as a context manager:
    leaving the block closes the source.
    """

    def __init__(
        self, table: TransactionTable, ref: ActorRef, args: tuple, kwargs: dict, seconds: float | None
    ) -> None:
        self.table = table
        self.ref = ref
        self.args = args
        self.kwargs = kwargs
        self.seconds = seconds
        table.hub.require_task(f"iterating {ref.path}")
        ref.check_args(args, kwargs)
        mode = Mode.ITERATOR if seconds is None else Mode.TIMED_ITERATOR
        self.txn = Transaction(table, ref.path, current_txn(table), mode, ref.owner, None, args)
        self.txn.add_done_callback(self._on_finish)
        self._waiter: Waiter | None = None
        self._buffer: collections.deque | None = None
        self._gen: Generator[Any, None, None] | None = None
        if seconds is not None:
            self.txn.set_deadline(seconds)
        if ref.is_generator:
            self._gen = ref.fn(*args, **kwargs)
            self.txn.closer = self._gen.close
        elif ref.kind is Kind.STREAM:
            self._buffer = collections.deque(maxlen=max(1, ref.buffer))
            start_stream_impl(ref, self.txn, args, kwargs, first_only=False, on_value=self._push)

    def _push(self, value: Any) -> None:
        if self._buffer is None:
            raise RuntimeError(f"{self.ref.path}: a value came for an iterator that takes none")
        self._buffer.append(value)
        if self._waiter is not None:
            self._waiter.wake()

    def _on_finish(self, txn: Transaction) -> None:
        if self._waiter is not None:
            self._waiter.wake()

    # -- context manager and closing ---------------------------------------------------
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

    # -- iteration -------------------------------------------------------------------
    def _stopped(self) -> Any:
        """What ``next`` does once the transaction has finished: drain the buffer, then
        stop (done or deadline) or raise why it ended."""
        txn = self.txn
        if self._buffer and txn.state is TxnState.DONE:
            return self._buffer.popleft()
        if txn.state is TxnState.DONE or txn.timed_out:
            raise StopIteration
        raise caller_error(txn)

    def __next__(self) -> Any:
        txn = self.txn
        if txn.done:
            return self._stopped()
        task = self.table.hub.require_task(f"iterating {self.ref.path}")
        if self._buffer is not None:
            while not self._buffer:
                if txn.done:
                    return self._stopped()
                self._waiter = w = Waiter(task)
                # the stream's wait bounds each wait for an item; a timed iterator's own
                # deadline replaces it
                timer = arm_wait(self.ref, txn) if self.seconds is None else None
                try:
                    w.wait()
                finally:
                    self._waiter = None
                    if timer is not None:
                        timer.cancel()
            return self._buffer.popleft()
        try:
            if self._gen is not None:
                return self._next_from_generator(task, self._gen)
            return self._invoke_once(task)
        except (ActorTimeout, ActorCancelled):
            if txn.done:  # the iterator's own deadline or cancel ended the item
                return self._stopped()
            raise

    def _invoke_once(self, task: Task) -> Any:
        """One repeated invocation of a sync or async actor, as a child transaction."""
        ref, txn = self.ref, self.txn
        child = Transaction(
            self.table, ref.path, txn, Mode.SYNC, ref.owner, task if ref.kind is Kind.SYNC else None, self.args
        )
        if ref.kind is Kind.SYNC:
            task.txns.append(txn)  # nested calls see the iterator as their parent
            try:
                return run_body(ref, child, task, self.args, self.kwargs)
            finally:
                task.txns.pop()
        w = Waiter(task)
        child.add_done_callback(lambda t: w.wake())
        start_async_impl(ref, child, self.args, self.kwargs)
        try:
            w.wait()
        finally:
            if not child.done:
                child.cancel("caller cancelled")
        return result_or_raise(child)

    def _next_from_generator(self, task: Task, gen: Generator[Any, None, None]) -> Any:
        txn = self.txn
        txn.task = task  # cancellation reaches the generator only while it runs
        task.txns.append(txn)
        try:
            task.raise_pending()
            return next(gen)
        except StopIteration:
            txn.closer = None
            txn.finish(TxnState.DONE, None)
            raise
        except Cancelled as c:
            drop_pending(task, txn)
            gen.close()
            txn.finish(TxnState.CANCELLED, error=c)
            if c.transaction is txn:
                return self._stopped()
            raise
        except BaseException as e:
            txn.finish(TxnState.FAILED, error=e)
            if not is_failure(e):
                raise
            raise caller_error(txn) from e
        finally:
            task.txns.pop()
            txn.task = None
