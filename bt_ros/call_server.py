"""The CallActor action, ``/actorbt/call``: call any actor of the runtime.

``actor`` names it (resolved as from the root); ``args_yaml`` holds its arguments (see
:func:`bt_ros.goals.parse_call_args`). The result carries ``result_yaml``, the
returned value as YAML, or ``error_code`` and ``error_msg``, the failure (an unknown
actor or bad arguments: ``INVALID_GOAL``, the goal aborted at once). Goals run
concurrently; the feedback is ``running`` when the call starts and ``success`` or
``failure`` before the result, each with ``elapsed``. ``actorbt serve`` prints one line
per call when it ends (or is refused): the actor and its arguments, the outcome, the time.
"""

from __future__ import annotations

from typing import Iterable

from bt_engine.bus.messages import RosMessage

from .goal_server import GoalServer, one_line
from .goals import GoalError, Invocation, decode_call_goal, parse_call_args
from .rostypes import Value
from .yamlio import dump

__all__ = ["CallServer"]


class CallServer(GoalServer):
    """``/actorbt/call`` (see the module docstring)."""

    label = "call"
    announce_accepted = False  # one line per call, when it ends

    def describe(self, call: Invocation) -> str:
        return _call_text(call.path, call.args, call.kwargs)

    def describe_request(self, goal: RosMessage) -> str:
        name = goal.actor.strip() or "(no actor)"
        try:
            args, kwargs = parse_call_args(goal.args_yaml)
        except GoalError:  # shown as sent
            text = one_line(goal.args_yaml)
            return f"{name} {text}" if text else name
        return _call_text(name, args, kwargs)

    def admit(self, goal: RosMessage) -> Invocation:
        return decode_call_goal(self.owner.rt, goal.actor, goal.args_yaml)

    def result(self, success: bool, status: str, value: Value, error: str, code: int) -> RosMessage:
        res = self.action_type.Result()
        res.success = success
        res.result_yaml = dump(value) if success else ""
        res.error_code = code
        res.error_msg = error
        return res


def _call_text(name: str, args: Iterable[object], kwargs: dict[str, object]) -> str:
    """``name(1.0, 'a', k=2)``, cut to one line."""
    shown = [repr(a) for a in args] + [f"{k}={v!r}" for k, v in kwargs.items()]
    return f"{name}({one_line(', '.join(shown))})"
