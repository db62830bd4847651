"""actorbt engine. Knows nothing of robots.

Layering (docs/architecture.md): ``bt_engine`` imports none of ``actors``, ``planning`` or ``sim``,
and inside it imports only go downwards, with no cycles; ``tests/test_layering.py``
reads every import (relative, in functions, under TYPE_CHECKING) to keep it so.
The core, bottom to top::

    errors, clock, modes -> actor, hub -> transaction -> outcome, handles -> execution
    -> iterator -> invoke -> external -> api -> subsystem -> runtime -> default

The public surface is re-exported here; everything else is internal.
"""

from .actor import ActorRef, Safety, actor
from .clock import Clock, VirtualClock, WallClock
from .default import (
    check_actor,
    close_default_runtime,
    default_runtime,
    get_value,
    register_subsystem,
    run_actor,
    run_actor_async,
    run_actor_mode,
    set_default_runtime,
    set_value,
)
from .docstrings import param_docs
from .errors import (
    ActorbtError,
    ActorCancelled,
    ActorError,
    ActorTimeout,
    AmbiguousActorError,
    BadArgumentsError,
    BadModeError,
    Cancelled,
    Failure,
    HubBlockingError,
    RuntimeClosedError,
    UnknownActorError,
)
from .modes import Kind, Mode
from .runtime import Runtime, current_runtime
from .signal import Signal
from .subsystem import SubNet, SubSystem
from .transaction import Transaction, TxnState

__all__ = [
    "ActorRef",
    "Safety",
    "ActorbtError",
    "ActorCancelled",
    "ActorError",
    "ActorTimeout",
    "AmbiguousActorError",
    "BadArgumentsError",
    "BadModeError",
    "Cancelled",
    "Clock",
    "Failure",
    "HubBlockingError",
    "Kind",
    "Mode",
    "Runtime",
    "RuntimeClosedError",
    "Signal",
    "SubNet",
    "SubSystem",
    "Transaction",
    "TxnState",
    "UnknownActorError",
    "VirtualClock",
    "WallClock",
    "actor",
    "check_actor",
    "close_default_runtime",
    "current_runtime",
    "default_runtime",
    "get_value",
    "param_docs",
    "register_subsystem",
    "run_actor",
    "run_actor_async",
    "run_actor_mode",
    "set_default_runtime",
    "set_value",
]
