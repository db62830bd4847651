"""``serve(rt)``: the runtime's actors and trees as ROS 2 actions, on node ``actorbt``.

What is served, and who does it:

- ``/actorbt/call`` (``actorbt_interfaces/action/CallActor``): call any actor
  (:mod:`bt_engine.ros.call_server`).
- ``/actorbt/tree/<name>`` (``RunTree``), one per tree actor (``ActorRef.is_tree``) that
  exists when ``serve`` is called (:mod:`bt_engine.ros.tree_server`). A tree in a
  subsystem (``nav.patrol``) is served as ``/actorbt/tree/nav/patrol``
  (:func:`bt_engine.ros.names.tree_action_name`).
- ``/actorbt/rejections``: why goals were rejected (below).

Goal semantics (the goal's way through is in :mod:`bt_engine.ros.goal_server`):

- A malformed goal (invalid YAML, unknown or missing inputs, wrong types, unknown actor,
  :mod:`bt_engine.ros.goals`) is **rejected**. The action protocol carries no reason
  with a rejection, so the reason is logged and published on ``/actorbt/rejections``
  (``std_msgs/String``, reliable, transient local): YAML ``{action, goal, reason}``
  where ``goal`` is :func:`~bt_engine.ros.names.goal_text` of the rejected goal.
  ``actorbt goal`` and ``actorbt rcall`` print it.
- Work starts only after acceptance (``rt.start`` with ``on_done``); a goal is marked
  succeeded only when the actor or tree has returned.
- Cancel: the goal's transaction is cancelled with ``"goal canceled"``, which halts a
  tree and cancels every transaction under it; the goal ends CANCELED.
- **A second goal for a tree that is running is rejected by default**
  (``preempt=False``). With ``preempt=True`` it cancels the running goal (which ends
  ABORTED with status ``aborted: preempted by a newer goal``) and runs once that has
  stopped. ``/actorbt/call`` goals run concurrently.
- ``close()`` cancels running goals (they end ABORTED, ``server shutting down``) and
  destroys the node.
- With ``record_dir``, every tree goal is recorded as a JSON Lines trace (the trees
  layer's TraceRecorder, runtime transactions included). ``actorbt serve`` records by
  default. The recorder observes every run of the runtime, so tree goals that overlap
  in time also see each other's events.
- ``on_event(line)`` hears one line per goal event (tree goal accepted, any goal
  rejected or ended, with its outcome and time; see :mod:`bt_engine.ros.goal_server`);
  ``actorbt serve`` prints them. They are logged at INFO level either way.

With the ROS transport (``--bus ros``, ``transport: ros``) the node lives in the transport's context and
executor thread; otherwise the server makes its own :class:`RosHost`.
"""
from __future__ import annotations

import logging
import pathlib
import time
from typing import Any, Callable

import yaml

from ..errors import Cancelled, Failure
from .call_server import CallServer
from .goal_server import GoalServer
from .host import RosClosedError, RosHost
from .names import CALL_ACTION, NODE_NAME, REJECTIONS_TOPIC, goal_text, rejections_qos, tree_action_name
from .transport import RosTransport
from .tree_server import TreeProgress, TreeServer

log = logging.getLogger("actorbt.ros.server")

#: seconds a finished goal's result is kept (see Server)
RESULT_TIMEOUT = 2

__all__ = ["Server", "serve"]


