"""A client of a running ``actorbt serve``, for programs and the ``actorbt`` command:
goals to ``/actorbt/tree/<name>``, calls through ``/actorbt/call``.

    with Remote() as remote:
        outputs = remote.run_tree("bt_pick_place", {"category": "can"})
        value = remote.call("robot.navigation.goto", 1.0, 2.0, 0.0)

Blocking methods wait in the calling thread; rclpy runs in the Remote's own executor
thread (its own Context), so Ctrl-C reaches the caller as KeyboardInterrupt and
:meth:`RemoteGoal.cancel` can cancel the goal.
"""
from __future__ import annotations

import collections
import os
import threading
import time
import uuid
from typing import Any, Callable

import yaml

from ..errors import ActorbtError, ActorTimeout
from .client import (STATUS_NAMES, ActionGoalError, GoalCall, GoalNotSentError,
                     GoalRejectedError, ServerWait)
from .host import RosClosedError, RosHost
from .names import CALL_ACTION, REJECTIONS_TOPIC, goal_text, rejections_qos, tree_action_name
from .yamlio import dump

__all__ = ["Remote", "RemoteCallError", "RemoteGoal"]


class RemoteCallError(ActorbtError):
    """A remote actor call or tree goal ended without success."""

    def __init__(self, what: str, status: str, detail: str = "") -> None:
        self.status = status
        self.detail = detail
        super().__init__(f"{what} {status}" + (f": {detail}" if detail else ""))


class RemoteGoal:
    """One goal in flight. ``wait()`` for it; ``cancel()`` it; then read ``status``
    (a GoalStatus name: succeeded, canceled, aborted), ``result`` (the Result message)
    and ``error`` (an exception when it did not succeed)."""

    def __init__(self, remote: "Remote", action: str, goal: Any) -> None:
        self.remote = remote
        self.action = action
        self.goal = goal
        self.accepted = threading.Event()
        self.done = threading.Event()
        self.status = "pending"
        self.result: Any = None
        self.error: BaseException | None = None
        self.ended_at: float | None = None
        self.call: GoalCall | None = None

    def _on_accepted(self, handle: Any) -> None:
        self.status = "accepted"
        self.accepted.set()

    def _on_status(self, status: int, result: Any) -> None:
        self.status = STATUS_NAMES.get(status, str(status))
        self.result = result

    def _on_result(self, result: Any) -> None:
        self.status = "succeeded"
        self.result = result
        self.ended_at = time.monotonic()
        self.accepted.set()
        self.done.set()

    def _on_error(self, exc: BaseException) -> None:
        if isinstance(exc, GoalRejectedError):
            self.status = "rejected"  # wait() adds the reason, off the executor thread
        elif isinstance(exc, GoalNotSentError):
            self.status = "canceled"
        elif not isinstance(exc, ActionGoalError):
            self.status = "failed"
        self.error = exc
        self.ended_at = time.monotonic()
        self.accepted.set()
        self.done.set()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait for the end; True when it ended. Interruptible with Ctrl-C."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.done.is_set():
            step = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
            if step <= 0:
                return False
            self.done.wait(step)
        err = self.error
        if isinstance(err, GoalRejectedError) and not err.reason:
            reason = self.remote.rejection_reason(self.action, self.goal)
            if reason:
                self.error = GoalRejectedError(self.action, reason)
        return True

    def cancel(self) -> None:
        """Ask the server to cancel the goal (as soon as it is accepted)."""
        if not self.done.is_set():
            try:
                self.remote.host.post(self._cancel)
            except RosClosedError:
                pass

    def _cancel(self) -> None:
        # Unlike GoalCall.cancel, keep following the goal: the result reports CANCELED.
        call = self.call
        if call is None or call.finished:
            return
        if call.handle is not None:
            call.handle.cancel_goal_async()
        else:
            call.cancel()  # not accepted yet: cancelled on acceptance, or never sent


