"""``serve(rt)``: the runtime's actors and trees as ROS 2 actions, on node ``actorbt``.

- ``/actorbt/call`` (``actorbt_interfaces/action/CallActor``): call any actor.
  ``args_yaml`` is parsed with ``yaml.safe_load`` (see ``yamlio.parse_call_args``);
  ``result_yaml`` is the result as YAML, ``error`` the failure.
- ``/actorbt/tree/<name>`` (``RunTree``), one per tree actor (``ActorRef.is_tree``) that
  exists when ``serve`` is called: ``inputs_yaml`` is a mapping of the tree's inputs,
  checked against its declared inputs before the goal is accepted. The result carries
  ``success``, ``status`` and the outputs as YAML. A tree in a subsystem
  (``nav.patrol``) is served as ``/actorbt/tree/nav/patrol``.

Goal semantics:

- A malformed goal (invalid YAML, unknown or missing inputs, wrong types, unknown actor)
  is **rejected**. The action protocol carries no reason with a rejection, so the
  reason is logged and published on ``/actorbt/rejections`` (``std_msgs/String``,
  reliable, transient local): YAML ``{action, goal, reason}`` where ``goal`` is
  :func:`goal_text` of the rejected goal. ``actorbt goal`` and ``actorbt rcall`` print it.
- Work starts only after acceptance (``rt.start`` with ``on_done``); a goal is marked
  succeeded only when the actor or tree has returned.
- Feedback: one message when the work starts (``status: running``); for trees of the
  trees layer, one after every tick in which a node changed status (``active_node`` is
  the running tip, through nested trees joined with `` > ``; ``tick_count`` the root
  run's ticks), and a last one when the run finishes.
- Cancel: the tree's transaction is cancelled with ``"goal canceled"``, which halts the
  tree and cancels every transaction under it; the goal ends CANCELED.
- **A second goal for a tree that is running is rejected by default**
  (``preempt=False``). With ``preempt=True`` it cancels the running goal (which ends
  ABORTED with status ``aborted: preempted by a newer goal``) and runs once that has
  stopped. ``/actorbt/call`` goals run concurrently.
- ``close()`` cancels running goals (they end ABORTED, ``server shutting down``) and
  destroys the node.
- With ``record_dir``, every tree goal is recorded as a JSON Lines trace (the trees
  layer's TraceRecorder, runtime transactions included) in
  ``<record_dir>/<time>-<tree>-<goal id>.jsonl``. ``actorbt serve`` records by default.
  The recorder observes every run of the runtime, so tree goals that overlap in time
  also see each other's events.

With the ROS transport (``--ros``) the node lives in the transport's context and
executor thread; otherwise the server makes its own :class:`RosHost`.
"""
from __future__ import annotations

import functools
import logging
import pathlib
import re
import time
from typing import Any

import yaml

from ..errors import ActorbtError, BadArgumentsError, Cancelled, Failure
from .host import RosClosedError, RosHost
from .yamlio import GoalError, dump, parse_call_args, parse_inputs

log = logging.getLogger("actorbt.ros.server")

NODE_NAME = "actorbt"
CALL_ACTION = "/actorbt/call"
TREE_PREFIX = "/actorbt/tree/"
REJECTIONS_TOPIC = "/actorbt/rejections"
#: seconds a finished goal's result is kept (see Server)
RESULT_TIMEOUT = 2

__all__ = ["CALL_ACTION", "REJECTIONS_TOPIC", "TREE_PREFIX", "Server", "goal_text",
           "rejections_qos", "serve", "tree_action_name"]


def tree_action_name(tree: str) -> str:
    """``/actorbt/tree/<name>`` for a tree path (dots become slashes)."""
    parts = []
    for part in tree.replace("/", ".").split("."):
        part = re.sub(r"[^A-Za-z0-9_]", "_", part)
        if part and part[0].isdigit():
            part = "_" + part
        if part:
            parts.append(part)
    return TREE_PREFIX + "/".join(parts)


def goal_text(goal: Any) -> str:
    """What identifies a goal in a rejection message: the inputs of a RunTree goal,
    ``actor`` and ``args_yaml`` of a CallActor goal."""
    if hasattr(goal, "inputs_yaml"):
        return goal.inputs_yaml
    return f"{goal.actor}\n{goal.args_yaml}"


