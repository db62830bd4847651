"""Running one actor under one transaction, for each kind of actor (how it is written).

- a sync body runs in a task (greenlet) with its transaction on the task's stack;
- an async implementation is started with ``done``; a stream with ``emit``;
- a generator is a stream whose values are pulled in the consumer's task.

The call modes (:mod:`bt_engine.invoke`, :mod:`bt_engine.iterator`) are built from
these. Everything here runs on the hub thread.
"""

from __future__ import annotations

import logging
from typing import Any, Callable

from .actor import ActorRef
from .errors import ActorTimeout, BadArgumentsError, Cancelled
from .handles import Done, Emitter
from .hub import Task, TimerHandle
from .modes import Mode
from .outcome import caller_error, is_failure
from .transaction import Transaction, TransactionTable, TxnState

log = logging.getLogger("actorbt")


def current_txn(table: TransactionTable) -> Transaction | None:
    """The transaction whose code is running now, if any (the parent of new calls)."""
    task = table.hub.current_task()
    if task is not None and task.txns:
        return task.txns[-1]
    return None


# -- sync bodies ---------------------------------------------------------------------------
def run_body(ref: "ActorRef | GenFirst", txn: Transaction, task: Task, args: tuple, kwargs: dict) -> Any:
    """Run a sync-kind actor's body in ``task`` under ``txn`` and translate its outcome.

    Returns the result. Raises what the caller sees (:mod:`bt_engine.outcome`), or
    re-raises a Cancelled aimed at an outer transaction, or KeyboardInterrupt/SystemExit.
    """
    task.txns.append(txn)
    try:
        task.raise_pending()
        result = ref.fn(*args, **kwargs)
    except Cancelled as c:
        drop_pending(task, txn)
        txn.finish(TxnState.CANCELLED, error=c)
        if c.transaction is txn:
            raise caller_error(txn) from None
        raise
    except BaseException as e:
        if not is_failure(e):
            txn.finish(TxnState.FAILED, error=e)
            raise
        err: BaseException = e
        if isinstance(e, TypeError):
            err = bad_arguments(ref, args, kwargs, txn) or e
        txn.finish(TxnState.FAILED, error=err)
        raise caller_error(txn) from (None if err is not e else e)
    else:
        drop_pending(task, txn)
        txn.finish(TxnState.DONE, result)
        return result
    finally:
        task.txns.pop()


def drop_pending(task: Task, txn: Transaction) -> None:
    """Forget a pending cancel aimed at ``txn`` or below it: that work has ended."""
    pending = task.pending_cancel
    if pending is None:
        return
    t = pending.transaction
    while t is not None:
        if t is txn:
            task.pending_cancel = None
            return
        t = t.parent


def bad_arguments(ref: "ActorRef | GenFirst", args: tuple, kwargs: dict, txn: Transaction) -> BadArgumentsError | None:
    """The BadArgumentsError of call ``txn`` when its arguments do not fit, or None when
    they fit (a TypeError raised inside the actor is then the actor's own failure)."""
    try:
        ref.check_args(args, kwargs)
    except BadArgumentsError as e:
        e.transaction_id = txn.id  # it is this call's own error
        return e
    return None


class GenFirst:
    """Adapts a generator actor so its body returns the first yielded value (the sync
    and async modes of a stream)."""

    def __init__(self, ref: ActorRef) -> None:
        self.path = ref.path
        self._ref = ref

    def fn(self, *args: Any, **kwargs: Any) -> Any:
        gen = self._ref.fn(*args, **kwargs)
        try:
            return next(gen)
        except StopIteration:
            raise LookupError(f"stream {self.path} ended without a value") from None
        finally:
            gen.close()

    def check_args(self, args: tuple, kwargs: dict) -> None:
        self._ref.check_args(args, kwargs)


def sync_body(ref: ActorRef) -> "ActorRef | GenFirst":
    """What a sync-style call runs: the actor itself, or a generator's first value."""
    return GenFirst(ref) if ref.is_generator else ref


def spawn(
    table: TransactionTable, ref: ActorRef, mode: Mode, args: tuple, body: Callable[[Task, Transaction], Any]
) -> Transaction:
    """Run ``body(task, txn)`` in a new task under a new transaction (child of the
    current one)."""
    hub = table.hub
    parent = current_txn(table)

    def main() -> None:
        try:
            body(task, txn)
        except Exception:
            pass  # recorded on txn by run_body
        except Cancelled:
            pass
        finally:
            if not txn.done:  # a body that ended without finishing (a cancelled stream)
                txn.finish(TxnState.CANCELLED, error=Cancelled(txn, txn.reason or "cancelled"))

    task = Task(hub, main)
    txn = Transaction(table, ref.path, parent, mode, ref.owner, task, args)
    hub.ready.append((hub.switch_to, (task,)))
    return txn


# -- async and stream implementations ----------------------------------------------------------
def start_async_impl(
    ref: ActorRef, txn: Transaction, args: tuple, kwargs: dict, on_result: Callable[[Any], None] | None = None
) -> None:
    """Start an async-kind implementation; ``done(result)`` finishes ``txn`` (or, with
    ``on_result``, hands the result there)."""
    _call_impl(ref, txn, Done(txn, on_result), args, kwargs)


