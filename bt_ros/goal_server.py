"""One action server of ``actorbt serve`` and the goals it runs.

A goal's way through (thread in brackets):

1. ``goal_callback`` [executor]: :meth:`GoalServer.admit` decodes and validates the goal
   once (:mod:`bt_ros.goals`). Every goal is accepted: one that cannot run (a
   :class:`~bt_ros.goals.GoalError`) is aborted at once in step 3, with the reason
   in the result's ``error_msg`` and its ``error_code`` (``INVALID_GOAL``, ``BUSY``,
   ``SHUTDOWN``), because the action protocol carries no reason with a rejection.
2. ``handle_accepted_callback`` [executor]: rclpy calls it right after (same thread, same
   request message), so the decoded call (or the refusal) is handed over there and
   becomes a :class:`ServedGoal`, known by its goal id from then on (cancel requests
   find it).
3. ``execute_callback`` [executor, a coroutine]: the work is started on the hub with
   ``rt.start``; its outcome comes back to the coroutine through an rclpy Future, and
   becomes the result: succeeded, canceled (the client asked) or aborted, with the
   :class:`~bt_ros.error_codes.Ending` as ``error_code``. The last feedback goes
   out before the result.

Subclasses say what a goal means (:meth:`GoalServer.admit`), how feedback and results
look, and may wait their turn before the work starts (a tree runs one goal at a time).

Each goal is told to the owner's :meth:`Owner.announce` in one line per event, e.g.

    goal 3f2a1b9c bt_pick_place {category: can}: accepted
    goal 3f2a1b9c bt_pick_place: succeeded in 12.3 s (trace .actorbt/goals/...jsonl)
    call 5e6f7a8b robot.navigation.goto(1.0, 2.0, 0.0): succeeded in 8.21 s
    goal 9a8b7c6d bt_pick {category: 3}: refused (INVALID_GOAL): input 'category' expects str, got int
"""

from __future__ import annotations

import os
import time
from typing import TYPE_CHECKING, Callable, Protocol

from bt_engine.bus.messages import RosAction, RosMessage
from bt_engine.errors import Cancelled, Failure
from .error_codes import Ending, error_code
from .goals import GoalError, Invocation
from .host import RosClosedError, RosHost
from .rostypes import Outcome, Value

if TYPE_CHECKING:
    import pathlib

    from rclpy.action import ActionServer, CancelResponse, GoalResponse
    from rclpy.action.server import ServerGoalHandle
    from rclpy.node import Node

    from bt_engine import Runtime, Transaction

__all__ = ["GoalServer", "Owner", "ServedGoal"]


class Owner(Protocol):
    """What a GoalServer needs from the server that owns it (see ``server.Server``)."""

    rt: Runtime
    host: RosHost
    #: no new goals: the server is shutting down
    closing: bool
    #: a goal for a running tree preempts it (otherwise it is refused: BUSY)
    preempt: bool
    #: where tree goals are recorded (None: not recorded)
    record_dir: "str | pathlib.Path | None"

    def announce(self, line: str) -> None:
        """Tell about a goal: one line (accepted, refused, how it ended)."""