class Server:
    """The action servers of one runtime; see the module docstring.

    Args:
        rt: the runtime whose actors and trees are served.
        preempt: a goal for a running tree preempts it (default: it is rejected).
        node_name: the node's name.
        record_dir: record each tree goal as a trace in this folder (None: no traces).
        result_timeout: how long a finished goal's result stays available [s]. Every
            goal the server keeps is in every status message its clients decode, so a
            long timeout makes each goal slower (rclpy's default, 900 s, added about
            16 us per kept goal to every round trip here). rclpy clients ask for the
            result as soon as the goal is accepted, so a few seconds is plenty.
        on_event: called with one line per goal event (executor thread; must not block).
    """

    def __init__(self, rt: Any, *, preempt: bool = False, node_name: str = NODE_NAME,
                 record_dir: "str | pathlib.Path | None" = None,
                 result_timeout: int = RESULT_TIMEOUT,
                 on_event: Callable[[str], None] | None = None) -> None:
        from actorbt_interfaces.action import CallActor, RunTree
        from std_msgs.msg import String

        self.rt = rt
        self.preempt = preempt
        self.record_dir = record_dir
        self.on_event = on_event
        self.closing = False
        self._closed = False
        self._String = String
        bus = rt.bus
        self._own_host = not isinstance(bus, RosTransport)
        self.host: RosHost = RosHost("serve") if self._own_host else bus.host
        try:
            self.node = self.host.create_node(node_name)
            self._progress = TreeProgress(rt)
            self.endpoints: list[GoalServer] = [CallServer(self, CALL_ACTION, CallActor)]
            refs = rt.run_on_hub(lambda: sorted((r for r in rt.root.all_actors() if r.is_tree),
                                                key=lambda r: r.path))
            taken: set[str] = {CALL_ACTION}
            for ref in refs:
                name = tree_action_name(ref.path)
                if name in taken:
                    log.warning("tree %s is not served: %s is taken", ref.path, name)
                    continue
                taken.add(name)
                self.endpoints.append(TreeServer(self, name, RunTree, ref, self._progress))

            def create() -> None:
                self._rejections = self.node.create_publisher(String, REJECTIONS_TOPIC,
                                                              rejections_qos())
                for ep in self.endpoints:
                    ep.create(self.node, result_timeout)
            self.host.call(create)
            self._progress.install()
        except BaseException:
            if self._own_host:
                self.host.close()
            raise
        log.info("serving %s and %d trees", CALL_ACTION, len(self.endpoints) - 1)

    @property
    def actions(self) -> list[str]:
        """The action names served."""
        return [ep.action for ep in self.endpoints]

    def reject(self, action: str, goal: Any, reason: str) -> None:
        """Log and publish why ``goal`` on ``action`` was rejected (executor thread)."""
        # a warning, unless it is told through on_event anyway (`actorbt serve`)
        log.log(logging.INFO if self.on_event is not None else logging.WARNING,
                "%s: goal rejected: %s", action, reason)
        text = yaml.safe_dump({"action": action, "goal": goal_text(goal), "reason": reason},
                              sort_keys=False)
        try:
            self._rejections.publish(self._String(data=text))
        except Exception:
            log.exception("publishing a rejection failed")

    def announce(self, line: str) -> None:
        """One line about a goal: logged, and handed to ``on_event``."""
        log.info("%s", line)
        if self.on_event is not None:
            self.on_event(line)

    # -- lifecycle -----------------------------------------------------------------------
    def close(self, grace: float = 3.0) -> None:
        """Cancel running goals (they end aborted), then destroy the servers and node."""
        if self._closed:
            return
        self._closed = True
        self.closing = True
        host = self.host
        if not host.closed:
            try:
                goals = host.call(lambda: [g for ep in self.endpoints for g in ep.goals.values()])
            except RosClosedError:
                goals = []
            for g in goals:
                g.cancel("the server is shutting down")
            deadline = time.monotonic() + grace
            while goals and time.monotonic() < deadline:
                if all(g.finished.done() for g in goals):
                    break
                time.sleep(0.005)
            for g in goals:  # the runtime did not answer: end them anyway
                if not g.finished.done():
                    g.resolve(Failure(Cancelled(None, "the server is shutting down")))
            host.flush(timeout=1.0)   # the execute coroutines finish
            host.flush(timeout=1.0)   # their results go out
        self._progress.remove()
        if not host.closed:
            def destroy() -> None:
                for ep in self.endpoints:
                    ep.destroy()
                self.node.destroy_publisher(self._rejections)
            try:
                host.call(destroy)
                host.destroy_node(self.node)
            except RosClosedError:
                pass
        if self._own_host:
            host.close()

    def __enter__(self) -> "Server":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def serve(rt: Any, *, preempt: bool = False, node_name: str = NODE_NAME,
          record_dir: "str | pathlib.Path | None" = None,
          on_event: Callable[[str], None] | None = None) -> Server:
    """Expose ``rt``'s actors and trees as ROS 2 actions (see the module docstring).

    Returns the :class:`Server`; ``close()`` it before closing the runtime.
    """
    return Server(rt, preempt=preempt, node_name=node_name, record_dir=record_dir,
                  on_event=on_event)
