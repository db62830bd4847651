"""Actions on the bus: a server takes goals, sends feedback and ends each goal with a
result; a client sends a goal, waits for its result and may cancel it. Robots offer
their long skills this way (``/navigate_to_pose``, ``/arm_controller/follow_joint_trajectory``,
``/gripper_controller/gripper_cmd``), so a simulated robot serves the same actions and
an actor that drives it is a client, whichever transport carries them.

The server side is the same on every transport: ``transport.action_server(name,
action_type, on_goal)`` calls ``on_goal(goal)`` on the hub with a :class:`ServerGoal`;
the server answers through it, from the hub, when it likes (a controller ends its goal
from a timer, steps later). The client side is an async actor made by
``transport.register_action(scope, name, action_type, server)``.

Outcomes as a client sees them: the ``Result`` of a succeeded goal; an aborted or
canceled goal fails the call with :class:`ActionGoalError` (carrying the result, whose
error fields say why); a rejected goal fails with :class:`GoalRejectedError`.
"""

from __future__ import annotations

import inspect
import itertools
from typing import TYPE_CHECKING, Any, Callable

from ..errors import ActorbtError
from ..modes import Kind
from .messages import RosAction, RosMessage

if TYPE_CHECKING:
    from ..actor import ActorRef
    from ..handles import Done

#: GoalStatus codes (action_msgs/msg/GoalStatus) by name
STATUS_NAMES = {
    0: "unknown",
    1: "accepted",
    2: "executing",
    3: "canceling",
    4: "succeeded",
    5: "canceled",
    6: "aborted",
}
STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED = 4, 5, 6


class ServerUnavailableError(ActorbtError, TimeoutError):
    """No action or service server answered within the wait."""

    def __init__(self, server: str, seconds: float, hint: str = "") -> None:
        self.server = server
        self.seconds = seconds
        within = f" within {seconds:g} s" if seconds > 0 else ""  # 0: it cannot come (local)
        super().__init__(f"no server for {server}{within}" + (f" ({hint})" if hint else ""))


class GoalRejectedError(ActorbtError):
    """The action server rejected the goal."""

    def __init__(self, server: str, reason: str = "") -> None:
        self.server = server
        self.reason = reason
        super().__init__(f"{server} rejected the goal" + (f": {reason}" if reason else ""))


class ActionGoalError(ActorbtError):
    """The goal ended without succeeding (aborted, or canceled by the server)."""

    def __init__(self, server: str, status: int, result: Any) -> None:
        self.server = server
        self.status = status
        self.result = result
        super().__init__(
            f"goal on {server} ended {STATUS_NAMES.get(status, status)}"
            + (f": {result_detail(result)}" if result_detail(result) else "")
        )


def result_detail(result: Any) -> str:
    """The words a result gives for its outcome: the ``error_msg`` / ``error_string`` /
    ``status`` / ``error`` field it has (ROS actions name it differently), with the code."""
    for text_field in ("error_msg", "error_string", "status", "error"):
        text = getattr(result, text_field, "")
        if isinstance(text, str) and text:
            code = getattr(result, "error_code", None)
            return f"{text} (error_code {code})" if code else text
    code = getattr(result, "error_code", None)
    return f"error_code {code}" if code else ""


def build_message(msg_type: type[RosMessage], value: Any, fields: dict[str, Any]) -> Any:
    """A ``msg_type`` from an instance, a mapping of fields, or keyword fields."""
    if isinstance(value, msg_type):
        msg = value
    elif value is None:
        msg = msg_type()
    elif isinstance(value, dict):
        msg = msg_type()
        fields = {**value, **fields}
    else:
        raise TypeError(f"expected a {msg_type.__name__} or a mapping of its fields, got {type(value).__name__}")
    known = msg_type.get_fields_and_field_types()
    for key, val in fields.items():
        if key not in known:
            raise TypeError(f"{msg_type.__name__} has no field {key!r}; fields: {', '.join(known)}")
        current = getattr(msg, key)
        if isinstance(val, dict) and hasattr(current, "get_fields_and_field_types"):
            val = build_message(type(current), val, {})  # a nested message from its fields
        setattr(msg, key, val)
    return msg


def message_signature(first: str, msg_type: type[RosMessage]) -> inspect.Signature:
    """``(first: msg_type = None, *, field: type = default, ...)`` for a goal or request
    type; each field is annotated with its Python type (a nested message's class, ``list``
    for a sequence), so the catalog can tell its JSON type."""
    P = inspect.Parameter
    params = [P(first, P.POSITIONAL_OR_KEYWORD, default=None, annotation=msg_type)]
    default = msg_type()
    for field in msg_type.get_fields_and_field_types():
        if field == first:
            continue
        value = getattr(default, field)
        kind = type(value)
        annotation = list if isinstance(value, (list, tuple)) or kind.__name__ == "array" else kind
        params.append(P(field, P.KEYWORD_ONLY, default=value, annotation=annotation))
    return inspect.Signature(params)