def start_stream_impl(
    ref: ActorRef, txn: Transaction, args: tuple, kwargs: dict, first_only: bool, on_value: Callable[[Any], None] | None
) -> None:
    """Start an emit-style stream; with ``first_only`` the first value finishes ``txn``,
    otherwise every value goes to ``on_value`` until the stream ends or is closed."""

    def push(value: Any) -> None:
        if txn.done:
            return
        if first_only:
            closer, txn.closer = txn.closer, None
            txn.finish(TxnState.DONE, value)
            if closer is not None:
                call_quietly(closer)
        elif on_value is not None:
            on_value(value)

    def end(error: BaseException | None) -> None:
        if txn.done:
            return
        if error is not None:
            txn.finish(TxnState.FAILED, error=error)
        elif first_only:
            txn.finish(TxnState.FAILED, error=LookupError(f"stream {ref.path} ended without a value"))
        else:
            txn.finish(TxnState.DONE, None)

    _call_impl(ref, txn, Emitter(txn.table.hub, push, end), args, kwargs)


def _call_impl(ref: ActorRef, txn: Transaction, handle: Done | Emitter, args: tuple, kwargs: dict) -> None:
    """Call an async or stream implementation with its ``done``/``emit`` handle and keep
    the closer it returns (or call it at once if the work already finished)."""
    hub = txn.table.hub
    if not ref.hub_only:
        # It may complete from another thread: the virtual clock paces itself until then.
        hub.foreign_work_started()
        txn.add_done_callback(lambda t: hub.foreign_work_ended())
    try:
        closer = ref.fn(handle, *args, **kwargs)
    except BaseException as e:
        if not is_failure(e):
            txn.finish(TxnState.FAILED, error=e)
            raise
        err = bad_arguments(ref, args, kwargs, txn) if isinstance(e, TypeError) else None
        txn.finish(TxnState.FAILED, error=err or e)
        return
    closer = _closer_of(closer, txn)
    if closer is not None:
        if txn.done:
            call_quietly(closer)
        else:
            txn.closer = closer


def _closer_of(returned: Any, txn: Transaction) -> Callable[[], Any] | None:
    """The closer an implementation returned: a callable, or ros_actor's list of
    ``("close", fn(transaction))`` pairs."""
    if callable(returned):
        return returned
    if isinstance(returned, (list, tuple)):
        for pair in returned:
            if isinstance(pair, (list, tuple)) and len(pair) == 2 and pair[0] == "close" and callable(pair[1]):
                fn = pair[1]
                return lambda: fn(txn)
    return None


def call_quietly(fn: Callable[[], Any]) -> None:
    """Call a closer; log what it raises (closing must go on)."""
    try:
        fn()
    except Exception:
        log.exception("closer %r raised", fn)


# -- a stream's wait for its next value (ActorRef.wait) ----------------------------------------
class StreamWait:
    """Fails ``txn`` (a call of stream ``ref``) with :class:`ActorTimeout` when no value
    has come for ``ref.wait`` seconds [runtime clock] since it was made or since the last
    :meth:`heard`: the sync and async modes (the first value) and the multi mode (the
    gap between values). One timer, moved on lazily, whatever the message rate.
    ``on_expired()`` runs after the transaction failed (the multi mode's callback)."""

    __slots__ = ("ref", "txn", "wait", "last", "timer", "on_expired")

    def __init__(self, ref: ActorRef, txn: Transaction, on_expired: Callable[[], None] | None = None) -> None:
        if ref.wait is None:
            raise ValueError(f"{ref.path} waits forever for a value: it has no StreamWait")
        self.ref = ref
        self.wait: float = ref.wait
        self.txn = txn
        self.on_expired = on_expired
        self.last = txn.table.clock.now()
        repace(ref, txn)
        self.timer: TimerHandle = txn.table.hub.call_at(self.last + self.wait, self._check)
        txn.add_done_callback(lambda t: self.timer.cancel())

    def heard(self) -> None:
        """A value came: the wait starts again."""
        self.last = self.txn.table.clock.now()

    def _check(self) -> None:
        txn = self.txn
        if txn.done:
            return
        due = self.last + self.wait
        if due > txn.table.clock.now():
            self.timer = txn.table.hub.call_at(due, self._check)
            return
        wait_expired(self.ref, txn)
        if self.on_expired is not None:
            self.on_expired()


def arm_wait(ref: ActorRef, txn: Transaction) -> TimerHandle | None:
    """A timer failing ``txn`` when ``ref.wait`` seconds pass from now (one wait of an
    iterator for its next item; cancel it when the item comes), or None when ``ref``
    waits forever."""
    if ref.wait is None or txn.done:
        return None
    repace(ref, txn)
    return txn.table.hub.call_at(txn.table.clock.now() + ref.wait, wait_expired, ref, txn)


def repace(ref: ActorRef, txn: Transaction) -> None:
    """Before a wait for a value another thread delivers (a ROS subscriber): anchor the
    virtual clock's wall pacing now, so the wait lasts ``ref.wait`` seconds of wall time
    even when virtual time fell behind wall time earlier (an offload holds it still)."""
    if not ref.hub_only:
        hub = txn.table.hub
        hub.foreign_work_started()
        hub.foreign_work_ended()


def wait_expired(ref: ActorRef, txn: Transaction) -> None:
    """The caller of ``txn`` waited ``ref.wait`` seconds for a value in vain: close the
    stream and fail the call with an ActorTimeout saying what it waited for."""
    if txn.done:
        return
    seconds = float(ref.wait or 0.0)
    detail = ""
    if ref.wait_detail is not None:
        try:
            detail = ref.wait_detail(seconds)
        except Exception:
            log.exception("describing the wait of %s failed", ref.path)
    err = ActorTimeout(ref.path, seconds, detail or f"no value within {seconds:g} s")
    err.transaction_id = txn.id  # this call's own error
    closer, txn.closer = txn.closer, None
    if closer is not None:
        call_quietly(closer)
    txn.finish(TxnState.FAILED, error=err)