class ServedGoal:
    """One accepted goal. Each method says the thread it runs on.

    ``call`` is what it runs; None for a goal that cannot run (``refusal`` says why)."""

    def __init__(
        self, server: "GoalServer", handle: ServerGoalHandle, call: Invocation | None, refusal: GoalError | None = None
    ) -> None:
        from rclpy.task import Future

        self.server = server
        self.rt = server.owner.rt
        self.handle = handle
        self.key = bytes(handle.goal_id.uuid)
        self.call = call
        self.refusal = refusal
        self.txn: Transaction | None = None
        self.cancel_reason: str | None = None
        self.cancel_ending = Ending.UNKNOWN  # why the server cancelled it (not the client)
        self.resolved = False
        self.outcome = Future()  # the work's result or Failure; set on the executor thread
        self.finished = Future()  # set when the execute coroutine has ended
        self.accepted_at = time.monotonic()
        self.started_at: float | None = None  # when the work started (monotonic)
        self.end_status = "aborted"  # the Result's status, once it is known

    @property
    def short_id(self) -> str:
        """The goal id's first 8 hex digits (as in the trace file's name)."""
        return self.key.hex()[:8]

    @property
    def subject(self) -> str:
        """What the goal runs, for announce lines: the actor path (or the action)."""
        return self.call.path if self.call is not None else self.server.action

    def elapsed(self) -> float:
        """Seconds since the work started (0 before); any thread."""
        return 0.0 if self.started_at is None else time.monotonic() - self.started_at

    # -- any thread ------------------------------------------------------------------------
    def start(self) -> None:
        """Start the work on the hub."""
        self._to_hub(self._start_on_hub)

    def cancel(self, reason: str, ending: Ending = Ending.UNKNOWN) -> None:
        """Cancel the work (before or after it started) with ``reason``; ``ending`` is
        the error code when it was not the client who asked."""
        if self.cancel_ending is Ending.UNKNOWN:
            self.cancel_ending = ending
        self._to_hub(self._cancel_on_hub, reason)

    def resolve(self, outcome: Outcome) -> None:
        """Hand the outcome to the execute coroutine; the first outcome wins."""
        if self.resolved:
            return
        self.resolved = True
        try:
            self.server.owner.host.post(self._set_outcome, outcome)
        except RosClosedError:
            pass

    def send_feedback(self, fb: RosMessage) -> None:
        """Publish feedback message ``fb`` (it is sent from the executor thread)."""
        host = self.server.owner.host
        if host.in_executor_thread():
            self.handle.publish_feedback(fb)
            return
        try:
            host.post(self.handle.publish_feedback, fb)
        except RosClosedError:
            pass

    def _to_hub(self, fn: Callable[..., object], *args: object) -> None:
        try:
            self.rt.call_soon_threadsafe(fn, *args)
        except Exception:  # the runtime is gone: the work cannot run any more
            self.cancel_ending = Ending.SHUTDOWN
            self.resolve(Failure(Cancelled(None, "the runtime is closed")))

    # -- hub -------------------------------------------------------------------------------
    def _start_on_hub(self) -> None:
        if self.cancel_reason is not None:
            self.resolve(Failure(Cancelled(None, self.cancel_reason)))
            return
        self.started_at = time.monotonic()
        self.starting()
        call = self.call
        assert call is not None  # a refused goal never starts
        try:
            txn = self.rt.start(call.path, *call.args, on_done=self._on_done, **call.kwargs)
        except BaseException as e:  # the runtime is closing, or a late surprise
            self.ended()
            self.resolve(Failure(e))
            return
        self.txn = txn
        if not self.resolved:
            self.started(txn)

    def _on_done(self, outcome: Outcome) -> None:
        self.ended()
        self.resolve(outcome)

    def _cancel_on_hub(self, reason: str) -> None:
        if self.cancel_reason is None:
            self.cancel_reason = reason
        if self.txn is not None and not self.txn.done:
            self.txn.cancel(reason)

    # Hooks for subclasses (hub): before the transaction starts, once it runs, once it ended.
    def starting(self) -> None:
        pass

    def started(self, txn: Transaction) -> None:
        pass

    def ended(self) -> None:
        pass

    # -- executor thread -----------------------------------------------------------------
    def _set_outcome(self, outcome: Outcome) -> None:
        if not self.outcome.done():
            self.outcome.set_result(outcome)


