"""The call-mode matrix: every mode (how a caller runs an actor) for every kind (how the
actor is written). See docs/architecture.md, "The life of a call".

All functions here run on the hub thread. Blocking modes need a task (a greenlet);
calls from other threads come through :mod:`bt_engine.external` first.
"""

from __future__ import annotations

from typing import Any, Callable

from .actor import ActorRef
from .errors import ActorbtError, Cancelled, Failure
from .execution import (
    StreamWait,
    current_txn,
    drop_pending,
    run_body,
    spawn,
    start_async_impl,
    start_stream_impl,
    sync_body,
)
from .hub import Task, Waiter
from .iterator import ActorIterator
from .modes import Kind, Mode
from .outcome import failure_of, is_failure, result_or_raise
from .transaction import Transaction, TransactionTable, TxnState


def dispatch(
    table: TransactionTable,
    ref: ActorRef,
    mode: Mode,
    args: tuple,
    kwargs: dict,
    cb: Callable | None = None,
    seconds: float | None = None,
) -> Any:
    """Run ``ref`` in ``mode``. Returns the result, a Transaction or an iterator."""
    if mode is Mode.SYNC:
        return call_sync(table, ref, args, kwargs, None)
    if mode is Mode.TIMED:
        return call_sync(table, ref, args, kwargs, seconds)
    if mode is Mode.ASYNC:
        return start_async(table, ref, args, kwargs, cb)
    if mode is Mode.MULTI:
        return start_multi(table, ref, args, kwargs, cb)
    return ActorIterator(table, ref, args, kwargs, seconds if mode is Mode.TIMED_ITERATOR else None)


# -- sync and timed --------------------------------------------------------------------
def call_sync(table: TransactionTable, ref: ActorRef, args: tuple, kwargs: dict, seconds: float | None) -> Any:
    """Block the calling task until ``ref`` returns (a stream: its first value)."""
    task = table.hub.require_task(f"a sync call of {ref.path}")
    parent = task.txns[-1] if task.txns else None
    mode = Mode.SYNC if seconds is None else Mode.TIMED
    if ref.kind is Kind.SYNC or ref.is_generator:
        txn = Transaction(table, ref.path, parent, mode, ref.owner, task, args)
        if seconds is not None:
            txn.set_deadline(seconds)
        return run_body(sync_body(ref), txn, task, args, kwargs)
    ref.check_args(args, kwargs)
    txn = Transaction(table, ref.path, parent, mode, ref.owner, None, args)
    w = Waiter(task)
    txn.add_done_callback(lambda t: w.wake())
    if seconds is not None:
        txn.set_deadline(seconds)  # the caller's deadline replaces a stream's wait
    elif ref.wait is not None:
        StreamWait(ref, txn)  # a silent stream fails the call (a topic nobody publishes)
    _start_impl_once(ref, txn, args, kwargs)
    try:
        w.wait()
    finally:
        if not txn.done:  # our caller was cancelled while waiting
            txn.cancel("caller cancelled")
    return result_or_raise(txn)


def _start_impl_once(ref: ActorRef, txn: Transaction, args: tuple, kwargs: dict) -> None:
    """Start an async implementation, or a stream until its first value."""
    if ref.kind is Kind.ASYNC:
        start_async_impl(ref, txn, args, kwargs)
    else:
        start_stream_impl(ref, txn, args, kwargs, first_only=True, on_value=None)


# -- async -------------------------------------------------------------------------------
def _notify(cb: Callable | None, txn: Transaction) -> None:
    if cb is not None:
        txn.add_done_callback(lambda t: cb(t.result if t.state is TxnState.DONE else failure_of(t)))


def start_async(table: TransactionTable, ref: ActorRef, args: tuple, kwargs: dict, cb: Callable | None) -> Transaction:
    """Start ``ref`` and return its Transaction; ``cb(result | Failure)`` at the end."""
    if ref.kind is Kind.SYNC or ref.is_generator:
        body = sync_body(ref)
        txn = spawn(table, ref, Mode.ASYNC, args, lambda task, txn: run_body(body, txn, task, args, kwargs))
        _notify(cb, txn)
        return txn
    ref.check_args(args, kwargs)
    txn = Transaction(table, ref.path, current_txn(table), Mode.ASYNC, ref.owner, None, args)
    _notify(cb, txn)
    if ref.wait is not None:
        StreamWait(ref, txn)
    _start_impl_once(ref, txn, args, kwargs)
    return txn


