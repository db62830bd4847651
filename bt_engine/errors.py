"""Every error the engine raises derives from :class:`ActorbtError`.

``Cancelled`` is the one exception that does not: it derives from ``BaseException`` so that
``except Exception`` in actor code cannot swallow a cancellation.
"""

from __future__ import annotations

import difflib
import inspect
from typing import Any, Iterable


class ActorbtError(Exception):
    """Root of every error raised by actorbt."""

    #: the id of the call (transaction) whose own error this is, set when the error is
    #: raised for that call (see :func:`bt_engine.outcome.caller_error`); None otherwise
    transaction_id: int | None = None


class UnknownActorError(ActorbtError, LookupError):
    """No actor of that name is visible from the caller's scope."""

    def __init__(self, name: str, known: Iterable[str], scope: str = "") -> None:
        self.name = name
        self.suggestions = difflib.get_close_matches(name, sorted(set(known)), n=5, cutoff=0.5)
        where = f" from {scope!r}" if scope else ""
        hint = f"; did you mean: {', '.join(self.suggestions)}?" if self.suggestions else ""
        super().__init__(f"unknown actor {name!r}{where}{hint}")


class AmbiguousActorError(ActorbtError, LookupError):
    """A name is defined in two sibling subsystems and was looked up above them."""

    def __init__(self, name: str, paths: Iterable[str]) -> None:
        self.name = name
        self.paths = sorted(paths)
        super().__init__(
            f"actor name {name!r} is ambiguous here; use one of the absolute paths: " + ", ".join(self.paths)
        )


class BadArgumentsError(ActorbtError, TypeError):
    """The arguments do not fit the actor's signature."""

    def __init__(self, path: str, signature: inspect.Signature, reason: str) -> None:
        self.path = path
        self.signature = signature
        super().__init__(f"bad arguments for actor {path}{signature}: {reason}")


class BadModeError(ActorbtError, ValueError):
    """A call-mode or actor-kind string that does not exist."""


#: the longest message text an error repeats from its cause [characters]
MESSAGE_LIMIT = 300


def shorten(text: str, limit: int = MESSAGE_LIMIT) -> str:
    """``text`` cut to ``limit`` characters by eliding its middle."""
    if len(text) <= limit:
        return text
    keep = (limit - 5) // 2
    return f"{text[:keep]} ... {text[-keep:]}"


def _path_chain(paths: list[str], limit: int = 6) -> str:
    if len(paths) > limit:
        hidden = len(paths) - limit + 2
        paths = paths[: limit // 2] + [f"... {hidden} more ..."] + paths[-(limit // 2 - 1) :]
    return " -> ".join(paths)


class ActorError(ActorbtError):
    """An exception escaped an actor. ``__cause__`` holds the original exception.

    Attributes: ``path`` (the actor that failed), ``cause`` (what escaped it: the
    exception, or the ActorError of an actor it called), ``root_cause`` (the innermost
    exception of a chain of failed calls) and ``call_chain`` (the actor paths from this
    one down to where the failure started).

    The message stays short however deep the chain: the call chain (elided in the
    middle) and the innermost cause.
    """

    def __init__(self, path: str, cause: BaseException) -> None:
        self.path = path
        self.cause = cause
        inner = cause if isinstance(cause, ActorError) else None
        self.call_chain: list[str] = [path] + (inner.call_chain if inner else [])
        self.root_cause: BaseException = inner.root_cause if inner else cause
        root = self.root_cause
        super().__init__(f"actor {_path_chain(self.call_chain)} failed: {type(root).__name__}: {shorten(str(root))}")


class ActorTimeout(ActorbtError, TimeoutError):
    """A call with a deadline did not finish before it, or a stream's caller waited
    longer than the stream's ``wait`` for its next value (a subscriber whose topic is
    silent); ``detail`` then says what was waited for."""

    def __init__(self, path: str, seconds: float, detail: str = "") -> None:
        self.path = path
        self.seconds = seconds
        self.detail = detail
        super().__init__(f"actor {path}: {detail}" if detail else f"actor {path} did not finish within {seconds:g} s")


class ActorCancelled(ActorbtError):
    """The transaction a caller was waiting on was cancelled by someone else."""

    def __init__(self, path: str, reason: str) -> None:
        self.path = path
        self.reason = reason
        super().__init__(f"actor {path} was cancelled: {reason}")


class HubBlockingError(ActorbtError, RuntimeError):
    """A blocking call was made where blocking is impossible (a hub callback)."""


class RuntimeClosedError(ActorbtError, RuntimeError):
    """The runtime was closed."""


class Cancelled(BaseException):
    """Raised at the next blocking point of a cancelled transaction.

    Carries the transaction that was cancelled (``transaction``) and who or why
    (``reason``), like trio's Cancelled.
    """

    def __init__(self, transaction: Any = None, reason: str = "cancelled") -> None:
        self.transaction = transaction
        self.reason = reason
        super().__init__(reason)


class Failure:
    """What an async callback receives instead of a result when the call failed.

    A ``Failure`` is falsy, so ``if result:`` reads naturally in callbacks, and it
    carries the exception (``exception``) and the transaction.
    """

    __slots__ = ("exception", "transaction")

    def __init__(self, exception: BaseException, transaction: Any = None) -> None:
        self.exception = exception
        self.transaction = transaction

    def __bool__(self) -> bool:
        return False

    @property
    def cancelled(self) -> bool:
        return isinstance(self.exception, (Cancelled, ActorCancelled))

    def __repr__(self) -> str:
        return f"Failure({self.exception!r})"
