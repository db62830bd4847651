"""actorbt engine. Knows nothing of robots.

Layering (DESIGN.md): ``bt_engine`` imports none of ``actors``, ``planning`` or ``sim``;
a test reads the imports to keep it so. The public surface is re-exported here.
"""
from .actor import ActorRef, actor
from .clock import Clock, VirtualClock, WallClock
from .errors import (ActorbtError, ActorCancelled, ActorError, ActorTimeout,
                     AmbiguousActorError, BadArgumentsError, BadModeError, Cancelled, Failure,
                     HubBlockingError, RuntimeClosedError, UnknownActorError)
from .modes import Kind, Mode
from .runtime import Runtime, current_runtime
from .signal import Signal
from .subsystem import SubNet, SubSystem
from .transaction import Transaction, TxnState

__all__ = [
    "ActorRef", "ActorbtError", "ActorCancelled", "ActorError", "ActorTimeout",
    "AmbiguousActorError", "BadArgumentsError", "BadModeError", "Cancelled", "Clock",
    "Failure", "HubBlockingError", "Kind", "Mode", "Runtime", "RuntimeClosedError", "Signal",
    "SubNet", "SubSystem", "Transaction", "TxnState", "UnknownActorError", "VirtualClock",
    "WallClock", "actor", "current_runtime",
]