# -- multi -------------------------------------------------------------------------------
def start_multi(table: TransactionTable, ref: ActorRef, args: tuple, kwargs: dict, cb: Callable | None) -> Transaction:
    """Call ``cb`` with every value until the transaction is cancelled or the stream
    ends; a failure is passed to ``cb`` as a Failure and ends it."""
    emit = cb if cb is not None else (lambda v: None)
    if ref.kind is Kind.SYNC:
        return _spawn_root(
            table, ref, Mode.MULTI, args, lambda task, txn: _repeat_sync(table, ref, task, txn, args, kwargs, emit)
        )
    if ref.is_generator:
        return _spawn_root(
            table, ref, Mode.MULTI, args, lambda task, txn: _pull_generator(ref, txn, args, kwargs, emit)
        )
    ref.check_args(args, kwargs)
    txn = Transaction(table, ref.path, current_txn(table), Mode.MULTI, ref.owner, None, args)
    if ref.kind is Kind.STREAM:
        on_value = emit
        if ref.wait is not None:  # the gap between values is bounded
            on_value = _resetting(StreamWait(ref, txn, on_expired=lambda: emit(failure_of(txn))), emit)
        start_stream_impl(ref, txn, args, kwargs, first_only=False, on_value=on_value)
        if txn.state is TxnState.FAILED and cb is not None:
            cb(failure_of(txn))
        return txn

    def again(value: Any) -> None:
        emit(value)
        if not txn.done:
            table.hub.call_soon(restart)

    def restart() -> None:
        if not txn.done:
            start_async_impl(ref, txn, args, kwargs, on_result=again)
            if txn.state is TxnState.FAILED and cb is not None:
                cb(failure_of(txn))

    restart()
    return txn


def _resetting(gap: StreamWait, emit: Callable[[Any], Any]) -> Callable[[Any], None]:
    """``emit`` that starts the wait for the next value again."""

    def on_value(value: Any) -> None:
        gap.heard()
        emit(value)

    return on_value


def _repeat_sync(
    table: TransactionTable,
    ref: ActorRef,
    task: Task,
    txn: Transaction,
    args: tuple,
    kwargs: dict,
    emit: Callable[[Any], Any],
) -> None:
    while True:
        child = Transaction(table, ref.path, txn, Mode.SYNC, ref.owner, task, args)
        try:
            value = run_body(ref, child, task, args, kwargs)
        except ActorbtError as e:
            txn.finish(TxnState.FAILED, error=e)
            emit(Failure(e, txn))
            return
        emit(value)
        table.hub.yield_now()  # let others run between invocations


def _pull_generator(ref: ActorRef, txn: Transaction, args: tuple, kwargs: dict, emit: Callable[[Any], Any]) -> None:
    gen = ref.fn(*args, **kwargs)
    try:
        for value in gen:
            emit(value)
    except BaseException as e:
        if not is_failure(e):
            raise
        txn.finish(TxnState.FAILED, error=e)
        emit(failure_of(txn))
        return
    finally:
        gen.close()
    txn.finish(TxnState.DONE, None)


def _spawn_root(
    table: TransactionTable, ref: ActorRef, mode: Mode, args: tuple, body: Callable[[Task, Transaction], None]
) -> Transaction:
    """Spawn ``body`` with its transaction on the task's stack, so that calls it makes
    are children and a cancel ends it quietly."""

    def wrapped(task: Task, txn: Transaction) -> None:
        task.txns.append(txn)
        try:
            task.raise_pending()
            body(task, txn)
        except Cancelled as c:
            drop_pending(task, txn)
            txn.finish(TxnState.CANCELLED, error=c)
        finally:
            task.txns.pop()

    return spawn(table, ref, mode, args, wrapped)
