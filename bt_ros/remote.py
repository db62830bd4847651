"""A client of a running ``actorbt serve``, for programs and the ``actorbt`` command:
goals to ``/actorbt/tree/<name>``, calls through ``/actorbt/call``.

    with Remote() as remote:
        outputs = remote.run_tree("bt_pick_place", {"category": "can"})
        value = remote.call("robot.navigation.goto", 1.0, 2.0, 0.0)

Blocking methods wait in the calling thread; rclpy runs in the Remote's own executor
thread (its own Context), so Ctrl-C reaches the caller as KeyboardInterrupt and
:meth:`RemoteGoal.cancel` can cancel the goal.

What is served is read from the ROS graph: :meth:`Remote.served_actions` and
:meth:`Remote.served_trees` list the discovered ``/actorbt/...`` action servers, and
:meth:`Remote.check_tree` fails at once with close matches when a tree is not served.
One Remote keeps its node, so calls after the first skip start-up and discovery
(``actorbt rshell``). ``Remote(namespace="robot1")`` talks to ``serve --namespace robot1``.

A goal the server cannot run is accepted and aborted at once with ``INVALID_GOAL`` (or
``BUSY``: the tree runs another goal) and the reason in ``error_msg``; a RemoteGoal
tells it as refused: status ``rejected``, error :class:`GoalRefusedError` (a
GoalRejectedError) with the reason, since the goal never ran.
"""

from __future__ import annotations

import difflib
import os
import threading
import time
import uuid
from typing import TYPE_CHECKING, Any, Callable

import yaml

from bt_engine.bus.messages import RosAction, RosMessage
from bt_engine.errors import ActorbtError, ActorTimeout
from .client import (
    STATUS_NAMES,
    ActionGoalError,
    GoalCall,
    GoalNotSentError,
    GoalRejectedError,
    ServerUnavailableError,
    ServerWait,
)
from .error_codes import REFUSED, ending_of
from .host import RosClosedError, RosHost
from .names import CALL_ACTION, NODE_NAME, in_namespace, tree_action_name, tree_of_action
from .rostypes import Value
from .yamlio import dump

if TYPE_CHECKING:
    from rclpy.action import ActionClient
    from rclpy.action.client import ClientGoalHandle

__all__ = ["GoalRefusedError", "NoServeError", "Remote", "RemoteCallError", "RemoteGoal", "UnknownTreeError"]

#: what every action of ``actorbt serve`` starts with (in the root namespace)
SERVE_PREFIX = f"/{NODE_NAME}/"


class GoalRefusedError(GoalRejectedError):
    """The server accepted the goal and aborted it at once: it cannot run (``error_code``
    ``INVALID_GOAL`` or ``BUSY``, the reason in ``error_msg``)."""

    def __init__(self, server: str, reason: str, code: str) -> None:
        super().__init__(server, reason)
        self.code = code
        self.args = (f"{server} refused the goal ({code}): {reason}",)


class NoServeError(ServerUnavailableError):
    """No ``actorbt serve`` was discovered within the wait."""

    def __init__(self, seconds: float) -> None:
        super().__init__(CALL_ACTION, seconds)
        self.args = (str(self),)

    def __str__(self) -> str:
        return (
            f"no actorbt serve found within {self.seconds:g} s; start one with "
            "`actorbt serve` (ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE must match "
            "on both sides)"
        )


class UnknownTreeError(ActorbtError, LookupError):
    """The running ``actorbt serve`` serves no tree of that name."""

    def __init__(self, tree: str, served: list[str]) -> None:
        self.tree = tree
        self.served = sorted(served)
        self.suggestions = close_matches(tree, self.served)
        hint = f"; did you mean: {', '.join(self.suggestions)}?" if self.suggestions else ""
        listed = ", ".join(self.served) if self.served else "none"
        super().__init__(f"no served tree {tree!r}{hint} (served: {listed})")