def rejections_qos() -> Any:
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    return QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


class _Endpoint:
    """One action server: /actorbt/call, or one tree."""

    def __init__(self, kind: str, action: str, action_type: type, ref: Any = None) -> None:
        self.kind = kind
        self.action = action
        self.action_type = action_type
        self.ref = ref
        self.server: Any = None
        self.active: _Goal | None = None  # the running tree goal
        self.reserved = 0  # accepted, not yet executing
        self.goals: dict[bytes, _Goal] = {}


class _Goal:
    """One accepted goal. Fields are touched on the thread named in each method."""

    def __init__(self, server: "Server", ep: _Endpoint, handle: Any) -> None:
        from rclpy.task import Future
        self.server = server
        self.ep = ep
        self.handle = handle
        self.key = bytes(handle.goal_id.uuid)
        self.path = ""
        self.args: list = []
        self.kwargs: dict = {}
        self.txn: Any = None
        self.cancel_reason: str | None = None
        self.resolved = False
        self.outcome = Future()   # set on the executor thread
        self.finished = Future()  # set when the execute coroutine has ended
        self.top: Any = None      # the root TreeRun, when the trees layer reports one
        self.last_run: Any = None
        self.final: str | None = None
        self.flush_scheduled = False
        self.recorder: Any = None
        self.trace_path: str | None = None

    # -- hub -----------------------------------------------------------------------------
    def start_on_hub(self) -> None:
        rt = self.server.rt
        if self.cancel_reason is not None:
            self.resolve(Failure(Cancelled(None, self.cancel_reason)))
            return
        if self.ep.kind == "tree" and self.server.record_dir is not None:
            self._open_trace()
        try:
            txn = rt.start(self.path, *self.args, on_done=self.on_done, **self.kwargs)
        except BaseException as e:  # bad arguments found late, runtime closing
            self._close_trace()
            self.resolve(Failure(e))
            return
        self.txn = txn
        if not self.resolved:
            self.server._by_txn[txn.id] = self

    def on_done(self, outcome: Any) -> None:
        if self.txn is not None:
            self.server._by_txn.pop(self.txn.id, None)
        if self.flush_scheduled:
            self.flush()
        self._close_trace()
        self.resolve(outcome)

    def _open_trace(self) -> None:
        try:
            from ..trees import TraceRecorder, tree_host
            host = tree_host(self.server.rt)
            if host is None:
                return
            folder = pathlib.Path(self.server.record_dir)
            folder.mkdir(parents=True, exist_ok=True)
            stamp = time.strftime("%Y%m%d-%H%M%S")
            gid = self.key.hex()[:8]
            path = folder / f"{stamp}-{self.path.replace('.', '_')}-{gid}.jsonl"
            self.recorder = TraceRecorder(path, host, tree=self.path, inputs=self.kwargs,
                                          transactions=True)
            self.trace_path = str(path)
        except Exception:
            log.exception("cannot record the goal for %s", self.path)

    def _close_trace(self) -> None:
        rec, self.recorder = self.recorder, None
        if rec is not None:
            try:
                rec.close()
            except Exception:
                log.exception("closing the trace %s failed", self.trace_path)

    def cancel_on_hub(self, reason: str) -> None:
        if self.cancel_reason is None:
            self.cancel_reason = reason
        if self.txn is not None and not self.txn.done:
            self.txn.cancel(reason)

    def resolve(self, outcome: Any) -> None:
        """Hand the outcome to the execute coroutine (any thread)."""
        if self.resolved:
            return
        self.resolved = True
        try:
            self.server.host.post(self._set_outcome, outcome)
        except RosClosedError:
            pass

    def progress(self, run: Any, top: Any, final: str | None = None) -> None:
        """A tree run under this goal changed (hub, from the trees layer's observer)."""
        self.top = top
        self.last_run = run
        if final is not None and run is top:
            self.final = final
        if not self.flush_scheduled:
            self.flush_scheduled = True
            self.server.rt.hub.call_soon(self.flush)

    def flush(self) -> None:
        """Publish one feedback message for the changes since the last one (hub)."""
        if not self.flush_scheduled:
            return
        self.flush_scheduled = False
        top, run = self.top, self.last_run
        if top is None:
            return
        chain = []
        r = run
        while r is not None:
            chain.append(r)
            if r is top:
                break
            r = r.parent
        tips = []
        for r in reversed(chain):
            try:
                tip = r.tip_path()
            except Exception:
                tip = None
            if tip:
                tips.append(tip if r is top else f"{r.mission.name}:{tip}")
        status = self.final or _status_name(getattr(top, "status", None))
        self.send_feedback(status, " > ".join(tips), int(getattr(top, "ticks", 0)))

    def send_feedback(self, status: str, active: str = "", ticks: int = 0) -> None:
        """Publish feedback (from any thread; it is sent from the executor thread)."""
        fb_type = self.ep.action_type.Feedback
        if self.ep.kind == "tree":
            fb = fb_type(status=status, active_node=active, tick_count=max(0, ticks))
        else:
            fb = fb_type(status=status)
        host = self.server.host
        if host.in_executor_thread():
            self.handle.publish_feedback(fb)
            return
        try:
            host.post(self.handle.publish_feedback, fb)
        except RosClosedError:
            pass

    # -- executor thread ---------------------------------------------------------------
    def _set_outcome(self, outcome: Any) -> None:
        if not self.outcome.done():
            self.outcome.set_result(outcome)


