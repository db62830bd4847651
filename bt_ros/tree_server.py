"""The RunTree action of one tree, ``/actorbt/tree/<name>``: one goal at a time,
feedback from the trees layer's progress, and a trace of every goal.

- A second goal for a running tree is refused (aborted at once, ``BUSY``), unless the
  owner preempts: then the running goal is cancelled (``preempted by a newer goal``,
  ``PREEMPTED``) and the new one starts once it has stopped.
- Feedback, each with ``elapsed`` (seconds since the work started): one message right
  after the goal starts (``running``; ``active_node`` the tree's name until the first
  tick tells the running node); for missions of the trees layer, one message after
  every tick in which a node changed status (``active_node`` is the running tip, through
  nested trees joined with `` > ``; ``tick_count`` the root run's ticks) and a last one
  when the run finishes, before the result. Other tree actors get a last ``success`` or
  ``failure``.
- With the owner's ``record_dir``, each goal is recorded as a JSON Lines trace,
  ``<record_dir>/<time>-<tree>-<goal id>.jsonl``, that ``actorbt replay`` replays.
  The recorder follows the goal's transaction, so the trace holds only the goal's runs
  (not those of other goals that overlap it), and it records the wall clock
  (``clock: wall`` in the header): the replay compares times relative to the run's
  start, with a tolerance (see :mod:`bt_tools.replay`).
"""

from __future__ import annotations

import logging
import pathlib
import time
from typing import TYPE_CHECKING

from bt_engine.bus.messages import RosAction, RosMessage
from .error_codes import Ending
from .goal_server import GoalServer, Owner, ServedGoal, one_line, shown_path
from .goals import GoalError, Invocation, decode_tree_goal
from .rostypes import Outcome, Value
from .yamlio import dump, flow

if TYPE_CHECKING:
    from py_trees.common import Status
    from rclpy.action.server import ServerGoalHandle

    from bt_engine import ActorRef, Runtime, Transaction
    from bt_engine.trees import TraceRecorder, TreeHost, TreeObserver, TreeRun

log = logging.getLogger("actorbt.ros.server")

__all__ = ["TreeGoal", "TreeProgress", "TreeServer"]


def _status_name(status: Status | None) -> str:
    name = (getattr(status, "name", None) or str(status or "running")).lower()
    return "halted" if name == "invalid" else name


class TreeProgress:
    """Routes the trees layer's run events to the goal whose transaction runs the root
    run. One per server; its table is touched on the hub only."""

    def __init__(self, rt: Runtime) -> None:
        self.rt = rt
        self.goals: dict[int, TreeGoal] = {}  # transaction id -> goal
        self._host: TreeHost | None = None
        self._observer: TreeObserver | None = None

    def install(self) -> None:
        """Observe the runtime's tree runs (not on the hub: it waits for the hub)."""
        try:
            from bt_engine.trees import TreeObserver, tree_host
        except ImportError:  # a build without the trees layer
            return
        host = tree_host(self.rt)
        if host is None:
            return
        progress = self

        class Observer(TreeObserver):
            def run_started(self, run: TreeRun) -> None:
                progress._changed(run)

            def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
                progress._changed(run)

            def run_finished(self, run: TreeRun, status: Status, outcome: Outcome) -> None:
                progress._changed(run, status)

        observer = Observer()
        self.rt.run_on_hub(host.observers.append, observer)
        self._host, self._observer = host, observer

    def remove(self) -> None:
        if self._observer is None or self._host is None:  # install() sets both
            return
        try:
            self.rt.run_on_hub(self._host.observers.remove, self._observer)
        except Exception:
            pass
        self._observer = None

    def _changed(self, run: TreeRun, finished: Status | None = None) -> None:
        top = run
        while top.parent is not None:
            top = top.parent
        txn_id = top.txn_id
        g = self.goals.get(txn_id) if txn_id is not None else None
        if g is not None:
            final = _status_name(finished) if finished is not None and run is top else None
            g.progress(run, top, final)