def close_matches(name: str, known: list[str], n: int = 5) -> list[str]:
    """Names of ``known`` that contain ``name``, then difflib's close matches."""
    low = name.lower()
    found = [k for k in known if low and low in k.lower()]
    found += difflib.get_close_matches(name, known, n=n, cutoff=0.5)
    return list(dict.fromkeys(found))[:n]


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

    def __init__(self, remote: "Remote", action: str, goal: RosMessage) -> None:
        self.remote = remote
        self.action = action
        self.goal = goal
        self.accepted = threading.Event()
        self.done = threading.Event()
        self.status = "pending"
        self.result: RosMessage | None = None
        self.error: BaseException | None = None
        self.ended_at: float | None = None
        self.call: GoalCall | None = None

    def _on_accepted(self, handle: ClientGoalHandle) -> None:
        self.status = "accepted"
        self.accepted.set()

    def _on_status(self, status: int, result: RosMessage) -> None:
        self.status = STATUS_NAMES.get(status, str(status))
        self.result = result

    def _on_result(self, result: RosMessage) -> None:
        self.status = "succeeded"
        self.result = result
        self.ended_at = time.monotonic()
        self.accepted.set()
        self.done.set()

    def _on_error(self, exc: BaseException) -> None:
        if isinstance(exc, ActionGoalError) and exc.result is not None:
            ending = ending_of(type(exc.result), getattr(exc.result, "error_code", 0))
            if ending in REFUSED:
                exc = GoalRefusedError(self.action, exc.result.error_msg, ending.value)
        if isinstance(exc, GoalRejectedError):
            self.status = "rejected"
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
        namespace: the namespace of the ``actorbt serve`` to talk to (``robot1``).
    """

    def __init__(self, node_name: str | None = None, *, wait: float = 10.0, namespace: str | None = None) -> None:
        self.wait = wait
        self.namespace = namespace or ""
        #: what every action of the serve starts with (``/robot1/actorbt/``)
        self.prefix = in_namespace(SERVE_PREFIX, self.namespace)
        self.call_action = in_namespace(CALL_ACTION, self.namespace)
        self.host = RosHost("client")
        try:
            self.node = self.host.create_node(node_name or f"actorbt_client_{os.getpid()}_{self.host.id}", lean=True)
            self._waiter = ServerWait(self.node)
            self._clients: dict[str, ActionClient] = {}
            self._created: dict[str, float] = {}
            self._feedback: dict[bytes, tuple[RemoteGoal, Callable[[RosMessage], None]]] = {}
        except BaseException:
            self.host.close()
            raise

    # -- what is served (the ROS graph) ---------------------------------------------------
    #: once a serve is discovered, how long its list of actions must stay the same before
    #: a tree missing from it counts as not served (its endpoints arrive one by one) [s]
    GRAPH_SETTLE = 0.5

    def served_actions(self) -> list[str]:
        """The ``/actorbt/...`` actions that have a server in the ROS graph now."""

        def query() -> list[str]:
            from rclpy.action.graph import get_action_names_and_types

            node = self.node
            return sorted(
                name
                for name, _ in get_action_names_and_types(node)
                if name.startswith(self.prefix) and node.count_services(f"{name}/_action/send_goal") > 0
            )

        return self.host.call(query)

    def served_trees(self) -> list[str]:
        """The trees served now (``nav.patrol`` for ``/actorbt/tree/nav/patrol``)."""
        return [t for t in (tree_of_action(a, self.namespace) for a in self.served_actions()) if t]

    def wait_for_serve(self, timeout: float | None = None) -> list[str]:
        """Wait until an ``actorbt serve`` is discovered and return its actions.

        Raises:
            NoServeError: none within ``timeout`` (default: this Remote's ``wait``) [s].
        """
        seconds = self.wait if timeout is None else timeout
        deadline = time.monotonic() + seconds
        while True:
            actions = self.served_actions()
            if actions:
                return actions
            if time.monotonic() >= deadline:
                raise NoServeError(seconds)
            time.sleep(0.02)

    def check_tree(self, tree: str, timeout: float | None = None) -> None:
        """Return once ``tree`` is served. Fails at once (after :data:`GRAPH_SETTLE`) when a
        serve is up without it.

        Raises:
            NoServeError: no ``actorbt serve`` within ``timeout`` [s] (default ``wait``).
            UnknownTreeError: the serve has no such tree (with close matches).
        """
        action = tree_action_name(tree, self.namespace)
        seconds = self.wait if timeout is None else timeout
        deadline = time.monotonic() + seconds
        actions = self.wait_for_serve(seconds)
        changed = time.monotonic()
        while action not in actions:
            now = time.monotonic()
            if now - changed >= self.GRAPH_SETTLE or now >= deadline:
                raise UnknownTreeError(tree, [t for t in (tree_of_action(a, self.namespace) for a in actions) if t])
            time.sleep(0.02)
            latest = self.served_actions()
            if latest != actions:
                actions, changed = latest, time.monotonic()

    # -- goals ---------------------------------------------------------------------------
    #: a new action client's feedback subscription needs a moment to be matched by the
    #: server's publisher, even once the server is discovered; feedback published
    #: before that is lost (ROS 2 feedback is volatile), so the first goal with a
    #: feedback callback waits this [s] (goals without one do not)
    SETTLE = 0.25

    def _client(self, action_type: type[RosAction], action: str) -> ActionClient:
        from rclpy.action import ActionClient
        from rclpy.qos import QoSProfile

        client = self._clients.get(action)
        if client is None:
            client = self._clients[action] = ActionClient(self.node, action_type, action)
            self._created[action] = time.monotonic()
            # Feedback through our own subscription: rclpy drops a goal's feedback
            # callback when its result arrives, and the result (a service reply) often
            # overtakes the last feedback message (a topic).
            self.node.create_subscription(
                action_type.Impl.FeedbackMessage, f"{action}/_action/feedback", self._on_feedback, QoSProfile(depth=100)
            )
        return client

    #: how long a finished goal still receives feedback that arrives late [s]
    FEEDBACK_GRACE = 2.0

    def _on_feedback(self, msg: RosMessage) -> None:
        entry = self._feedback.get(bytes(msg.goal_id.uuid))
        if entry is not None:
            entry[1](msg.feedback)

    def _prune_feedback(self) -> None:
        now = time.monotonic()
        for key, (g, _) in list(self._feedback.items()):
            if g.ended_at is not None and now - g.ended_at > self.FEEDBACK_GRACE:
                del self._feedback[key]

    def wait_for(self, action_type: type[RosAction], action: str, timeout: float | None = None) -> bool:
        """Wait until ``action`` is discovered; False after ``timeout`` [s]."""
        client = self.host.call(self._client, action_type, action)
        deadline = time.monotonic() + (self.wait if timeout is None else timeout)
        while not client.server_is_ready():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)
        return True

    def send(
        self,
        action_type: type[RosAction],
        action: str,
        goal: RosMessage,
        *,
        on_feedback: Callable[[RosMessage], None] | None = None,
        wait: float | None = None,
    ) -> RemoteGoal:
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
            settled = self._created[action] + (self.SETTLE if on_feedback is not None else 0.0)
            goal_id = uuid.uuid4().bytes
            self._prune_feedback()
            if on_feedback is not None:
                self._feedback[goal_id] = (g, on_feedback)
            g.call = GoalCall(
                _Settling(client, settled),
                action,
                self._waiter,
                goal,
                server_timeout=self.wait if wait is None else wait,
                on_result=g._on_result,
                on_error=g._on_error,
                on_accepted=g._on_accepted,
                on_status=g._on_status,
                goal_uuid=UUID(uuid=list(goal_id)),
            )
            g.call.start()

        self.host.post(start)  # cancel() is posted after it, so it finds g.call
        return g

    def tree_goal(
        self,
        tree: str,
        inputs: "dict | str | None" = None,
        *,
        on_feedback: Callable[[RosMessage], None] | None = None,
        wait: float | None = None,
    ) -> RemoteGoal:
        """Start a goal on ``/actorbt/tree/<tree>``; ``inputs`` a mapping or YAML text."""
        from actorbt_interfaces.action import RunTree

        text = inputs if isinstance(inputs, str) else (dump(inputs) if inputs else "")
        return self.send(
            RunTree,
            tree_action_name(tree, self.namespace),
            RunTree.Goal(inputs_yaml=text),
            on_feedback=on_feedback,
            wait=wait,
        )

    def run_tree(
        self,
        tree: str,
        inputs: "dict | str | None" = None,
        *,
        timeout: float | None = None,
        on_feedback: Callable[[RosMessage], None] | None = None,
    ) -> Value:
        """Run a tree to the end and return its outputs; raise RemoteCallError (failed,
        canceled), GoalRejectedError or ActorTimeout (then the goal is cancelled)."""
        g = self.tree_goal(tree, inputs, on_feedback=on_feedback)
        self._finish(g, timeout, f"tree {tree}")
        result = g.result
        assert result is not None  # _finish raised for a goal that did not succeed
        return yaml.safe_load(result.outputs_yaml) if result.outputs_yaml else {}

    def call_goal(self, actor: str, *args: Value, **kwargs: Value) -> RemoteGoal:
        """Start a call of ``actor`` through ``/actorbt/call``."""
        from actorbt_interfaces.action import CallActor

        text = dump({"args": list(args), "kwargs": kwargs}) if (args or kwargs) else ""
        return self.send(CallActor, self.call_action, CallActor.Goal(actor=actor, args_yaml=text))

    def call(self, actor: str, *args: Value, timeout: float | None = None, **kwargs: Value) -> Value:
        """Call ``actor`` in the served runtime and return its result (as YAML data)."""
        return self.finish(self.call_goal(actor, *args, **kwargs), timeout, f"actor {actor}")

    def finish(self, g: RemoteGoal, timeout: float | None = None, what: str | None = None) -> Value:
        """Wait for goal ``g`` and return its value as YAML data: a call's result, a tree's
        outputs. Cancels it after ``timeout`` [s] or on Ctrl-C; raises as :meth:`call`."""
        self._finish(g, timeout, what or g.action)
        res = g.result
        text = getattr(res, "result_yaml", None)
        if text is None:
            text = getattr(res, "outputs_yaml", "")
        return yaml.safe_load(text) if text else None

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
                detail = getattr(res, "error_msg", "") or getattr(res, "status", "")
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

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Settling:
    """An ActionClient whose server counts as ready only after ``settled`` (monotonic)."""

    def __init__(self, client: ActionClient, settled: float) -> None:
        self._client = client
        self._settled = settled

    def server_is_ready(self) -> bool:
        return self._client.server_is_ready() and time.monotonic() >= self._settled

    def __getattr__(self, name: str) -> Any:  # whatever the wrapped ActionClient has (rclpy: untyped)
        return getattr(self._client, name)