class GoalServer:
    """One rclpy ActionServer whose goals run actors of the owner's runtime.

    Args:
        owner: the server this action belongs to (runtime, host, closing).
        action: the action name.
        action_type: the action type (RunTree, CallActor).
    """

    #: the first word of this server's announce lines
    label = "goal"
    #: announce acceptance too (not only the end)
    announce_accepted = True

    def __init__(self, owner: Owner, action: str, action_type: type[RosAction]) -> None:
        self.owner = owner
        self.action = action
        self.action_type = action_type
        self.goals: dict[bytes, ServedGoal] = {}  # accepted, not ended; executor thread
        # goal callback -> accepted callback: the request and its call, or why it cannot run
        self._admitted: tuple[RosMessage, Invocation | None, GoalError | None] | None = None
        self._server: ActionServer | None = None
        #: no new goals: the action is being withdrawn (its tree left the folder)
        self.withdrawn: GoalError | None = None

    # -- what a goal means (subclasses) ----------------------------------------------------
    def admit(self, goal: RosMessage) -> Invocation:
        """The call ``goal`` asks for, or GoalError with the reason it cannot run."""
        raise NotImplementedError

    def new_goal(
        self, handle: ServerGoalHandle, call: Invocation | None, refusal: GoalError | None = None
    ) -> ServedGoal:
        return ServedGoal(self, handle, call, refusal)

    def feedback(self, g: ServedGoal, status: str) -> RosMessage:
        return self.action_type.Feedback(status=status, elapsed=g.elapsed())

    def first_feedback(self, g: ServedGoal) -> None:
        """Publish the feedback that tells the work has started (executor thread)."""
        g.send_feedback(self.feedback(g, "running"))

    def result(self, success: bool, status: str, value: Value, error: str, code: int) -> RosMessage:
        """The Result message: ``status`` as in ``succeeded``, ``canceled``, ``failed: …``;
        ``value`` what the work returned (success only); ``error`` the reason otherwise;
        ``code`` the ``error_code``."""
        raise NotImplementedError

    async def take_turn(self, g: ServedGoal) -> None:
        """Wait until ``g`` may start (executor thread)."""

    def leave(self, g: ServedGoal) -> None:
        """``g`` has ended (executor thread)."""

    def concluding(self, g: ServedGoal, outcome: Outcome) -> None:
        """The work of ``g`` ended with ``outcome``; the result goes out next: the last
        feedback goes out now."""
        g.handle.publish_feedback(self.feedback(g, "failure" if isinstance(outcome, Failure) else "success"))

    def describe(self, call: Invocation) -> str:
        """What an accepted goal runs, short, for announce lines."""
        return call.path

    def describe_request(self, goal: RosMessage) -> str:
        """A goal message (perhaps malformed), short, for announce lines."""
        return self.action

    def end_note(self, g: ServedGoal) -> str:
        """What follows the outcome in the goal's last line (e.g. its trace)."""
        return ""

    def _announce(self, line: str) -> None:
        try:
            self.owner.announce(line)
        except Exception:  # telling must never break serving
            pass

    def _announce_end(self, g: ServedGoal) -> None:
        if g.refusal is not None:
            self._announce(
                f"{self.label} {g.short_id} {self.describe_request(g.handle.request)}: "
                f"refused ({g.refusal.ending.value}): {one_line(str(g.refusal))}"
            )
            return
        took = time.monotonic() - g.accepted_at
        # the arguments are in the accepted line, when there is one
        assert g.call is not None
        subject = g.call.path if self.announce_accepted else self.describe(g.call)
        self._announce(
            f"{self.label} {g.short_id} {subject}: {one_line(g.end_status)} in {seconds(took)}{self.end_note(g)}"
        )

    # -- rclpy (executor thread) -----------------------------------------------------------
    def create(self, node: Node, result_timeout: int) -> None:
        from rclpy.action import ActionServer

        self._server = ActionServer(
            node,
            self.action_type,
            self.action,
            self._execute,
            result_timeout=result_timeout,
            goal_callback=self._on_goal,
            handle_accepted_callback=self._on_accepted,
            cancel_callback=self._on_cancel,
        )

    def destroy(self) -> None:
        if self._server is not None:
            self._server.destroy()
            self._server = None

    def _on_goal(self, goal: RosMessage) -> GoalResponse:
        from rclpy.action import GoalResponse

        call: Invocation | None = None
        refusal: GoalError | None = None
        try:
            if self.owner.closing:
                raise GoalError("the server is shutting down", Ending.SHUTDOWN)
            if self.withdrawn is not None:
                raise self.withdrawn
            call = self.admit(goal)
        except GoalError as e:  # accepted all the same, and aborted with the reason
            refusal = e
        self._admitted = (goal, call, refusal)
        return GoalResponse.ACCEPT

    def _on_accepted(self, handle: ServerGoalHandle) -> None:
        admitted, self._admitted = self._admitted, None
        # rclpy calls this right after the goal callback accepted this very request, on
        # the same thread (ActionServer._execute_goal_request).
        if admitted is None or admitted[0] is not handle.request:
            raise RuntimeError(f"{self.action}: accepted a goal that was not admitted")
        g = self.new_goal(handle, admitted[1], admitted[2])
        self.goals[g.key] = g
        if self.announce_accepted and g.call is not None:
            self._announce(f"{self.label} {g.short_id} {self.describe(g.call)}: accepted")
        handle.execute()

    def _on_cancel(self, handle: ServerGoalHandle) -> CancelResponse:
        from rclpy.action import CancelResponse

        g = self.goals.get(bytes(handle.goal_id.uuid))
        if g is not None:
            g.cancel("goal canceled")
        return CancelResponse.ACCEPT

    async def _execute(self, handle: ServerGoalHandle) -> RosMessage:
        g = self.goals[bytes(handle.goal_id.uuid)]
        try:
            if g.refusal is not None:
                handle.abort()
                return self._result(g, g.refusal.ending, f"aborted: {g.refusal}", None, str(g.refusal))
            await self.take_turn(g)
            if handle.is_cancel_requested:
                handle.canceled()
                return self._result(g, Ending.CANCELED, "canceled", None, "goal canceled")
            if self.owner.closing or self.withdrawn is not None:
                why = self.withdrawn or GoalError("the server is shutting down", Ending.SHUTDOWN)
                handle.abort()
                return self._result(g, why.ending, f"aborted: {why}", None, str(why))
            self.first_feedback(g)
            g.start()
            outcome = await g.outcome
            return self._conclude(g, outcome)
        finally:
            self.leave(g)
            self.goals.pop(g.key, None)
            g.finished.set_result(True)
            self._announce_end(g)

    def _result(self, g: ServedGoal, ending: Ending, status: str, value: Value, error: str) -> RosMessage:
        g.end_status = status
        return self.result(
            ending is Ending.SUCCEEDED, status, value, error, error_code(self.action_type.Result, ending)
        )

    def _conclude(self, g: ServedGoal, outcome: Outcome) -> RosMessage:
        handle = g.handle
        self.concluding(g, outcome)
        if not isinstance(outcome, Failure):
            handle.succeed()
            return self._result(g, Ending.SUCCEEDED, "succeeded", outcome, "")
        exc = outcome.exception
        if outcome.cancelled or isinstance(exc, Cancelled):
            reason = getattr(exc, "reason", "") or str(exc)
            if handle.is_cancel_requested:
                handle.canceled()
                return self._result(g, Ending.CANCELED, "canceled", None, reason)
            handle.abort()
            return self._result(g, g.cancel_ending, f"aborted: {reason}", None, reason)
        handle.abort()
        return self._result(g, Ending.FAILED, f"failed: {exc}", None, f"{type(exc).__name__}: {exc}")


# -- announce lines -------------------------------------------------------------------------
#: the longest piece of text (arguments, a reason) an announce line carries
LINE_PIECE = 160


def one_line(text: str, limit: int = LINE_PIECE) -> str:
    """``text`` on one line (whitespace runs become one space), cut at ``limit``."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[: limit - 1] + "\u2026"


def seconds(value: float) -> str:
    """``0.03 s``, ``8.21 s``, ``12.3 s``."""
    return f"{value:.2f} s" if value < 10 else f"{value:.1f} s"


def shown_path(path: str) -> str:
    """``path`` relative to the working folder when it is inside it."""
    try:
        rel = os.path.relpath(path)
    except ValueError:
        return path
    return path if rel.startswith(os.pardir) else rel
