"""The CallActor action, ``/actorbt/call``: call any actor of the runtime.

``actor`` names it (resolved as from the root); ``args_yaml`` holds its arguments (see
:func:`bt_engine.ros.goals.parse_call_args`). The result carries ``result_yaml``, the
returned value as YAML, or ``error``, the failure. Goals run concurrently; the only
feedback is ``running`` when the call starts.
"""
from __future__ import annotations

from typing import Any

from .goal_server import GoalServer
from .goals import Invocation, decode_call_goal
from .yamlio import dump

__all__ = ["CallServer"]


class CallServer(GoalServer):
    """``/actorbt/call`` (see the module docstring)."""

    def admit(self, goal: Any) -> Invocation:
        return decode_call_goal(self.owner.rt, goal.actor, goal.args_yaml)

    def result(self, success: bool, status: str, value: Any, error: str) -> Any:
        res = self.action_type.Result()
        res.success = success
        res.result_yaml = dump(value) if success else ""
        res.error = error
        return res
