"""Goals and service calls, driven from the executor thread of a :class:`RosHost`.

rclpy's ActionClient and Client keep no lock around their request tables, so every
request here is sent from the executor thread (post ``start``/``cancel`` with
``host.post``). Callbacks (``on_result`` …) run on the executor thread too; hand results
to the hub with ``rt.call_soon_threadsafe`` or the thread-safe ``done``.
"""
from __future__ import annotations

import time
from typing import Any, Callable

from ..errors import ActorbtError

#: GoalStatus codes by name
STATUS_NAMES = {0: "unknown", 1: "accepted", 2: "executing", 3: "canceling", 4: "succeeded",
                5: "canceled", 6: "aborted"}
STATUS_SUCCEEDED = 4


class ServerUnavailableError(ActorbtError, TimeoutError):
    """No action or service server answered within the wait."""

    def __init__(self, server: str, seconds: float) -> None:
        self.server = server
        self.seconds = seconds
        super().__init__(f"no server for {server} within {seconds:g} s "
                         "(is it running? ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_DOMAIN_ID "
                         "must match on both sides)")


class GoalRejectedError(ActorbtError):
    """The action server rejected the goal."""

    def __init__(self, server: str, reason: str = "") -> None:
        self.server = server
        self.reason = reason
        super().__init__(f"{server} rejected the goal" + (f": {reason}" if reason else ""))


class GoalNotSentError(ActorbtError):
    """The goal was cancelled while it waited for the server, so it was never sent."""

    def __init__(self, server: str) -> None:
        self.server = server
        super().__init__(f"goal for {server} cancelled before it was sent")


class ActionGoalError(ActorbtError):
    """The goal ended without succeeding (aborted or canceled by the server)."""

    def __init__(self, server: str, status: int, result: Any) -> None:
        self.server = server
        self.status = status
        self.result = result
        detail = getattr(result, "status", "") or getattr(result, "error", "")
        super().__init__(f"goal on {server} ended {STATUS_NAMES.get(status, status)}"
                         + (f": {detail}" if detail else ""))


def build_message(msg_type: type, value: Any, fields: dict[str, Any]) -> Any:
    """A ``msg_type`` from an instance, a mapping of fields, or keyword fields."""
    if isinstance(value, msg_type):
        msg = value
    elif value is None:
        msg = msg_type()
    elif isinstance(value, dict):
        msg = msg_type()
        fields = {**value, **fields}
    else:
        raise TypeError(f"expected a {msg_type.__name__} or a mapping of its fields, "
                        f"got {type(value).__name__}")
    known = msg_type.get_fields_and_field_types()
    for key, val in fields.items():
        if key not in known:
            raise TypeError(f"{msg_type.__name__} has no field {key!r}; fields: {', '.join(known)}")
        setattr(msg, key, val)
    return msg


class ServerWait:
    """Waits for servers to be discovered, by polling from a node timer (executor thread)."""

    PERIOD = 0.01

    def __init__(self, node: Any) -> None:
        self._node = node
        self._waiting: list[list] = []
        self._timer: Any = None

    def when_ready(self, is_ready: Callable[[], bool], timeout: float,
                   on_ready: Callable[[], None], on_timeout: Callable[[], None]) -> list:
        """Call ``on_ready`` once ``is_ready()``, or ``on_timeout`` after ``timeout`` s."""
        if is_ready():
            on_ready()
            return []
        entry = [is_ready, time.monotonic() + timeout, on_ready, on_timeout]
        self._waiting.append(entry)
        if self._timer is None:
            self._timer = self._node.create_timer(self.PERIOD, self._poll)
        return entry

    def forget(self, entry: list) -> None:
        if entry in self._waiting:
            self._waiting.remove(entry)

    def _poll(self) -> None:
        now = time.monotonic()
        for entry in list(self._waiting):
            is_ready, deadline, on_ready, on_timeout = entry
            if is_ready():
                self._waiting.remove(entry)
                on_ready()
            elif now >= deadline:
                self._waiting.remove(entry)
                on_timeout()
        if not self._waiting and self._timer is not None:
            self._node.destroy_timer(self._timer)
            self._timer = None


