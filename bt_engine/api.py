"""The calling API shared by SubSystem, SubNet and Runtime: the proposal's names
(``run_actor``, ``run_actor_mode``, ...) and the keyword-only ones (``call``, ``start``,
``stream``). Each resolves names from its own scope."""
from __future__ import annotations

import contextlib
from typing import TYPE_CHECKING, Any, Callable, Iterator

from .errors import BadModeError
from .modes import Mode

if TYPE_CHECKING:
    from .runtime import Runtime
    from .subsystem import SubSystem
    from .transaction import Transaction


class CallApi:
    """Mixin: call actors by name, resolved from ``self._call_scope()``."""

    _rt: "Runtime"

    def _call_scope(self) -> "SubSystem":  # pragma: no cover - overridden
        raise NotImplementedError

    def _dispatch(self, name: str, mode: Mode, args: tuple, kwargs: dict,
                  cb: Callable | None = None, seconds: float | None = None) -> Any:
        rt = self._rt
        if rt.hub.thread_id == _get_ident():
            from .invoke import dispatch
            return dispatch(rt, self._call_scope().resolve(name), mode, args, kwargs, cb, seconds)
        return rt._external(self._call_scope(), name, mode, args, kwargs, cb, seconds)

    # -- the proposal's API ----------------------------------------------------------
    def run_actor(self, name: str, /, *args: Any, **kwargs: Any) -> Any:
        """Call actor ``name`` synchronously and return its result."""
        return self._dispatch(name, Mode.SYNC, args, kwargs)

    def run_actor_mode(self, name: str, mode: "str | Mode", /, *args: Any, **kwargs: Any) -> Any:
        """Call actor ``name`` in ``mode``.

        ``'async'`` and ``'multi'`` take the callback first; ``'timed'`` and
        ``'timed_iterator'`` take the seconds first; the actor's arguments follow.
        """
        m = Mode.parse(mode)
        cb = seconds = None
        if m in (Mode.ASYNC, Mode.MULTI):
            if not args or not (args[0] is None or callable(args[0])):
                raise BadModeError(f"mode {m.value!r} needs a callback (or None) before the "
                                   "actor's arguments")
            cb, args = args[0], args[1:]
        elif m in (Mode.TIMED, Mode.TIMED_ITERATOR):
            if not args or not isinstance(args[0], (int, float)) or isinstance(args[0], bool):
                raise BadModeError(f"mode {m.value!r} needs the seconds before the actor's arguments")
            seconds, args = float(args[0]), args[1:]
        return self._dispatch(name, m, args, kwargs, cb, seconds)

    def run_actor_async(self, name: str, callback: Callable[[Any], Any] | None, /, *args: Any,
                        **kwargs: Any) -> "Transaction":
        """Start actor ``name``; ``callback(result)`` (or a Failure) when it finishes."""
        return self._dispatch(name, Mode.ASYNC, args, kwargs, callback)

    def check_actor(self, name: str) -> bool:
        """True when ``name`` resolves to exactly one actor from this scope."""
        from .errors import ActorbtError
        try:
            self._call_scope().resolve(name)
        except ActorbtError:
            return False
        return True

    def transactions(self) -> list["Transaction"]:
        """The live transactions, oldest first."""
        return self._rt.transactions()

    # -- keyword-only API --------------------------------------------------------------
    def call(self, name: str, /, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        """Call ``name`` and return its result; with ``timeout`` [s] raise ActorTimeout."""
        mode = Mode.SYNC if timeout is None else Mode.TIMED
        return self._dispatch(name, mode, args, kwargs, None, timeout)

    def start(self, name: str, /, *args: Any, on_done: Callable[[Any], Any] | None = None,
              **kwargs: Any) -> "Transaction":
        """Start ``name`` and return its Transaction; ``on_done(result | Failure)``."""
        return self._dispatch(name, Mode.ASYNC, args, kwargs, on_done)

    @contextlib.contextmanager
    def stream(self, name: str, /, *args: Any, timeout: float | None = None,
               **kwargs: Any) -> Iterator[Iterator[Any]]:
        """``with x.stream(name) as it: for v in it: ...``; ``timeout`` [s] ends it."""
        mode = Mode.ITERATOR if timeout is None else Mode.TIMED_ITERATOR
        it = self._dispatch(name, mode, args, kwargs, None, timeout)
        try:
            yield it
        finally:
            it.close()


from threading import get_ident as _get_ident  # noqa: E402  (hot path: a local name)
