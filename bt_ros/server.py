"""``serve(rt)``: the runtime's actors and trees as ROS 2 actions, on node ``actorbt``.

What is served, and who does it (names in the node's namespace, see below):

- ``/actorbt/call`` (``actorbt_interfaces/action/CallActor``): call any actor
  (:mod:`bt_ros.call_server`).
- ``/actorbt/tree/<name>`` (``RunTree``), one per tree actor (``ActorRef.is_tree``)
  (:mod:`bt_ros.tree_server`). A tree in a subsystem (``nav.patrol``) is served
  as ``/actorbt/tree/nav/patrol`` (:func:`bt_ros.names.tree_action_name`). With
  ``trees_folder``, the folder is watched (:mod:`bt_ros.tree_watch`): a tree
  file added gets its action, a removed one's action is withdrawn (its running goal
  ends ``TREE_REMOVED``), a file that does not load is announced and not served.
- ``/actorbt/describe`` (``srv/Describe``): the JSON Schema of every served tree and
  actor (:mod:`bt_ros.describe_service`).
- ``/actorbt/call_now`` (``srv/CallActorNow``): a quick actor as a service
  (:mod:`bt_ros.call_now_service`).

Names: ``namespace`` puts the node, and so every name above, in a robot's namespace
(``robot1``: ``/robot1/actorbt/call``); ``ros_args`` are rclpy's arguments for the node
(``["-r", "__ns:=/robot1"]``, ``["-r", "/actorbt/tree/x:=/foo"]``). Actions are created
under the name the node resolves (rcl in Jazzy remaps topics and services, not action
names, so the server resolves them itself).

Goal semantics (the goal's way through is in :mod:`bt_ros.goal_server`):

- Results carry ``error_code`` and ``error_msg``, as Nav2's actions do; the codes are
  constants of the ``.action`` files (:mod:`bt_ros.error_codes`).
- A goal that cannot run (invalid YAML, unknown or missing inputs, wrong types, unknown
  actor, :mod:`bt_ros.goals`) is **accepted and aborted at once** with
  ``INVALID_GOAL`` and the reason in ``error_msg``, so a stock client sees why.
- Work starts only after acceptance (``rt.start`` with ``on_done``); a goal is marked
  succeeded only when the actor or tree has returned.
- Feedback carries ``elapsed``; a tree's names the active node from the first message
  on, and the last feedback goes out before the result.
- Cancel: the goal's transaction is cancelled with ``"goal canceled"``, which halts a
  tree and cancels every transaction under it; the goal ends CANCELED.
- **A second goal for a tree that is running is refused by default** (``preempt=False``;
  aborted at once, ``BUSY``). With ``preempt=True`` it cancels the running goal (which
  ends ABORTED, ``PREEMPTED``, status ``aborted: preempted by a newer goal``) and runs
  once that has stopped. ``/actorbt/call`` goals run concurrently.
- ``close()`` cancels running goals (they end ABORTED, ``SHUTDOWN``) and destroys the
  node.
- With ``record_dir``, every tree goal is recorded as a JSON Lines trace (the trees
  layer's TraceRecorder, runtime transactions included). ``actorbt serve`` records by
  default. The recorder observes every run of the runtime, so tree goals that overlap
  in time also see each other's events.
- ``on_event(line)`` hears one line per goal event (tree goal accepted, any goal
  refused or ended, with its outcome and time; see :mod:`bt_ros.goal_server`)
  and per change of the served trees; ``actorbt serve`` prints them. They are logged at
  INFO level either way.

With the ROS transport (``--bus ros``, ``transport: ros``) the node lives in the transport's context and
executor thread; otherwise the server makes its own :class:`RosHost`.
"""

from __future__ import annotations

import logging
import pathlib
import time
from typing import TYPE_CHECKING, Callable

from bt_engine.errors import Cancelled, Failure
from .call_now_service import CallNowService
from .call_server import CallServer
from .describe_service import DescribeService
from .error_codes import Ending
from .goal_server import GoalServer
from .goals import GoalError
from .host import RosClosedError, RosHost
from .names import CALL_ACTION, CALL_NOW_SERVICE, DESCRIBE_SERVICE, NODE_NAME, relative, tree_action_name
from .transport import RosTransport
from .tree_server import TreeProgress, TreeServer
from .tree_watch import TreeFolderWatch

if TYPE_CHECKING:
    from bt_engine import ActorRef, Runtime
    from .goal_server import ServedGoal

log = logging.getLogger("actorbt.ros.server")

#: seconds a finished goal's result is kept (see Server)
RESULT_TIMEOUT = 1
#: seconds a withdrawn tree's action server outlives its last goal (its result goes out)
WITHDRAW_DELAY = 0.5

__all__ = ["Server", "serve"]


