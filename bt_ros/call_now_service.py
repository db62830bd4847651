"""``/actorbt/call_now`` (``actorbt_interfaces/srv/CallActorNow``): a quick actor as a
service, for a ROS user who expects ``get_pose`` to be a service call.

The request is decoded as a CallActor goal (:func:`bt_ros.goals.decode_call_goal`).
The call runs on the hub like any goal; after ``timeout`` seconds (default
:data:`DEFAULT_TIMEOUT`) it is cancelled and the response says ``TIMEOUT``: anything
slow belongs to the action ``/actorbt/call``, which has feedback and cancel. The
callback is a coroutine, so a slow call never holds the executor thread.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from bt_engine.errors import Cancelled, Failure
from .error_codes import Ending, error_code
from .goals import GoalError, decode_call_goal
from .host import RosClosedError, RosHost
from .rostypes import Outcome, Value
from .yamlio import dump

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.service import Service

    from bt_engine import Runtime
    from bt_engine.bus.messages import RosMessage

log = logging.getLogger("actorbt.ros.server")

__all__ = ["CallNowService", "DEFAULT_TIMEOUT"]

#: seconds a call may take when the request gives no timeout
DEFAULT_TIMEOUT = 5.0


class CallNowService:
    """The service on the server's node; see the module docstring."""

    def __init__(self, rt: Runtime, host: RosHost, name: str) -> None:
        self.rt = rt
        self.host = host
        self.name = name
        self._service: Service | None = None
        self._node: Node | None = None

    def create(self, node: Node) -> None:
        from actorbt_interfaces.srv import CallActorNow

        self._node = node
        # rclpy's executor awaits a coroutine callback, but create_service's annotation
        # (a callback that returns the response) has no room for one
        self._service = node.create_service(CallActorNow, self.name, self._on_request)  # type: ignore[misc]

    def destroy(self) -> None:
        if self._service is not None and self._node is not None:  # create() sets both
            self._node.destroy_service(self._service)
            self._service = None

    async def _on_request(self, request: RosMessage, response: RosMessage) -> RosMessage:
        from rclpy.task import Future

        def answer(ending: Ending, text: str = "", value: Value = None) -> RosMessage:
            response.success = ending is Ending.SUCCEEDED
            response.error_code = error_code(type(response), ending)
            response.error_msg = text
            response.result_yaml = dump(value) if response.success else ""
            return response

        try:
            call = decode_call_goal(self.rt, request.actor, request.args_yaml)
        except GoalError as e:
            return answer(e.ending, str(e))
        timeout = request.timeout if request.timeout > 0 else DEFAULT_TIMEOUT
        outcome: Future = Future()
        timed_out = []

        def done(value: Outcome) -> None:  # hub
            try:
                self.host.post(lambda: outcome.done() or outcome.set_result(value))
            except RosClosedError:
                pass

        def start() -> None:  # hub
            try:
                txn = self.rt.start(call.path, *call.args, on_done=done, **call.kwargs)
            except Exception as e:  # the runtime is closing
                done(Failure(e))
                return

            def expire() -> None:
                if not txn.done:
                    timed_out.append(True)
                    txn.cancel(f"took longer than {timeout:g} s")

            self.rt.call_later(timeout, expire)

        try:
            self.rt.call_soon_threadsafe(start)
        except Exception:
            return answer(Ending.SHUTDOWN, "the server is shutting down")
        value = await outcome
        if not isinstance(value, Failure):
            return answer(Ending.SUCCEEDED, value=value)
        exc = value.exception
        if timed_out:
            return answer(
                Ending.TIMEOUT,
                f"{call.path} took longer than {timeout:g} s (cancelled); call it through the action /actorbt/call",
            )
        if value.cancelled or isinstance(exc, Cancelled):
            return answer(Ending.SHUTDOWN, getattr(exc, "reason", "") or str(exc))
        return answer(Ending.FAILED, f"{type(exc).__name__}: {exc}")
