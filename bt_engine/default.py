"""The module-level API (ros_actor's names), over one default runtime.

A ros_actor-style program runs by changing only its imports::

    from bt_engine import SubSystem, actor, register_subsystem, run_actor

    register_subsystem("camera", Camera)
    print(run_actor("pic_find"))

The default runtime is made on first use (virtual clock, local bus; or the one given
to :func:`set_default_runtime`) and closed when the interpreter exits. Explicit
:class:`Runtime` objects stay the normal way: this module is the one exception to "no
module-level state", a thin layer over that single instance.

Called from inside an actor, these functions act on the runtime running that actor.
"""

from __future__ import annotations

import atexit
import threading
from typing import Any, Callable

from .errors import ActorbtError
from .modes import Mode
from .runtime import Runtime, current_runtime
from .subsystem import SubSystem
from .transaction import Transaction

_lock = threading.Lock()
_default: Runtime | None = None
_exit_hook_installed = False


def _close_at_exit() -> None:
    global _exit_hook_installed
    if not _exit_hook_installed:
        atexit.register(close_default_runtime)
        _exit_hook_installed = True


def default_runtime() -> Runtime:
    """The default runtime, made now if there is none (or the last one was closed)."""
    global _default
    with _lock:
        if _default is None or _default.closed:
            _default = Runtime()
            _close_at_exit()
        return _default


def set_default_runtime(rt: Runtime | None) -> None:
    """Use ``rt`` as the default runtime (None: make a fresh one on next use); it is
    closed at exit like one made here. The runtime it replaces is closed now."""
    global _default
    with _lock:
        old, _default = _default, rt
        _close_at_exit()
    if old is not None and old is not rt and not old.closed:
        old.close()


def close_default_runtime() -> None:
    """Close the default runtime, if one was made (runs at interpreter exit)."""
    global _default
    with _lock:
        rt, _default = _default, None
    if rt is not None:
        rt.close()


def _here() -> Runtime:
    """The runtime of the actor running now, else the default one."""
    try:
        return current_runtime()
    except ActorbtError:  # not inside an actor
        return default_runtime()


def register_subsystem(name: str, cls: type[SubSystem], *args: Any, **kwargs: Any) -> SubSystem:
    """Create subsystem ``name`` of class ``cls`` under the root of the default runtime."""
    return _here().add_subsystem(name, cls, *args, **kwargs)


def run_actor(name: str, /, *args: Any, **kwargs: Any) -> Any:
    """Call actor ``name`` synchronously and return its result."""
    return _here().run_actor(name, *args, **kwargs)


def run_actor_mode(name: str, mode: "str | Mode", /, *args: Any, **kwargs: Any) -> Any:
    """Call actor ``name`` in ``mode`` (see :meth:`Runtime.run_actor_mode`)."""
    return _here().run_actor_mode(name, mode, *args, **kwargs)


def run_actor_async(name: str, callback: Callable[[Any], Any] | None, /, *args: Any, **kwargs: Any) -> Transaction:
    """Start actor ``name``; ``callback(result)`` (or a Failure) when it finishes."""
    return _here().run_actor_async(name, callback, *args, **kwargs)


def check_actor(name: str) -> bool:
    """True when ``name`` names exactly one actor of the default runtime."""
    return _here().check_actor(name)


def get_value(key: str, default: Any = None) -> Any:
    """A persistent value of the root scope (None, or ``default``, when missing)."""
    return _here().root.get_value(key, default)


def set_value(key: str, value: Any) -> None:
    """Store a persistent value in the root scope."""
    rt = _here()
    rt.run_on_hub(rt.root.set_value, key, value)