def _status_name(status: Any) -> str:
    name = (getattr(status, "name", None) or str(status or "running")).lower()
    return "halted" if name == "invalid" else name


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
    """

    def __init__(self, rt: Any, *, preempt: bool = False, node_name: str = NODE_NAME,
                 record_dir: "str | pathlib.Path | None" = None,
                 result_timeout: int = RESULT_TIMEOUT) -> None:
        from actorbt_interfaces.action import CallActor, RunTree
        from rclpy.action import ActionServer
        from std_msgs.msg import String

        from ..bus.ros import RosTransport

        self.rt = rt
        self.preempt = preempt
        self.record_dir = record_dir
        self._closing = False
        self._closed = False
        self._by_txn: dict[int, _Goal] = {}  # hub only
        self._parsed: dict[int, tuple[Any, tuple]] = {}  # executor thread only
        self._String = String
        bus = rt.bus
        self._own_host = not isinstance(bus, RosTransport)
        self.host: RosHost = RosHost("serve") if self._own_host else bus.host
        try:
            self.node = self.host.create_node(node_name)
            refs = rt.run_on_hub(lambda: sorted((r for r in rt.root.all_actors() if r.is_tree),
                                                key=lambda r: r.path))
            self.endpoints: list[_Endpoint] = [_Endpoint("call", CALL_ACTION, CallActor)]
            seen: set[str] = {CALL_ACTION}
            for ref in refs:
                name = tree_action_name(ref.path)
                if name in seen:
                    log.warning("tree %s is not served: %s is taken", ref.path, name)
                    continue
                seen.add(name)
                self.endpoints.append(_Endpoint("tree", name, RunTree, ref))

            def create() -> None:
                self._rejections = self.node.create_publisher(String, REJECTIONS_TOPIC,
                                                              rejections_qos())
                for ep in self.endpoints:
                    ep.server = ActionServer(
                        self.node, ep.action_type, ep.action, result_timeout=result_timeout,
                        execute_callback=functools.partial(self._execute, ep),
                        goal_callback=lambda goal, ep=ep: self._on_goal(ep, goal),
                        cancel_callback=lambda gh, ep=ep: self._on_cancel(ep, gh))
            self.host.call(create)
            self._observer = self._watch_trees()
        except BaseException:
            if self._own_host:
                self.host.close()
            raise
        log.info("serving %s and %d trees", CALL_ACTION, len(self.endpoints) - 1)

    @property
    def actions(self) -> list[str]:
        """The action names served."""
        return [ep.action for ep in self.endpoints]

    @property
    def trees(self) -> list[str]:
        """The tree actors served (paths)."""
        return [ep.ref.path for ep in self.endpoints if ep.kind == "tree"]

    # -- tree progress ---------------------------------------------------------------
    def _watch_trees(self) -> Any:
        try:
            from ..trees import TreeObserver, tree_host
        except ImportError:
            return None
        host = tree_host(self.rt)
        if host is None:
            return None
        server = self

        class Progress(TreeObserver):
            def _goal(self, run: Any) -> tuple[Any, Any]:
                top = run
                while getattr(top, "parent", None) is not None:
                    top = top.parent
                return server._by_txn.get(getattr(top, "txn_id", None)), top

            def run_started(self, run: Any) -> None:
                g, top = self._goal(run)
                if g is not None:
                    g.progress(run, top)

            def status_changed(self, run: Any, path: str, old: Any, new: Any) -> None:
                g, top = self._goal(run)
                if g is not None:
                    g.progress(run, top)

            def run_finished(self, run: Any, status: Any, outcome: Any) -> None:
                g, top = self._goal(run)
                if g is not None:
                    g.progress(run, top, final=_status_name(status) if run is top else None)

        obs = Progress()
        self.rt.run_on_hub(host.observers.append, obs)
        self._tree_host = host
        return obs

    def _mission(self, ref: Any) -> Any:
        """The trees layer's Mission for a tree actor, when it has one (type checks)."""
        try:
            from ..trees import tree_host
            host = tree_host(self.rt)
            if host is None or ref.path != ref.name:
                return None
            mission = host.library[ref.name]
            return mission if hasattr(mission, "bind_inputs") else None
        except Exception:
            return None

    # -- goals (executor thread) -------------------------------------------------------
    def _parse(self, ep: _Endpoint, goal: Any) -> tuple[str, list, dict]:
        """(actor path, args, kwargs) of a goal, or GoalError with the reason."""
        if ep.kind == "tree":
            inputs = parse_inputs(goal.inputs_yaml)
            mission = self._mission(ep.ref)
            try:
                if mission is not None:
                    mission.bind_inputs(**inputs)
                else:
                    ep.ref.check_args((), inputs)
            except (ActorbtError, TypeError, ValueError) as e:
                raise GoalError(str(e)) from None
            return ep.ref.path, [], inputs
        name = goal.actor.strip()
        if not name:
            raise GoalError("no actor named in the goal")
        args, kwargs = parse_call_args(goal.args_yaml)
        try:
            ref = self.rt.run_on_hub(self.rt.root.resolve, name)
            ref.check_args(tuple(args), kwargs)
        except BadArgumentsError as e:
            raise GoalError(str(e)) from None
        except ActorbtError as e:
            raise GoalError(str(e)) from None
        return ref.path, args, kwargs

    def _on_goal(self, ep: _Endpoint, goal: Any) -> Any:
        from rclpy.action import GoalResponse
        try:
            if self._closing:
                raise GoalError("the server is shutting down")
            parsed = self._parse(ep, goal)
            if ep.kind == "tree" and not self.preempt and (ep.active is not None or ep.reserved):
                raise GoalError(f"tree {ep.ref.path} is already running a goal; cancel it "
                                "first (this server rejects a second goal: it was started "
                                "without preempt)")
        except GoalError as e:
            self._reject(ep, goal, str(e))
            return GoalResponse.REJECT
        ep.reserved += 1
        # rclpy hands the same goal message to the execute callback: keep the parse.
        if len(self._parsed) > 1000:  # goals accepted but never executed (cannot happen)
            self._parsed.clear()
        self._parsed[id(goal)] = (goal, parsed)
        return GoalResponse.ACCEPT

    def _reject(self, ep: _Endpoint, goal: Any, reason: str) -> None:
        log.warning("%s: goal rejected: %s", ep.action, reason)
        text = yaml.safe_dump({"action": ep.action, "goal": goal_text(goal), "reason": reason},
                              sort_keys=False)
        try:
            self._rejections.publish(self._String(data=text))
        except Exception:
            log.exception("publishing a rejection failed")

    def _on_cancel(self, ep: _Endpoint, handle: Any) -> Any:
        from rclpy.action import CancelResponse
        g = ep.goals.get(bytes(handle.goal_id.uuid))
        if g is not None:
            self._to_hub(g, g.cancel_on_hub, "goal canceled")
        return CancelResponse.ACCEPT

    def _to_hub(self, g: _Goal, fn: Any, *args: Any) -> None:
        try:
            self.rt.call_soon_threadsafe(fn, *args)
        except Exception:  # the runtime is gone: the work cannot run any more
            g.resolve(Failure(Cancelled(None, "the runtime is closed")))

    async def _execute(self, ep: _Endpoint, handle: Any) -> Any:
        ep.reserved = max(0, ep.reserved - 1)
        g = _Goal(self, ep, handle)
        ep.goals[g.key] = g
        try:
            try:
                kept = self._parsed.pop(id(handle.request), None)
                if kept is not None and kept[0] is handle.request:
                    g.path, g.args, g.kwargs = kept[1]
                else:
                    g.path, g.args, g.kwargs = self._parse(ep, handle.request)
            except GoalError as e:  # the world changed since the goal was accepted
                handle.abort()
                return self._result(ep, False, f"failed: {e}", None, str(e))
            if ep.kind == "tree":
                prev = ep.active
                if prev is not None:
                    self._to_hub(prev, prev.cancel_on_hub, "preempted by a newer goal")
                    await prev.finished
                ep.active = g
            if handle.is_cancel_requested or self._closing:
                if handle.is_cancel_requested:
                    handle.canceled()
                    return self._result(ep, False, "canceled", None, "goal canceled")
                handle.abort()
                return self._result(ep, False, "aborted: the server is shutting down", None,
                                    "the server is shutting down")
            g.send_feedback("running")
            self._to_hub(g, g.start_on_hub)
            outcome = await g.outcome
            return self._conclude(g, outcome)
        finally:
            if ep.active is g:
                ep.active = None
            ep.goals.pop(g.key, None)
            g.finished.set_result(True)

    def _conclude(self, g: _Goal, outcome: Any) -> Any:
        handle, ep = g.handle, g.ep
        if g.top is None and ep.kind == "tree":
            # No progress from the trees layer for this actor: a last feedback at the end.
            fb = ep.action_type.Feedback(status="success" if not isinstance(outcome, Failure)
                                         else "failure", active_node="", tick_count=0)
            handle.publish_feedback(fb)
        if not isinstance(outcome, Failure):
            handle.succeed()
            return self._result(ep, True, "succeeded", outcome, "")
        exc = outcome.exception
        if outcome.cancelled or isinstance(exc, Cancelled):
            reason = getattr(exc, "reason", "") or str(exc)
            if handle.is_cancel_requested:
                handle.canceled()
                return self._result(ep, False, "canceled", None, reason)
            handle.abort()
            return self._result(ep, False, f"aborted: {reason}", None, reason)
        handle.abort()
        return self._result(ep, False, f"failed: {exc}", None, f"{type(exc).__name__}: {exc}")

    @staticmethod
    def _result(ep: _Endpoint, success: bool, status: str, value: Any, error: str) -> Any:
        res = ep.action_type.Result()
        res.success = success
        if ep.kind == "tree":
            res.status = status
            res.outputs_yaml = dump(value) if success else ""
        else:
            res.result_yaml = dump(value) if success else ""
            res.error = error
        return res

    # -- lifecycle -----------------------------------------------------------------------
    def close(self, grace: float = 3.0) -> None:
        """Cancel running goals (they end aborted), then destroy the servers and node."""
        if self._closed:
            return
        self._closed = True
        self._closing = True
        host = self.host
        if not host.closed:
            try:
                goals = host.call(lambda: [g for ep in self.endpoints for g in ep.goals.values()])
            except RosClosedError:
                goals = []
            for g in goals:
                self._to_hub(g, g.cancel_on_hub, "the server is shutting down")
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
        if self._observer is not None:
            try:
                self.rt.run_on_hub(self._tree_host.observers.remove, self._observer)
            except Exception:
                pass
        if not host.closed:
            def destroy() -> None:
                for ep in self.endpoints:
                    if ep.server is not None:
                        ep.server.destroy()
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
          record_dir: "str | pathlib.Path | None" = None) -> Server:
    """Expose ``rt``'s actors and trees as ROS 2 actions (see the module docstring).

    Returns the :class:`Server`; ``close()`` it before closing the runtime.
    """
    return Server(rt, preempt=preempt, node_name=node_name, record_dir=record_dir)

