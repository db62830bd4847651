"""An action served over ROS 2 for code on the hub (``RosTransport.action_server``): the
rclpy side of :mod:`bt_engine.bus.actions`, so a server written once (a simulated
controller, a navigation server) answers local and ROS clients alike.

A goal's way through (thread in brackets):

1. [executor] rclpy accepts every goal and runs ``_execute``, a coroutine: it makes the
   goal's :class:`~bt_engine.bus.actions.ServerGoal` and hands it to ``on_goal`` on the
   hub, then awaits the goal's end through an rclpy Future, without blocking the executor.
2. [hub] the server works, sends feedback and ends the goal; each of those is posted to
   the executor thread (rclpy's goal handles are not thread-safe).
3. [executor] a client's cancel request is accepted and posted to the hub as
   ``ServerGoal.request_cancel``; the server decides when the goal ends.

Servers validate goals themselves and abort a bad one with the reason in its result, as
ROS 2 controllers and Nav2 do, so a stock client sees why.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Callable, Protocol

from bt_engine.bus.actions import STATUS_CANCELED, STATUS_SUCCEEDED, ServerGoal
from bt_engine.bus.messages import RosAction, RosMessage
from .host import RosClosedError, RosHost

if TYPE_CHECKING:
    from rclpy.action import CancelResponse
    from rclpy.action.server import ServerGoalHandle
    from rclpy.node import Node

    from bt_engine import Runtime

log = logging.getLogger("actorbt.ros")


class Serving(Protocol):
    """What an action server uses of its RosTransport (which imports this module)."""

    node: Node
    host: RosHost

    @property
    def rt(self) -> Runtime: ...


class RosActionServer:
    """One action served by a :class:`~bt_ros.transport.RosTransport`'s node
    (``transport``: its ``node``, ``host`` and ``rt`` are used)."""

    def __init__(
        self, transport: Serving, name: str, action_type: type[RosAction], on_goal: Callable[[ServerGoal], None]
    ) -> None:
        from rclpy.action import ActionServer

        self.name = name
        self.action_type = action_type
        self.on_goal = on_goal
        self._transport = transport
        self._goals: dict[bytes, ServerGoal] = {}
        self.closed = False
        # created on this thread, like the action clients: the hub never waits for the
        # executor thread (which may be waiting for the hub)
        self._server = ActionServer(transport.node, action_type, name, self._execute, cancel_callback=self._on_cancel)

    # -- executor thread ---------------------------------------------------------------
    async def _execute(self, handle: ServerGoalHandle) -> RosMessage:
        from rclpy.task import Future

        rt = self._transport.rt
        ended: Future = Future()
        key = bytes(handle.goal_id.uuid)

        def finish(status: int, result: RosMessage) -> None:  # hub
            self._post(lambda: ended.done() or ended.set_result((status, result)))

        def feedback(msg: RosMessage) -> None:  # hub
            self._post(lambda: handle.is_active and handle.publish_feedback(msg))

        goal = ServerGoal(self.name, self.action_type, handle.request, finish, feedback)
        self._goals[key] = goal
        try:
            rt.call_soon_threadsafe(self._start, goal)
        except Exception as e:  # the runtime is closing
            log.debug("%s: goal not started: %s", self.name, e)
            handle.abort()
            return self.action_type.Result()
        try:
            status, result = await ended
        finally:
            self._goals.pop(key, None)
        if status == STATUS_SUCCEEDED:
            handle.succeed()
        elif status == STATUS_CANCELED and handle.is_cancel_requested:
            handle.canceled()
        else:  # aborted, or "canceled" by the server itself without a client's request
            handle.abort()
        return result

    def _on_cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        from rclpy.action import CancelResponse

        goal = self._goals.get(bytes(handle.goal_id.uuid))
        if goal is not None:
            try:
                self._transport.rt.call_soon_threadsafe(goal.request_cancel)
            except Exception:
                return CancelResponse.REJECT
        return CancelResponse.ACCEPT

    # -- hub ---------------------------------------------------------------------------
    def _start(self, goal: ServerGoal) -> None:
        if self.closed:
            goal.abort()
            return
        try:
            self.on_goal(goal)
        except Exception as e:
            log.exception("%s: the server failed on a goal", self.name)
            if goal.active:
                goal.abort(_with_error(self.action_type.Result(), f"{type(e).__name__}: {e}"))

    def _post(self, fn: Callable[[], object]) -> None:
        try:
            self._transport.host.post(fn)
        except RosClosedError:
            pass

    # -- lifecycle -------------------------------------------------------------------
    def close(self) -> None:
        """Stop serving: running goals are aborted and the server is destroyed."""
        if self.closed:
            return
        self.closed = True
        for goal in list(self._goals.values()):
            goal.abort()
        server = self._server

        def destroy() -> None:
            server.destroy()

        self._post(destroy)


def _with_error(result: RosMessage, text: str) -> RosMessage:
    """``result`` with ``text`` in its error text field, whichever the action names it."""
    fields = result.get_fields_and_field_types()
    for name in ("error_msg", "error_string", "error"):
        if fields.get(name) == "string":
            setattr(result, name, text)
            break
    return result
