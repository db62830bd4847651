"""The call-mode matrix: every mode (how a caller runs an actor) for every kind (how the
actor is written). See DESIGN.md, "Call modes".

All functions here run on the hub thread. Blocking modes need a task (a greenlet);
``Runtime`` routes calls from other threads through the hub first.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from .errors import (ActorCancelled, ActorError, ActorTimeout, BadArgumentsError,
                     Cancelled, Failure)
from .hub import Task, Waiter
from .modes import Kind, Mode
from .streams import ActorIterator, Done, Emitter
from .transaction import Transaction, TxnState

if TYPE_CHECKING:
    from .actor import ActorRef
    from .runtime import Runtime

#: what a sync call raises for its caller when the callee failed, timed out or was cancelled
_CALL_ERRORS = (ActorError, ActorTimeout, ActorCancelled, BadArgumentsError)


def dispatch(rt: "Runtime", ref: "ActorRef", mode: Mode, args: tuple, kwargs: dict,
             cb: Callable | None = None, seconds: float | None = None) -> Any:
    """Run ``ref`` in ``mode``. Returns the result, a Transaction or an iterator."""
    if mode is Mode.SYNC:
        return call_sync(rt, ref, args, kwargs, None)
    if mode is Mode.ASYNC:
        return start_async(rt, ref, args, kwargs, cb)
    if mode is Mode.TIMED:
        return call_sync(rt, ref, args, kwargs, seconds)
    if mode is Mode.MULTI:
        return start_multi(rt, ref, args, kwargs, cb)
    return ActorIterator(rt, ref, args, kwargs, seconds if mode is Mode.TIMED_ITERATOR else None)


def current_txn(rt: "Runtime") -> Transaction | None:
    task = rt.hub.current_task()
    if task is not None and task.txns:
        return task.txns[-1]
    return None


# -- executing a sync-kind body --------------------------------------------------------
def run_body(ref: "ActorRef", txn: Transaction, task: Task, args: tuple, kwargs: dict) -> Any:
    """Run a sync-kind actor's body in ``task`` under ``txn`` and translate its outcome.

    Returns the result; raises ActorError / BadArgumentsError / ActorTimeout /
    ActorCancelled for the caller, or re-raises a Cancelled aimed at an outer transaction.
    """
    task.txns.append(txn)
    try:
        task.raise_pending()
        result = ref.fn(*args, **kwargs)
    except Cancelled as c:
        _drop_pending(task, txn)
        txn.finish(TxnState.CANCELLED, error=c)
        if c.transaction is txn:
            if txn.timed_out:
                raise ActorTimeout(ref.path, (txn.deadline or 0.0) - txn.started) from None
            raise ActorCancelled(ref.path, c.reason) from None
        raise
    except TypeError as e:
        err: Exception = _bad_args(ref, args, kwargs) or ActorError(ref.path, e)
        txn.finish(TxnState.FAILED, error=err)
        if isinstance(err, BadArgumentsError):
            raise err from None
        raise err from e
    except Exception as e:
        txn.finish(TxnState.FAILED, error=e)
        raise ActorError(ref.path, e) from e
    except BaseException as e:  # GreenletExit, KeyboardInterrupt: pass through
        txn.finish(TxnState.FAILED, error=e)
        raise
    else:
        _drop_pending(task, txn)
        txn.finish(TxnState.DONE, result)
        return result
    finally:
        task.txns.pop()


def _drop_pending(task: Task, txn: Transaction) -> None:
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


def _bad_args(ref: "ActorRef", args: tuple, kwargs: dict) -> BadArgumentsError | None:
    try:
        ref.check_args(args, kwargs)
    except BadArgumentsError as e:
        return e
    return None


def outcome_for_caller(txn: Transaction, seconds: float | None = None) -> Any:
    """The result of a finished transaction, or the exception its sync caller sees."""
    st = txn.state
    if st is TxnState.DONE:
        return txn.result
    if st is TxnState.FAILED:
        err = txn.error
        if isinstance(err, (BadArgumentsError, ActorError)) and getattr(err, "path", None) == txn.path:
            raise err
        raise ActorError(txn.path, err) from err  # type: ignore[arg-type]
    if txn.timed_out:
        raise ActorTimeout(txn.path, seconds if seconds is not None else 0.0)
    raise ActorCancelled(txn.path, txn.reason or "cancelled")


# -- sync and timed --------------------------------------------------------------------
def call_sync(rt: "Runtime", ref: "ActorRef", args: tuple, kwargs: dict,
              seconds: float | None) -> Any:
    task = rt.hub.require_task(f"a sync call of {ref.path}")
    parent = task.txns[-1] if task.txns else None
    mode = Mode.SYNC if seconds is None else Mode.TIMED
    if ref.kind is Kind.SYNC or ref.is_generator:
        txn = Transaction(rt, ref.path, parent, mode, ref.owner, task, args)
        if seconds is not None:
            txn.set_deadline(seconds)
        body_ref = _GenFirst(ref) if ref.is_generator else ref
        return run_body(body_ref, txn, task, args, kwargs)  # type: ignore[arg-type]
    ref.check_args(args, kwargs)
    txn = Transaction(rt, ref.path, parent, mode, ref.owner, None, args)
    w = Waiter(task)
    txn.add_done_callback(lambda t: w.wake())
    if seconds is not None:
        txn.set_deadline(seconds)
    if ref.kind is Kind.ASYNC:
        _start_callback_impl(ref, txn, args, kwargs)
    else:
        _start_emit_impl(ref, txn, args, kwargs, first_only=True, on_value=None)
    try:
        w.wait()
    finally:
        if not txn.done:  # our caller was cancelled while waiting
            txn.cancel("caller cancelled")
    return outcome_for_caller(txn, seconds)


class _GenFirst:
    """Adapts a generator actor so its body returns the first yielded value (sync and
    async modes of a stream)."""

    def __init__(self, ref: "ActorRef") -> None:
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


def _start_callback_impl(ref: "ActorRef", txn: Transaction, args: tuple, kwargs: dict,
                         on_result: Callable[[Any], None] | None = None) -> None:
    """Start an async-kind implementation; ``done(result)`` finishes ``txn``."""
    _call_impl(ref, txn, Done(txn, on_result), args, kwargs)


def _start_emit_impl(ref: "ActorRef", txn: Transaction, args: tuple, kwargs: dict,
                     first_only: bool, on_value: Callable[[Any], None] | None) -> None:
    """Start an emit-style stream; with ``first_only`` the first value finishes ``txn``."""
    def push(value: Any) -> None:
        if txn.done:
            return
        if first_only:
            closer = txn.closer
            txn.closer = None
            txn.finish(TxnState.DONE, value)
            if closer is not None:
                _call_quietly(closer)
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

    _call_impl(ref, txn, Emitter(txn.rt, push, end), args, kwargs)


def _call_impl(ref: "ActorRef", txn: Transaction, handle: Any, args: tuple, kwargs: dict) -> None:
    """Call an async or stream implementation with its ``done``/``emit`` handle and keep
    the closer it returns (or call it at once if the work already finished)."""
    try:
        closer = ref.fn(handle, *args, **kwargs)
    except Exception as e:
        txn.finish(TxnState.FAILED, error=_bad_args(ref, args, kwargs) or e)
        return
    if callable(closer):
        if txn.done:
            _call_quietly(closer)
        else:
            txn.closer = closer


def _call_quietly(fn: Callable[[], Any]) -> None:
    try:
        fn()
    except Exception:
        import logging
        logging.getLogger("actorbt").exception("closer %r raised", fn)


# -- async -------------------------------------------------------------------------------
def _notify(cb: Callable | None, txn: Transaction) -> None:
    if cb is not None:
        txn.add_done_callback(lambda t: cb(t.result if t.state is TxnState.DONE else _failure(t)))


def _failure(txn: Transaction) -> Failure:
    err = txn.error
    if txn.state is TxnState.CANCELLED:
        if txn.timed_out:
            err = ActorTimeout(txn.path, (txn.deadline or 0.0) - txn.started)
        else:
            err = ActorCancelled(txn.path, txn.reason or "cancelled")
    elif not isinstance(err, (ActorError, BadArgumentsError)):
        wrapped = ActorError(txn.path, err)  # type: ignore[arg-type]
        wrapped.__cause__ = err
        err = wrapped
    return Failure(err, txn)  # type: ignore[arg-type]


def spawn(rt: "Runtime", ref: "ActorRef", mode: Mode, args: tuple, kwargs: dict,
          body: Callable[[Task, Transaction], Any]) -> Transaction:
    """Run ``body(task, txn)`` in a new task under a new transaction."""
    hub = rt.hub
    parent = current_txn(rt)

    def main() -> None:
        try:
            body(task, txn)
        except (Exception, Cancelled):
            pass  # already recorded on txn by run_body
        finally:
            if not txn.done:  # a body that ended without finishing (a cancelled stream)
                txn.finish(TxnState.CANCELLED, error=Cancelled(txn, txn.reason or "cancelled"))

    task = Task(hub, main)
    txn = Transaction(rt, ref.path, parent, mode, ref.owner, task, args)
    hub.ready.append((hub.switch_to, (task,)))
    return txn


def start_async(rt: "Runtime", ref: "ActorRef", args: tuple, kwargs: dict,
                cb: Callable | None) -> Transaction:
    if ref.kind is Kind.SYNC or ref.is_generator:
        body_ref = _GenFirst(ref) if ref.is_generator else ref
        txn = spawn(rt, ref, Mode.ASYNC, args, kwargs,
                    lambda task, txn: run_body(body_ref, txn, task, args, kwargs))
        _notify(cb, txn)
        return txn
    ref.check_args(args, kwargs)
    txn = Transaction(rt, ref.path, current_txn(rt), Mode.ASYNC, ref.owner, None, args)
    _notify(cb, txn)
    if ref.kind is Kind.ASYNC:
        _start_callback_impl(ref, txn, args, kwargs)
    else:
        _start_emit_impl(ref, txn, args, kwargs, first_only=True, on_value=None)
    return txn


# -- multi -------------------------------------------------------------------------------
def start_multi(rt: "Runtime", ref: "ActorRef", args: tuple, kwargs: dict,
                cb: Callable | None) -> Transaction:
    """Call ``cb`` with every value until the transaction is cancelled or the stream ends."""
    emit = cb if cb is not None else (lambda v: None)
    if ref.kind is Kind.SYNC:
        def repeat(task: Task, txn: Transaction) -> None:
            hub = rt.hub
            while True:
                child = Transaction(rt, ref.path, txn, Mode.SYNC, ref.owner, task, args)
                try:
                    value = run_body(ref, child, task, args, kwargs)
                except _CALL_ERRORS as e:
                    txn.finish(TxnState.FAILED, error=e)
                    emit(Failure(e, txn))
                    return
                emit(value)
                hub.yield_now()  # let others run between invocations
        return _spawn_root(rt, ref, Mode.MULTI, args, kwargs, repeat)
    if ref.is_generator:
        def pull(task: Task, txn: Transaction) -> None:
            gen = ref.fn(*args, **kwargs)
            try:
                for value in gen:
                    emit(value)
            except Exception as e:
                txn.finish(TxnState.FAILED, error=e)
                emit(_failure(txn))
                return
            finally:
                gen.close()
            txn.finish(TxnState.DONE, None)
        return _spawn_root(rt, ref, Mode.MULTI, args, kwargs, pull)
    ref.check_args(args, kwargs)
    txn = Transaction(rt, ref.path, current_txn(rt), Mode.MULTI, ref.owner, None, args)
    if ref.kind is Kind.STREAM:
        _start_emit_impl(ref, txn, args, kwargs, first_only=False, on_value=emit)
        if txn.state is TxnState.FAILED and cb is not None:
            cb(_failure(txn))
        return txn

    def again(value: Any) -> None:
        emit(value)
        if not txn.done:
            rt.hub.call_soon(restart)

    def restart() -> None:
        if not txn.done:
            _start_callback_impl(ref, txn, args, kwargs, on_result=again)
            if txn.state is TxnState.FAILED and cb is not None:
                cb(_failure(txn))
    restart()
    return txn


def _spawn_root(rt: "Runtime", ref: "ActorRef", mode: Mode, args: tuple, kwargs: dict,
                body: Callable[[Task, Transaction], None]) -> Transaction:
    def wrapped(task: Task, txn: Transaction) -> None:
        task.txns.append(txn)
        try:
            task.raise_pending()
            body(task, txn)
        except Cancelled as c:
            _drop_pending(task, txn)
            txn.finish(TxnState.CANCELLED, error=c)
        finally:
            task.txns.pop()
    return spawn(rt, ref, mode, args, kwargs, wrapped)

