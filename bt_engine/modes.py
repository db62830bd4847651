"""Actor kinds (how an actor is written) and call modes (how it is called).

Strings of the ros_actor-style API (``run_actor_mode(name, 'timed', ...)``) are parsed once into these enums.
"""

from __future__ import annotations

import difflib
import enum
from typing import Any, Callable

from .errors import BadModeError


class Kind(enum.Enum):
    """How an actor is implemented."""

    SYNC = "sync"
    """A plain function returning a value; may block on engine primitives."""
    ASYNC = "async"
    """``impl(done, *args)`` starts work and later calls ``done(result)``; may return a closer."""
    STREAM = "multi"
    """``impl(emit, *args)`` emits values until closed and returns a closer, or a generator."""

    @classmethod
    def parse(cls, value: "str | Kind") -> "Kind":
        if isinstance(value, Kind):
            return value
        kind = _KIND_NAMES.get(value)
        if kind is None:
            raise BadModeError(f"unknown actor kind {value!r}; expected one of: sync, async, multi (or stream)")
        return kind


_KIND_NAMES = {"sync": Kind.SYNC, "async": Kind.ASYNC, "multi": Kind.STREAM, "stream": Kind.STREAM}


class Mode(enum.Enum):
    """How a caller runs an actor."""

    SYNC = "sync"
    """Block the caller until the result (a stream: its next value)."""
    ASYNC = "async"
    """Return a Transaction at once; a callback receives the result."""
    MULTI = "multi"
    """Return a Transaction; a callback receives every value (repeated invocations)."""
    ITERATOR = "iterator"
    """An iterator over repeated invocations or emitted values."""
    TIMED_ITERATOR = "timed_iterator"
    """As ITERATOR, ending at a deadline on the runtime clock."""
    TIMED = "timed"
    """As SYNC with a deadline; raises ActorTimeout."""

    @classmethod
    def parse(cls, value: "str | Mode") -> "Mode":
        if isinstance(value, Mode):
            return value
        try:
            return _MODE_NAMES[value]
        except (KeyError, TypeError):
            close = difflib.get_close_matches(str(value), list(_MODE_NAMES), n=3)
            hint = f" (did you mean {', '.join(close)}?)" if close else ""
            raise BadModeError(
                f"unknown call mode {value!r}{hint}; expected one of: {', '.join(_MODE_NAMES)}"
            ) from None

    def split_args(self, args: tuple) -> "tuple[Callable | None, float | None, tuple]":
        """The ros_actor positional form: ``(callback, seconds, actor arguments)``.

        ``async`` and ``multi`` take the callback first; ``timed`` and ``timed_iterator``
        take the seconds first.
        """
        if self in (Mode.ASYNC, Mode.MULTI):
            if not args or not (args[0] is None or callable(args[0])):
                raise BadModeError(f"mode {self.value!r} needs a callback (or None) before the actor's arguments")
            return args[0], None, args[1:]
        if self in (Mode.TIMED, Mode.TIMED_ITERATOR):
            first: Any = args[0] if args else None
            if not isinstance(first, (int, float)) or isinstance(first, bool):
                raise BadModeError(f"mode {self.value!r} needs the seconds before the actor's arguments")
            return None, float(first), args[1:]
        return None, None, args


#: the enum values, plus the word orders ros_actor programs use ('timed' + a base mode)
_MODE_NAMES = {m.value: m for m in Mode} | {
    "timed_sync": Mode.TIMED,
    "sync_timed": Mode.TIMED,
    "iterator_timed": Mode.TIMED_ITERATOR,
}
