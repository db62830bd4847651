"""Why a goal of ``actorbt serve`` ended, as the ``error_code`` of its result.

The codes are constants of the ``.action`` and ``.srv`` files (``interfaces/``), as in
Nav2: ``NONE = 0`` for success, and each type its own range so that a code names its
action wherever it is logged (RunTree 1000-1099, CallActor 1100-1199, Describe
1200-1299). The server thinks in :class:`Ending`; :func:`error_code` looks the matching
constant up on the result type, so the numbers live in one place, the interface files.
"""

from __future__ import annotations

import enum
from bt_engine.bus.messages import RosMessage

__all__ = ["Ending", "REFUSED", "error_code", "ending_of"]


class Ending(enum.Enum):
    """Why a goal ended; the value is the constant's name on the result type."""

    SUCCEEDED = "NONE"
    INVALID_GOAL = "INVALID_GOAL"  # bad YAML, unknown input or actor, wrong type
    BUSY = "BUSY"  # the tree runs another goal
    FAILED = "FAILED"  # TREE_FAILED / ACTOR_FAILED
    CANCELED = "CANCELED"  # the client asked
    PREEMPTED = "PREEMPTED"  # a newer goal for the same tree
    SHUTDOWN = "SHUTDOWN"  # the server (or its runtime) is closing
    TREE_REMOVED = "TREE_REMOVED"  # the tree's file left the watched folder
    TIMEOUT = "TIMEOUT"  # a service call took too long
    UNKNOWN = "UNKNOWN"


#: endings of goals that never ran: clients tell them as refused (``actorbt goal`` exit 2)
REFUSED = (Ending.INVALID_GOAL, Ending.BUSY)

#: the failure constant of each result type, tried in order
_FAILED_NAMES = ("TREE_FAILED", "ACTOR_FAILED")


def error_code(result_type: type[RosMessage], ending: Ending) -> int:
    """The ``error_code`` constant for ``ending`` on ``result_type`` (a Result or
    Response class); ``UNKNOWN`` when the type has no such constant."""
    code = _constant(result_type, ending)
    if code is None:
        code = _constant(result_type, Ending.UNKNOWN)
    return code or 0


def ending_of(result_type: type[RosMessage], code: int) -> Ending:
    """The :class:`Ending` a result's ``error_code`` stands for (clients)."""
    for ending in Ending:
        if _constant(result_type, ending) == code:
            return ending
    return Ending.UNKNOWN


def _constant(result_type: type[RosMessage], ending: Ending) -> int | None:
    names = _FAILED_NAMES if ending is Ending.FAILED else (ending.value,)
    for name in names:
        code = getattr(result_type, name, None)
        if isinstance(code, int):
            return code
    return None
