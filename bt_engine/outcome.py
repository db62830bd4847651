"""What a caller sees of a finished transaction: its result, or the one exception that
says why not. Every call mode translates outcomes here, so they all agree.

- timed out: :class:`ActorTimeout`
- cancelled by someone else: :class:`ActorCancelled`
- failed: :class:`BadArgumentsError` (the call did not fit the signature), or
  :class:`ActorError` naming the actor and chaining the original exception
"""

from __future__ import annotations

from typing import Any

import greenlet

from .errors import ActorbtError, ActorCancelled, ActorError, ActorTimeout, Cancelled, Failure
from .transaction import Transaction, TxnState

#: exceptions that end the process or a greenlet; an actor never turns them into failures
PASS_THROUGH = (KeyboardInterrupt, SystemExit, greenlet.GreenletExit, Cancelled)


def is_failure(exc: BaseException) -> bool:
    """True for an exception escaping an actor that fails its call (every exception,
    and custom BaseException subclasses, but not the ones in :data:`PASS_THROUGH`)."""
    return not isinstance(exc, PASS_THROUGH)


def caller_error(txn: Transaction) -> ActorbtError:
    """The exception a caller sees for a transaction that finished without a result.

    It is tagged with the transaction's id (``transaction_id``): an error that already
    describes this transaction passes through, while one from a call it made (even to
    the same actor, recursively) is wrapped, so the call chain stays visible.
    """
    err: ActorbtError
    if txn.state is TxnState.CANCELLED:
        if txn.timed_out:
            err = ActorTimeout(txn.path, (txn.deadline or txn.started) - txn.started)
        else:
            err = ActorCancelled(txn.path, txn.reason or "cancelled")
    else:
        cause = txn.error
        if isinstance(cause, ActorbtError) and cause.transaction_id == txn.id:
            return cause
        err = ActorError(txn.path, cause if cause is not None else RuntimeError("no result"))
        err.__cause__ = cause
    err.transaction_id = txn.id
    return err


def result_or_raise(txn: Transaction) -> Any:
    """The result of a finished transaction, or raise :func:`caller_error`."""
    if txn.state is TxnState.DONE:
        return txn.result
    raise caller_error(txn)


def failure_of(txn: Transaction) -> Failure:
    """What an async callback receives for a transaction that finished without a result."""
    return Failure(caller_error(txn), txn)