def message_doc(summary: str, first: str, msg_type: type[RosMessage]) -> str:
    """A client actor's docstring: ``summary`` and an ``Args:`` entry for ``first`` (the
    whole message) and for each field of ``msg_type`` (a goal or request type)."""
    lines = [
        summary,
        "",
        "Args:",
        f"    {first}: the whole message, or a mapping of its fields (fields given as keywords override it)",
    ]
    default = msg_type()
    for field, ros_type in msg_type.get_fields_and_field_types().items():
        if field != first:  # a nested message's class is in the catalog's type already
            nested = hasattr(getattr(default, field), "get_fields_and_field_types")
            lines.append(f"    {field}: the message's {field}" + ("" if nested else f" ({ros_type})"))
    return "\n".join(lines)


def public_name(cls: type) -> str:
    """``package.msg.Name`` of a ROS message or action class (without the private
    module it is defined in)."""
    module = ".".join(p for p in cls.__module__.split(".") if not p.startswith("_"))
    return f"{module}.{cls.__name__}"


class ServerGoal:
    """One goal as its server sees it. Every method runs on the hub.

    The server ends the goal once, with :meth:`succeed`, :meth:`abort` or
    :meth:`canceled` (later calls are ignored). A client's cancel request calls the
    handler given to :meth:`on_cancel`; without one the goal is canceled at once with
    an empty result.
    """

    _ids = itertools.count(1)

    def __init__(
        self,
        server: str,
        action_type: type[RosAction],
        request: Any,
        finish: Callable[[int, Any], None],
        feedback: Callable[[Any], None],
    ) -> None:
        self.server = server
        self.action_type = action_type
        self.request = request
        self.id = next(self._ids)
        self.active = True
        self.cancel_requested = False
        self._finish = finish
        self._feedback = feedback
        self._on_cancel: Callable[[], None] | None = None

    def publish_feedback(self, feedback: Any) -> None:
        if self.active:
            self._feedback(feedback)

    def succeed(self, result: Any = None) -> None:
        self._end(STATUS_SUCCEEDED, result)

    def abort(self, result: Any = None) -> None:
        self._end(STATUS_ABORTED, result)

    def canceled(self, result: Any = None) -> None:
        self._end(STATUS_CANCELED, result)

    def on_cancel(self, handler: Callable[[], None]) -> None:
        """``handler()`` runs when a client asks to cancel; it ends the goal (perhaps
        after stopping the motion), usually with :meth:`canceled`."""
        self._on_cancel = handler

    def request_cancel(self) -> None:
        """A client asked to cancel (called by the transport)."""
        if not self.active or self.cancel_requested:
            return
        self.cancel_requested = True
        if self._on_cancel is not None:
            self._on_cancel()
        else:
            self.canceled()

    def _end(self, status: int, result: Any) -> None:
        if not self.active:
            return
        self.active = False
        self._finish(status, result if result is not None else self.action_type.Result())


OnGoal = Callable[[ServerGoal], None]


class LocalActionServer:
    """An action served on the local bus (see ``LocalBus.action_server``)."""

    def __init__(
        self, registry: dict[str, "LocalActionServer"], name: str, action_type: type[RosAction], on_goal: OnGoal
    ) -> None:
        self.name = name
        self.action_type = action_type
        self.on_goal = on_goal
        self.goals: dict[int, ServerGoal] = {}
        self._registry = registry
        self.closed = False

    def close(self) -> None:
        """Stop serving; goals still running are aborted."""
        if self.closed:
            return
        self.closed = True
        if self._registry.get(self.name) is self:
            del self._registry[self.name]
        for goal in list(self.goals.values()):
            goal.abort()


def local_client_actor(
    scope: Any, name: str, action_type: type[RosAction], server: str, servers: dict[str, LocalActionServer]
) -> ActorRef:
    """Async actor ``name(goal=None, **fields)`` sending goals to the local server
    ``server`` (see the module docstring for its outcomes). It completes only on the hub."""

    def send(done: Done, *args: Any, **fields: Any) -> Callable[[], None]:
        goal_msg = build_message(action_type.Goal, args[0] if args else fields.pop("goal", None), fields)
        target = servers.get(server)
        if target is None:
            done.fail(ServerUnavailableError(server, 0, "nothing serves it on the local bus"))
            return lambda: None

        withdrawn = False  # the call was cancelled: its transaction ends without us

        def finish(status: int, result: Any) -> None:
            target.goals.pop(goal.id, None)
            if withdrawn:
                return
            if status == STATUS_SUCCEEDED:
                done(result)
            else:
                done.fail(ActionGoalError(server, status, result))

        def cancel() -> None:
            nonlocal withdrawn
            withdrawn = True
            goal.request_cancel()

        goal = ServerGoal(server, action_type, goal_msg, finish, feedback=lambda fb: None)
        target.goals[goal.id] = goal
        target.on_goal(goal)
        return cancel

    doc = message_doc(
        f"Send a {public_name(action_type)} goal to action {server} and return its result.", "goal", action_type.Goal
    )
    return scope.add_actor(
        name, send, Kind.ASYNC, doc=doc, hub_only=True, signature=message_signature("goal", action_type.Goal)
    )