class GoalCall:
    """One goal: wait for the server, send, get the result, cancel.

    All methods run on the executor thread. Exactly one of ``on_result(result_msg)``
    (succeeded) or ``on_error(exc)`` is called, unless the call was cancelled before the
    goal was accepted.
    """

    def __init__(self, client: Any, server: str, waiter: ServerWait, goal: Any, *,
                 server_timeout: float, on_result: Callable[[Any], None],
                 on_error: Callable[[BaseException], None],
                 on_accepted: Callable[[Any], None] | None = None,
                 on_status: Callable[[int, Any], None] | None = None,
                 goal_uuid: Any = None) -> None:
        self.client = client
        self.goal_uuid = goal_uuid
        self.server = server
        self.goal = goal
        self.handle: Any = None
        self.cancelled = False
        self.sent = False
        self.finished = False
        self._waiter = waiter
        self._wait_entry: list | None = None
        self._timeout = server_timeout
        self._on_result = on_result
        self._on_error = on_error
        self._on_accepted = on_accepted
        self._on_status = on_status

    def start(self) -> None:
        self._wait_entry = self._waiter.when_ready(
            self.client.server_is_ready, self._timeout, self._send, self._unavailable)

    def _unavailable(self) -> None:
        self._finish_error(ServerUnavailableError(self.server, self._timeout))

    def _send(self) -> None:
        if self.cancelled:
            return
        self.sent = True
        fut = self.client.send_goal_async(self.goal, goal_uuid=self.goal_uuid)
        fut.add_done_callback(self._on_response)

    def _on_response(self, fut: Any) -> None:
        try:
            gh = fut.result()
        except Exception as e:
            self._finish_error(e)
            return
        if gh is None or not gh.accepted:
            self._finish_error(GoalRejectedError(self.server))
            return
        self.handle = gh
        if self._on_accepted is not None:
            self._on_accepted(gh)
        if self.cancelled:
            gh.cancel_goal_async()
        gh.get_result_async().add_done_callback(self._on_result_response)

    def _on_result_response(self, fut: Any) -> None:
        try:
            resp = fut.result()
        except Exception as e:
            self._finish_error(e)
            return
        if self._on_status is not None:
            self._on_status(resp.status, resp.result)
        if resp.status == STATUS_SUCCEEDED:
            if not self.finished:
                self.finished = True
                self._on_result(resp.result)
        else:
            self._finish_error(ActionGoalError(self.server, resp.status, resp.result))

    def _finish_error(self, exc: BaseException) -> None:
        if not self.finished:
            self.finished = True
            self._on_error(exc)

    def cancel(self) -> Any:
        """Ask the server to cancel the goal (now, or as soon as it is accepted); a goal
        not sent yet is not sent and ends with GoalNotSentError. Returns the
        cancel-response future when a request was sent."""
        if self.cancelled or self.finished:
            return None
        self.cancelled = True
        if self._wait_entry:
            self._waiter.forget(self._wait_entry)
        if not self.sent:
            self._finish_error(GoalNotSentError(self.server))
            return None
        if self.handle is not None:
            return self.handle.cancel_goal_async()
        return None


class ServiceCall:
    """One service request: wait for the server, call, deliver the response, or drop it
    on cancel. Executor thread only."""

    def __init__(self, client: Any, server: str, waiter: ServerWait, request: Any, *,
                 server_timeout: float, on_result: Callable[[Any], None],
                 on_error: Callable[[BaseException], None]) -> None:
        self.client = client
        self.server = server
        self.request = request
        self.cancelled = False
        self._waiter = waiter
        self._wait_entry: list | None = None
        self._timeout = server_timeout
        self._future: Any = None
        self._on_result = on_result
        self._on_error = on_error

    def start(self) -> None:
        self._wait_entry = self._waiter.when_ready(
            self.client.service_is_ready, self._timeout, self._send,
            lambda: self._on_error(ServerUnavailableError(self.server, self._timeout)))

    def _send(self) -> None:
        if self.cancelled:
            return
        self._future = self.client.call_async(self.request)
        self._future.add_done_callback(self._done)

    def _done(self, fut: Any) -> None:
        if self.cancelled:
            return
        try:
            self._on_result(fut.result())
        except Exception as e:
            self._on_error(e)

    def cancel(self) -> None:
        self.cancelled = True
        if self._wait_entry:
            self._waiter.forget(self._wait_entry)
        if self._future is not None and not self._future.done():
            self.client.remove_pending_request(self._future)
