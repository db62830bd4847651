"""Goals and service calls, driven from the executor thread of a :class:`RosHost`.

rclpy's ActionClient and Client keep no lock around their request tables, so every
request here is sent from the executor thread (post ``start``/``cancel`` with
``host.post``). Callbacks (``on_result`` …) run on the executor thread too; hand results
to the hub with ``rt.call_soon_threadsafe`` or the thread-safe ``done``.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Callable, Protocol

from bt_engine.bus.actions import (
    STATUS_NAMES,
    STATUS_SUCCEEDED,
    ActionGoalError,
    GoalRejectedError,
    ServerUnavailableError,
    build_message,
)
from bt_engine.bus.messages import RosMessage
from bt_engine.errors import ActorbtError

if TYPE_CHECKING:
    from rclpy.action.client import ClientGoalHandle
    from rclpy.client import Client
    from rclpy.node import Node
    from rclpy.task import Future
    from rclpy.timer import Timer

__all__ = [
    "STATUS_NAMES",
    "ActionGoalError",
    "GoalCall",
    "GoalNotSentError",
    "GoalRejectedError",
    "ServerLostError",
    "ServerUnavailableError",
    "ServerWait",
    "ServiceCall",
    "build_message",
]

#: why a ROS server may not be found (the hint of ServerUnavailableError)
DISCOVERY_HINT = "is it running? ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_DOMAIN_ID must match on both sides"


#: [s] an action server missing from the graph this long has lost the goals it ran
LOST_GRACE = 3.0


class GoalNotSentError(ActorbtError):
    """The goal was cancelled while it waited for the server, so it was never sent."""

    def __init__(self, server: str) -> None:
        self.server = server
        super().__init__(f"goal for {server} cancelled before it was sent")


class ServerLostError(ActorbtError):
    """The action server went away while it ran our goal (its process died or restarted):
    no result will come."""

    def __init__(self, server: str, grace: float) -> None:
        self.server = server
        super().__init__(
            f"the action server {server} went away while it ran the goal (gone for "
            f"{grace:g} s): the goal is lost; is the robot's process running?"
        )


class ServerWait:
    """Waits for servers to be discovered, and watches the servers of goals under way,
    by polling from a node timer (executor thread)."""

    PERIOD = 0.01
    #: [s] between two looks at a running goal's server
    WATCH_PERIOD = 0.5

    def __init__(self, node: Node) -> None:
        self._node = node
        self._waiting: list[list] = []
        self._timer: Timer | None = None
        self._watched: list[list] = []
        self._watch_timer: Timer | None = None

    def when_ready(
        self, is_ready: Callable[[], bool], timeout: float, on_ready: Callable[[], None], on_timeout: Callable[[], None]
    ) -> list:
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
        if entry in self._watched:
            self._watched.remove(entry)

    def watch(self, is_ready: Callable[[], bool], grace: float, on_lost: Callable[[], None]) -> list:
        """Call ``on_lost`` once ``is_ready()`` has been false for ``grace`` s (until
        ``forget``)."""
        entry = [is_ready, grace, on_lost, time.monotonic()]
        self._watched.append(entry)
        if self._watch_timer is None:
            self._watch_timer = self._node.create_timer(self.WATCH_PERIOD, self._look)
        return entry

    def _look(self) -> None:
        now = time.monotonic()
        for entry in list(self._watched):
            is_ready, grace, on_lost, seen = entry
            if is_ready():
                entry[3] = now
            elif now - seen >= grace:
                self._watched.remove(entry)
                on_lost()
        if not self._watched and self._watch_timer is not None:
            self._node.destroy_timer(self._watch_timer)
            self._watch_timer = None

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


class GoalClient(Protocol):
    """What a GoalCall needs of its rclpy ActionClient (a wrapper may stand in for it)."""

    def server_is_ready(self) -> bool: ...

    def send_goal_async(self, goal: RosMessage, *, goal_uuid: RosMessage | None = None) -> Future: ...


class GoalCall:
    """One goal: wait for the server, send, get the result, cancel.

    All methods run on the executor thread. Exactly one of ``on_result(result_msg)``
    (succeeded) or ``on_error(exc)`` is called, unless the call was cancelled before the
    goal was accepted.
    """

    def __init__(
        self,
        client: GoalClient,
        server: str,
        waiter: ServerWait,
        goal: RosMessage,
        *,
        server_timeout: float,
        on_result: Callable[[RosMessage], None],
        on_error: Callable[[BaseException], None],
        on_accepted: Callable[[ClientGoalHandle], None] | None = None,
        on_status: Callable[[int, RosMessage], None] | None = None,
        # a unique_identifier_msgs/UUID (rclpy makes one when None)
        goal_uuid: RosMessage | None = None,
    ) -> None:
        self.client = client
        self.goal_uuid = goal_uuid
        self.server = server
        self.goal = goal
        self.handle: ClientGoalHandle | None = None
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
        self._watch_entry: list | None = None
        #: [s] a server gone this long while it runs our goal has lost it
        self._lost_grace = min(server_timeout, LOST_GRACE)

    def start(self) -> None:
        self._wait_entry = self._waiter.when_ready(
            self.client.server_is_ready, self._timeout, self._send, self._unavailable
        )

    def _unavailable(self) -> None:
        self._finish_error(ServerUnavailableError(self.server, self._timeout, DISCOVERY_HINT))

    def _send(self) -> None:
        if self.cancelled:
            return
        self.sent = True
        fut = self.client.send_goal_async(self.goal, goal_uuid=self.goal_uuid)
        fut.add_done_callback(self._on_response)

    def _on_response(self, fut: Future) -> None:
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
        # a server that dies with our goal never answers: give up when it is gone
        self._watch_entry = self._waiter.watch(self.client.server_is_ready, self._lost_grace, self._lost)
        gh.get_result_async().add_done_callback(self._on_result_response)

    def _lost(self) -> None:
        self._finish_error(ServerLostError(self.server, self._lost_grace))

    def _on_result_response(self, fut: Future) -> None:
        try:
            resp = fut.result()
        except Exception as e:
            self._finish_error(e)
            return
        if self._on_status is not None:
            self._on_status(resp.status, resp.result)
        if resp.status == STATUS_SUCCEEDED:
            self._stop_watching()
            if not self.finished:
                self.finished = True
                self._on_result(resp.result)
        else:
            self._finish_error(ActionGoalError(self.server, resp.status, resp.result))

    def _finish_error(self, exc: BaseException) -> None:
        if not self.finished:
            self.finished = True
            self._on_error(exc)
        self._stop_watching()

    def _stop_watching(self) -> None:
        if self._watch_entry:
            self._waiter.forget(self._watch_entry)
            self._watch_entry = None

    def cancel(self) -> Future | None:
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

    def __init__(
        self,
        client: Client,
        server: str,
        waiter: ServerWait,
        request: RosMessage,
        *,
        server_timeout: float,
        on_result: Callable[[RosMessage], None],
        on_error: Callable[[BaseException], None],
    ) -> None:
        self.client = client
        self.server = server
        self.request = request
        self.cancelled = False
        self._waiter = waiter
        self._wait_entry: list | None = None
        self._timeout = server_timeout
        self._future: Future | None = None
        self._on_result = on_result
        self._on_error = on_error

    def start(self) -> None:
        self._wait_entry = self._waiter.when_ready(
            self.client.service_is_ready,
            self._timeout,
            self._send,
            lambda: self._on_error(ServerUnavailableError(self.server, self._timeout, DISCOVERY_HINT)),
        )

    def _send(self) -> None:
        if self.cancelled:
            return
        self._future = self.client.call_async(self.request)
        self._future.add_done_callback(self._done)

    def _done(self, fut: Future) -> None:
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
