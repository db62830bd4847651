"""The calling API shared by SubSystem, SubNet and Runtime: ros_actor's names
(``run_actor``, ``run_actor_mode``, ...) and the keyword-only ones (``call``, ``start``,
``stream``). Each resolves names from its own scope."""

from __future__ import annotations

import contextlib
from threading import get_ident
from typing import Any, Callable, Iterator

from .errors import ActorbtError
from .external import call_from_thread
from .invoke import dispatch
from .modes import Mode
from .transaction import Transaction, TransactionTable


class CallApi:
    """Mixin: call actors by name, resolved from ``self._call_scope()`` (an object with
    ``resolve(name)``), on the runtime's transaction table ``self._txns()``."""

    def _call_scope(self) -> Any:  # pragma: no cover - overridden
        raise NotImplementedError

    def _txns(self) -> TransactionTable:  # pragma: no cover - overridden
        raise NotImplementedError

    def _dispatch(
        self, name: str, mode: Mode, args: tuple, kwargs: dict, cb: Callable | None = None, seconds: float | None = None
    ) -> Any:
        table = self._txns()
        if table.hub.thread_id == get_ident():
            return dispatch(table, self._call_scope().resolve(name), mode, args, kwargs, cb, seconds)
        return call_from_thread(table, self._call_scope(), name, mode, args, kwargs, cb, seconds)

    # -- ros_actor's API --------------------------------------------------------------
    def run_actor(self, name: str, /, *args: Any, **kwargs: Any) -> Any:
        """Call actor ``name`` synchronously and return its result."""
        return self._dispatch(name, Mode.SYNC, args, kwargs)

    def run_actor_mode(self, name: str, mode: "str | Mode", /, *args: Any, **kwargs: Any) -> Any:
        """Call actor ``name`` in ``mode``.

        ``'async'`` and ``'multi'`` take the callback first; ``'timed'`` and
        ``'timed_iterator'`` take the seconds first; the actor's arguments follow.
        """
        m = Mode.parse(mode)
        cb, seconds, args = m.split_args(args)
        return self._dispatch(name, m, args, kwargs, cb, seconds)

    def run_actor_async(
        self, name: str, callback: Callable[[Any], Any] | None, /, *args: Any, **kwargs: Any
    ) -> Transaction:
        """Start actor ``name``; ``callback(result)`` (or a Failure) when it finishes."""
        return self._dispatch(name, Mode.ASYNC, args, kwargs, callback)

    def check_actor(self, name: str) -> bool:
        """True when ``name`` resolves to exactly one actor from this scope."""
        try:
            self._call_scope().resolve(name)
        except ActorbtError:
            return False
        return True

    def transactions(self) -> list[Transaction]:
        """The live transactions, oldest first."""
        return list(self._txns().live.values())

    # -- keyword-only API --------------------------------------------------------------
    def call(self, name: str, /, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        """Call ``name`` and return its result; with ``timeout`` [s] raise ActorTimeout."""
        mode = Mode.SYNC if timeout is None else Mode.TIMED
        return self._dispatch(name, mode, args, kwargs, None, timeout)

    def start(
        self, name: str, /, *args: Any, on_done: Callable[[Any], Any] | None = None, **kwargs: Any
    ) -> Transaction:
        """Start ``name`` and return its Transaction; ``on_done(result | Failure)``."""
        return self._dispatch(name, Mode.ASYNC, args, kwargs, on_done)

    @contextlib.contextmanager
    def stream(self, name: str, /, *args: Any, timeout: float | None = None, **kwargs: Any) -> Iterator[Iterator[Any]]:
        """``with x.stream(name) as it: for v in it: ...``; ``timeout`` [s] ends it."""
        mode = Mode.ITERATOR if timeout is None else Mode.TIMED_ITERATOR
        it = self._dispatch(name, mode, args, kwargs, None, timeout)
        try:
            yield it
        finally:
            it.close()