class Server:
    """The action servers of one runtime; see the module docstring.

    Args:
        rt: the runtime whose actors and trees are served.
        preempt: a goal for a running tree preempts it (default: it is refused).
        node_name: the node's name.
        namespace: the node's namespace (``robot1``; default: the root).
        ros_args: rclpy arguments for the node (remapping: ``["-r", "from:=to"]``).
        record_dir: record each tree goal as a trace in this folder (None: no traces).
        result_timeout: how long a finished goal's result stays available [s]. Every
            goal the server keeps is in every status message (three per goal) that the
            server publishes and each client decodes, so a long timeout makes each goal
            slower (rclpy's default, 900 s, added about 16 us per kept goal to every
            round trip here; with goals back to back, 2 s kept some 250 goals and cost a
            plain rclpy client about 2 ms a goal). rclpy clients ask for the result as
            soon as the goal is accepted, so a second is plenty.
        on_event: called with one line per goal event (executor thread; must not block).
        trees_folder: watch this folder and serve its trees as they come and go
            (None: the trees of ``rt`` when the server starts, for good).
        watch_period: seconds between two looks at ``trees_folder``.
    """

    def __init__(
        self,
        rt: Runtime,
        *,
        preempt: bool = False,
        node_name: str = NODE_NAME,
        namespace: str | None = None,
        ros_args: list[str] | None = None,
        record_dir: "str | pathlib.Path | None" = None,
        result_timeout: int = RESULT_TIMEOUT,
        on_event: Callable[[str], None] | None = None,
        trees_folder: "str | pathlib.Path | None" = None,
        watch_period: float = 1.0,
    ) -> None:
        from actorbt_interfaces.action import CallActor

        self.rt = rt
        self.preempt = preempt
        self.record_dir = record_dir
        self.on_event = on_event
        self.closing = False
        self._closed = False
        self._result_timeout = result_timeout
        self._watch: TreeFolderWatch | None = None
        bus = rt.bus
        self._own_host = not isinstance(bus, RosTransport)
        self.host: RosHost = bus.host if isinstance(bus, RosTransport) else RosHost("serve")
        try:
            self.node = self.host.create_node(node_name, namespace or None, ros_args=ros_args)
            #: the node's namespace, as clients name it (``/robot1``; ``/`` for the root)
            self.namespace = self.node.get_namespace()
            self._progress = TreeProgress(rt)
            self.call_server = CallServer(self, self.resolve(CALL_ACTION), CallActor)
            self.trees: dict[str, TreeServer] = {}  # tree path -> its action server
            self.describe = DescribeService(rt, self.resolve(DESCRIBE_SERVICE, service=True), self._served)
            self.call_now = CallNowService(rt, self.host, self.resolve(CALL_NOW_SERVICE, service=True))

            def create() -> None:
                self.call_server.create(self.node, result_timeout)
                self.describe.create(self.node)
                self.call_now.create(self.node)

            self.host.call(create)
            self.sync_trees(announce=False)
            self._progress.install()
            if trees_folder is not None:
                self._watch = TreeFolderWatch(rt, trees_folder, self._reloaded, watch_period).start()
        except BaseException:
            if self._own_host:
                self.host.close()
            raise
        log.info("serving %s and %d trees", self.call_server.action, len(self.trees))

    @property
    def endpoints(self) -> list[GoalServer]:
        """The action servers: ``/actorbt/call``, then the trees'."""
        return [self.call_server, *sorted(self.trees.values(), key=lambda ep: ep.action)]

    @property
    def actions(self) -> list[str]:
        """The action names served."""
        return [ep.action for ep in self.endpoints]

    @property
    def services(self) -> list[str]:
        """The service names served."""
        return [self.describe.name, self.call_now.name]

    def resolve(self, name: str, *, service: bool = False) -> str:
        """The full name ``name`` (a root-namespace name) has on this node: its namespace
        and remapping applied."""
        resolver = self.node.resolve_service_name if service else self.node.resolve_topic_name
        return resolver(relative(name))

    def _served(self) -> tuple[dict[str, str], str, str]:
        """For describe: tree path -> action, the call action, the namespace."""
        trees = {path: ep.action for path, ep in list(self.trees.items()) if ep.withdrawn is None}
        return trees, self.call_server.action, self.namespace

    def announce(self, line: str) -> None:
        """One line about a goal or the served trees: logged, and handed to ``on_event``."""
        log.info("%s", line)
        if self.on_event is not None:
            self.on_event(line)

    # -- the served trees ----------------------------------------------------------------
    def sync_trees(self, *, announce: bool = True, grace: float = 3.0) -> None:
        """Serve exactly the runtime's tree actors now: new ones get an action, gone ones
        are withdrawn (their goals end ``TREE_REMOVED``). Not on the hub or executor."""
        refs = self.rt.run_on_hub(
            lambda: sorted((r for r in self.rt.root.all_actors() if r.is_tree), key=lambda r: r.path)
        )
        gone = self.host.call(self._apply_trees, refs, announce)
        if not gone:
            return
        goals = self.host.call(lambda: [g for ep in gone for g in ep.goals.values()])
        _wait_finished(goals, grace)
        # their results must be out before the action server goes, or a client waits for
        # a result forever
        self._flush_results()
        time.sleep(WITHDRAW_DELAY)

        def destroy_gone() -> None:
            for ep in gone:
                ep.destroy()

        self.host.call(destroy_gone)

    def _apply_trees(self, refs: list[ActorRef], announce: bool) -> list[TreeServer]:
        """(executor thread) Create and withdraw tree action servers; the withdrawn."""
        from actorbt_interfaces.action import RunTree

        wanted = {ref.path: ref for ref in refs}
        gone = []
        for path in [p for p in self.trees if p not in wanted]:
            ep = self.trees.pop(path)
            ep.withdrawn = GoalError(
                f"tree {path} is no longer served: its file was removed from the trees folder", Ending.TREE_REMOVED
            )
            for g in list(ep.goals.values()):
                g.cancel("the tree's file was removed", Ending.TREE_REMOVED)
            gone.append(ep)
            if announce:
                self.announce(f"tree {path}: withdrawn {ep.action}")
        taken = {ep.action for ep in self.endpoints}
        for path, ref in wanted.items():
            served = self.trees.get(path)
            if served is not None:
                served.ref = ref  # an edited file: the same action, the new tree
                continue
            name = self.resolve(tree_action_name(path))
            if name in taken:
                log.warning("tree %s is not served: %s is taken", path, name)
                continue
            taken.add(name)
            ep = TreeServer(self, name, RunTree, ref, self._progress)
            ep.create(self.node, self._result_timeout)
            self.trees[path] = ep
            if announce:
                self.announce(f"tree {path}: served on {name}")
        return gone

    def _reloaded(self, errors: list[str]) -> None:
        """(watch thread) The trees folder was loaded again."""
        for text in errors:
            self.announce(f"tree file not served: {text}")
        if not self.closing:
            self.sync_trees()

    def _flush_results(self) -> None:
        self.host.flush(timeout=1.0)  # the execute coroutines finish
        self.host.flush(timeout=1.0)  # their results go out

    # -- lifecycle -----------------------------------------------------------------------
    def close(self, grace: float = 3.0) -> None:
        """Cancel running goals (they end aborted), then destroy the servers and node."""
        if self._closed:
            return
        self._closed = True
        self.closing = True
        if self._watch is not None:
            self._watch.close()
        host = self.host
        if not host.closed:
            try:
                goals = host.call(lambda: [g for ep in self.endpoints for g in ep.goals.values()])
            except RosClosedError:
                goals = []
            for g in goals:
                g.cancel("the server is shutting down", Ending.SHUTDOWN)
            _wait_finished(goals, grace)
            for g in goals:  # the runtime did not answer: end them anyway
                if not g.finished.done():
                    g.cancel_ending = Ending.SHUTDOWN
                    g.resolve(Failure(Cancelled(None, "the server is shutting down")))
            self._flush_results()
        self._progress.remove()
        if not host.closed:

            def destroy() -> None:
                for ep in self.endpoints:
                    ep.destroy()
                self.describe.destroy()
                self.call_now.destroy()

            try:
                host.call(destroy)
                host.destroy_node(self.node)
            except RosClosedError:
                pass
        if self._own_host:
            host.close()

    def __enter__(self) -> "Server":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _wait_finished(goals: list[ServedGoal], grace: float) -> None:
    """Wait up to ``grace`` [s] for ``goals`` to finish (not on the executor thread)."""
    deadline = time.monotonic() + grace
    while goals and not all(g.finished.done() for g in goals) and time.monotonic() < deadline:
        time.sleep(0.005)


def serve(
    rt: Runtime,
    *,
    preempt: bool = False,
    node_name: str = NODE_NAME,
    namespace: str | None = None,
    ros_args: list[str] | None = None,
    record_dir: "str | pathlib.Path | None" = None,
    on_event: Callable[[str], None] | None = None,
    trees_folder: "str | pathlib.Path | None" = None,
) -> Server:
    """Expose ``rt``'s actors and trees as ROS 2 actions (see the module docstring).

    Returns the :class:`Server`; ``close()`` it before closing the runtime.
    """
    return Server(
        rt,
        preempt=preempt,
        node_name=node_name,
        namespace=namespace,
        ros_args=ros_args,
        record_dir=record_dir,
        on_event=on_event,
        trees_folder=trees_folder,
    )
