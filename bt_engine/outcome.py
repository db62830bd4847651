"""What a caller sees of a finished transaction: its result, or the one exception that
says why not. Every call mode translates outcomes here, so they all agree.

- timed out: :class:`ActorTimeout`
- cancelled by someone else: :class:`ActorCancelled`
- failed: :class:`BadArgumentsError`, or :class:`ActorError` naming the actor and
  chaining the original exception
"""
from __future__ import annotations

from typing import Any

import greenlet

from .errors import (ActorbtError, ActorCancelled, ActorError, ActorTimeout,
                     BadArgumentsError, Cancelled, Failure)
from .transaction import Transaction, TxnState

#: exceptions that end the process or a greenlet; an actor never turns them into failures
PASS_THROUGH = (KeyboardInterrupt, SystemExit, greenlet.GreenletExit, Cancelled)


def is_failure(exc: BaseException) -> bool:
    """True for an exception escaping an actor that fails its call (every exception,
    and custom BaseException subclasses, but not the ones in :data:`PASS_THROUGH`)."""
    return not isinstance(exc, PASS_THROUGH)


def caller_error(txn: Transaction) -> ActorbtError:
    """The exception a caller sees for a transaction that finished without a result."""
    if txn.state is TxnState.CANCELLED:
        if txn.timed_out:
            return ActorTimeout(txn.path, (txn.deadline or txn.started) - txn.started)
        return ActorCancelled(txn.path, txn.reason or "cancelled")
    err = txn.error
    if isinstance(err, (ActorError, BadArgumentsError)) and getattr(err, "path", None) == txn.path:
        return err
    wrapped = ActorError(txn.path, err if err is not None else RuntimeError("no result"))
    wrapped.__cause__ = err
    return wrapped


def result_or_raise(txn: Transaction) -> Any:
    """The result of a finished transaction, or raise :func:`caller_error`."""
    if txn.state is TxnState.DONE:
        return txn.result
    raise caller_error(txn)


def failure_of(txn: Transaction) -> Failure:
    """What an async callback receives for a transaction that finished without a result."""
    return Failure(caller_error(txn), txn)