class Remote:
    """A ROS 2 client of ``actorbt serve`` (see the module docstring).

    Args:
        node_name: this client's node name (default ``actorbt_client_<pid>_<host id>``).
        wait: how long to wait for a server to be discovered [s].
    """

    def __init__(self, node_name: str | None = None, *, wait: float = 10.0) -> None:
        self.wait = wait
        self.host = RosHost("client")
        try:
            self.node = self.host.create_node(node_name or f"actorbt_client_{os.getpid()}_{self.host.id}")
            self._waiter = ServerWait(self.node)
            self._clients: dict[str, Any] = {}
            self._created: dict[str, float] = {}
            self._feedback: dict[bytes, tuple[RemoteGoal, Callable[[Any], None]]] = {}
            self._rejections: collections.deque = collections.deque(maxlen=200)
            self._rej_cond = threading.Condition()
            from std_msgs.msg import String
            self.host.call(lambda: self.node.create_subscription(
                String, REJECTIONS_TOPIC, self._on_rejection, rejections_qos()))
        except BaseException:
            self.host.close()
            raise

    # -- rejections -------------------------------------------------------------------
    def _on_rejection(self, msg: Any) -> None:
        try:
            data = yaml.safe_load(msg.data)
        except yaml.YAMLError:
            return
        if isinstance(data, dict):
            with self._rej_cond:
                self._rejections.append(data)
                self._rej_cond.notify_all()

    def rejection_reason(self, action: str, goal: Any, timeout: float = 1.0) -> str:
        """The reason the server published for rejecting ``goal`` on ``action``."""
        key = goal_text(goal)
        deadline = time.monotonic() + timeout
        with self._rej_cond:
            while True:
                for d in reversed(self._rejections):
                    if d.get("action") == action and d.get("goal") == key:
                        return str(d.get("reason", ""))
                left = deadline - time.monotonic()
                if left <= 0:
                    return ""
                self._rej_cond.wait(left)

    # -- goals ---------------------------------------------------------------------------
    #: a new action client's feedback subscription needs a moment to be matched by the
    #: server's publisher, even once the server is discovered; feedback published
    #: before that is lost (ROS 2 feedback is volatile), so the first goal waits this [s]
    SETTLE = 0.25

    def _client(self, action_type: type, action: str) -> Any:
        from rclpy.action import ActionClient
        from rclpy.qos import QoSProfile
        client = self._clients.get(action)
        if client is None:
            client = self._clients[action] = ActionClient(self.node, action_type, action)
            self._created[action] = time.monotonic()
            # Feedback through our own subscription: rclpy drops a goal's feedback
            # callback when its result arrives, and the result (a service reply) often
            # overtakes the last feedback message (a topic).
            self.node.create_subscription(action_type.Impl.FeedbackMessage,
                                          f"{action}/_action/feedback", self._on_feedback,
                                          QoSProfile(depth=100))
        return client

    #: how long a finished goal still receives feedback that arrives late [s]
    FEEDBACK_GRACE = 2.0

    def _on_feedback(self, msg: Any) -> None:
        entry = self._feedback.get(bytes(msg.goal_id.uuid))
        if entry is not None:
            entry[1](msg.feedback)

    def _prune_feedback(self) -> None:
        now = time.monotonic()
        for key, (g, _) in list(self._feedback.items()):
            if g.ended_at is not None and now - g.ended_at > self.FEEDBACK_GRACE:
                del self._feedback[key]

    def wait_for(self, action_type: type, action: str, timeout: float | None = None) -> bool:
        """Wait until ``action`` is discovered; False after ``timeout`` [s]."""
        client = self.host.call(self._client, action_type, action)
        deadline = time.monotonic() + (self.wait if timeout is None else timeout)
        while not client.server_is_ready():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)
        return True

    def send(self, action_type: type, action: str, goal: Any, *,
             on_feedback: Callable[[Any], None] | None = None,
             wait: float | None = None) -> RemoteGoal:
        """Send ``goal`` (waiting up to ``wait`` s for the server) and return at once."""
        g = RemoteGoal(self, action, goal)

        def start() -> None:
            try:
                begin()
            except Exception as e:
                g._on_error(e)

        def begin() -> None:
            from unique_identifier_msgs.msg import UUID
            client = self._client(action_type, action)
            settled = self._created[action] + self.SETTLE
            goal_id = uuid.uuid4().bytes
            self._prune_feedback()
            if on_feedback is not None:
                self._feedback[goal_id] = (g, on_feedback)
            g.call = GoalCall(_Settling(client, settled), action, self._waiter, goal,
                              server_timeout=self.wait if wait is None else wait,
                              on_result=g._on_result, on_error=g._on_error,
                              on_accepted=g._on_accepted, on_status=g._on_status,
                              goal_uuid=UUID(uuid=list(goal_id)))
            g.call.start()
        self.host.post(start)  # cancel() is posted after it, so it finds g.call
        return g

    def tree_goal(self, tree: str, inputs: "dict | str | None" = None, *,
                  on_feedback: Callable[[Any], None] | None = None,
                  wait: float | None = None) -> RemoteGoal:
        """Start a goal on ``/actorbt/tree/<tree>``; ``inputs`` a mapping or YAML text."""
        from actorbt_interfaces.action import RunTree
        text = inputs if isinstance(inputs, str) else (dump(inputs) if inputs else "")
        return self.send(RunTree, tree_action_name(tree), RunTree.Goal(inputs_yaml=text),
                         on_feedback=on_feedback, wait=wait)

    def run_tree(self, tree: str, inputs: "dict | str | None" = None, *,
                 timeout: float | None = None,
                 on_feedback: Callable[[Any], None] | None = None) -> Any:
        """Run a tree to the end and return its outputs; raise RemoteCallError (failed,
        canceled), GoalRejectedError or ActorTimeout (then the goal is cancelled)."""
        g = self.tree_goal(tree, inputs, on_feedback=on_feedback)
        self._finish(g, timeout, f"tree {tree}")
        return yaml.safe_load(g.result.outputs_yaml) if g.result.outputs_yaml else {}

    def call_goal(self, actor: str, *args: Any, **kwargs: Any) -> RemoteGoal:
        """Start a call of ``actor`` through ``/actorbt/call``."""
        from actorbt_interfaces.action import CallActor
        text = dump({"args": list(args), "kwargs": kwargs}) if (args or kwargs) else ""
        return self.send(CallActor, CALL_ACTION, CallActor.Goal(actor=actor, args_yaml=text))

    def call(self, actor: str, *args: Any, timeout: float | None = None, **kwargs: Any) -> Any:
        """Call ``actor`` in the served runtime and return its result (as YAML data)."""
        g = self.call_goal(actor, *args, **kwargs)
        self._finish(g, timeout, f"actor {actor}")
        return yaml.safe_load(g.result.result_yaml) if g.result.result_yaml else None

    def _finish(self, g: RemoteGoal, timeout: float | None, what: str) -> None:
        try:
            if not g.wait(timeout):
                g.cancel()
                g.wait(5.0)
                raise ActorTimeout(what, timeout or 0.0)
        except KeyboardInterrupt:
            g.cancel()
            g.wait(5.0)
            raise
        if g.error is not None:
            if isinstance(g.error, ActionGoalError):
                res = g.error.result
                detail = getattr(res, "error", "") or getattr(res, "status", "")
                raise RemoteCallError(what, g.status, detail) from None
            raise g.error

    # -- lifecycle -----------------------------------------------------------------------
    def close(self) -> None:
        try:
            self.host.flush(timeout=0.5)  # pending cancel requests go out
        except RosClosedError:
            pass
        self.host.close()

    def __enter__(self) -> "Remote":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class _Settling:
    """An ActionClient whose server counts as ready only after ``settled`` (monotonic)."""

    def __init__(self, client: Any, settled: float) -> None:
        self._client = client
        self._settled = settled

    def server_is_ready(self) -> bool:
        return self._client.server_is_ready() and time.monotonic() >= self._settled

    def __getattr__(self, name: str) -> Any:
        return getattr(self._client, name)