class TreeGoal(ServedGoal):
    """A goal of a tree: feedback from its runs, and its trace."""

    server: "TreeServer"

    def __init__(
        self, server: "TreeServer", handle: ServerGoalHandle, call: Invocation | None, refusal: GoalError | None = None
    ) -> None:
        super().__init__(server, handle, call, refusal)
        self.top: TreeRun | None = None  # the root TreeRun, once the trees layer reports one
        self.last_run: TreeRun | None = None
        self.final: str | None = None
        self.flush_scheduled = False
        self.recorder: TraceRecorder | None = None
        self.trace_path: str | None = None

    # -- hub -------------------------------------------------------------------------------
    def starting(self) -> None:
        record_dir = self.server.owner.record_dir
        if record_dir is not None:
            self._open_trace(record_dir)
        # the first feedback, right after the start (after the first tick when that
        # comes at once, so it names the running node)
        self.flush_scheduled = True
        self.rt.hub.call_soon(self.flush)

    def started(self, txn: Transaction) -> None:
        self.server.progress.goals[txn.id] = self
        if self.recorder is not None:
            self.recorder.follow(txn)  # only this goal's runs and transactions

    def ended(self) -> None:
        if self.txn is not None:
            self.server.progress.goals.pop(self.txn.id, None)
        if self.flush_scheduled:
            self.flush()
        self._close_trace()

    def progress(self, run: TreeRun, top: TreeRun, final: str | None = None) -> None:
        """A tree run under this goal changed."""
        self.top = top
        self.last_run = run
        if final is not None:
            self.final = final
        if not self.flush_scheduled:
            self.flush_scheduled = True
            self.rt.hub.call_soon(self.flush)

    def flush(self) -> None:
        """Publish one feedback message for the changes since the last one."""
        if not self.flush_scheduled:
            return
        self.flush_scheduled = False
        top, run = self.top, self.last_run
        if top is None:  # no tick yet, or not a mission: the tree itself is active
            self.send_feedback(self.server.feedback(self, "running", self.subject))
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
        self.send_feedback(
            self.server.feedback(self, status, " > ".join(tips) or self.subject, int(getattr(top, "ticks", 0)))
        )

    def _open_trace(self, record_dir: str | pathlib.Path) -> None:
        call = self.call
        if call is None:
            raise RuntimeError("a refused goal has no trace: it never starts")
        path = call.path
        try:
            from bt_engine.trees import TraceRecorder, tree_host

            host = tree_host(self.rt)
            if host is None:
                return
            folder = pathlib.Path(record_dir)
            folder.mkdir(parents=True, exist_ok=True)
            stamp = time.strftime("%Y%m%d-%H%M%S")
            gid = self.key.hex()[:8]
            file = folder / f"{stamp}-{path.replace('.', '_')}-{gid}.jsonl"
            self.recorder = TraceRecorder(file, host, tree=path, inputs=call.kwargs, transactions=True)
            self.trace_path = str(file)
        except Exception:
            log.exception("cannot record the goal for %s", path)

    def _close_trace(self) -> None:
        rec, self.recorder = self.recorder, None
        if rec is not None:
            try:
                rec.close()
            except Exception:
                log.exception("closing the trace %s failed", self.trace_path)


def _tree_goal(g: ServedGoal) -> TreeGoal:
    """``g`` as the TreeGoal a tree server makes of every goal."""
    if not isinstance(g, TreeGoal):
        raise TypeError(f"a tree server's goals are TreeGoals, got {type(g).__name__}")
    return g


class TreeServer(GoalServer):
    """``/actorbt/tree/<name>`` for tree actor ``ref`` (see the module docstring)."""

    def __init__(
        self, owner: Owner, action: str, action_type: type[RosAction], ref: ActorRef, progress: TreeProgress
    ) -> None:
        super().__init__(owner, action, action_type)
        self.ref = ref
        self.progress = progress
        self.active: TreeGoal | None = None  # the goal whose work runs (executor thread)

    def admit(self, goal: RosMessage) -> Invocation:
        call = decode_tree_goal(self.owner.rt, self.ref, goal.inputs_yaml)
        if self.active_goals() and not self.owner.preempt:
            raise GoalError(
                f"tree {self.ref.path} is already running a goal; cancel it "
                "first (this server refuses a second goal: it was started "
                "without preempt)",
                Ending.BUSY,
            )
        return call

    def active_goals(self) -> list[ServedGoal]:
        """The goals that run or wait to run (not the refused ones, ending now)."""
        return [g for g in self.goals.values() if g.refusal is None]

    def new_goal(self, handle: ServerGoalHandle, call: Invocation | None, refusal: GoalError | None = None) -> TreeGoal:
        return TreeGoal(self, handle, call, refusal)

    def describe(self, call: Invocation) -> str:
        return f"{call.path} {one_line(flow(call.kwargs))}" if call.kwargs else call.path

    def describe_request(self, goal: RosMessage) -> str:
        text = one_line(goal.inputs_yaml)
        return f"{self.ref.path} {text}" if text else self.ref.path

    def end_note(self, g: ServedGoal) -> str:
        path = getattr(g, "trace_path", None)
        return f" (trace {shown_path(path)})" if path else ""

    def feedback(self, g: ServedGoal, status: str, active: str = "", ticks: int = 0) -> RosMessage:
        return self.action_type.Feedback(
            status=status, active_node=active or g.subject, tick_count=max(0, ticks), elapsed=g.elapsed()
        )

    def first_feedback(self, g: ServedGoal) -> None:
        """Sent from the hub once the work starts (TreeGoal.starting)."""

    def result(self, success: bool, status: str, value: Value, error: str, code: int) -> RosMessage:
        res = self.action_type.Result()
        res.success = success
        res.status = status
        res.outputs_yaml = dump(value) if success else ""
        res.error_code = code
        res.error_msg = error
        return res

    async def take_turn(self, g: ServedGoal) -> None:
        tree_goal = _tree_goal(g)
        prev = self.active
        if prev is not None:
            prev.cancel("preempted by a newer goal", Ending.PREEMPTED)
            await prev.finished
        self.active = tree_goal

    def leave(self, g: ServedGoal) -> None:
        if self.active is g:
            self.active = None

    def concluding(self, g: ServedGoal, outcome: Outcome) -> None:
        if _tree_goal(g).top is None:
            # No progress from the trees layer for this actor: a last feedback at the end.
            super().concluding(g, outcome)
