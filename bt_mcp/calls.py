"""One tool call on the runtime: started on the hub, its tree transitions reported as
they happen, cancelled through the engine when the client cancels, and summarised.

The MCP server runs on an asyncio loop in the main thread; actors run on the runtime's
hub thread. The hub hands events over with ``loop.call_soon_threadsafe``; the loop
never blocks on the hub (starting a call waits in a worker thread).
"""

from __future__ import annotations

import asyncio
import json
import time
from dataclasses import dataclass, field
from typing import Any, Awaitable, Callable

import anyio

from bt_engine.actor import ActorRef
from bt_engine.errors import ActorCancelled, ActorError, Cancelled, Failure
from bt_engine.invoke import dispatch
from bt_engine.modes import Mode
from bt_engine.runtime import Runtime
from bt_engine.transaction import Transaction
from bt_engine.trees import TreeFailure, to_json
from .progress import CallWatch, RunWatcher

__all__ = ["CallOutcome", "run_call", "result_text", "MAX_TEXT"]

#: the longest result text (a camera image as JSON is megabytes)
MAX_TEXT = 20_000
#: how long a cancelled call may take to stop before the server answers anyway [s]
CANCEL_GRACE = 10.0


@dataclass
class CallOutcome:
    """How a call ended.

    Attributes:
        value: the result (a tree's outputs), JSON-able.
        error: why it failed (``None``: it succeeded).
        failed_at: for a tree that failed, the node path where.
        sim_time, wall_time: how long it ran [s] on the runtime clock and the wall.
        ticks: the outermost tree run's ticks (0 for a plain actor).
        trace: the trace events of its tree runs (``dropped``: how many did not fit).
        cancelled: it was cancelled (``error`` says by whom).
    """

    value: Any = None
    error: str | None = None
    failed_at: str | None = None
    sim_time: float = 0.0
    wall_time: float = 0.0
    ticks: int = 0
    trace: list[dict[str, Any]] = field(default_factory=list)
    dropped: int = 0
    cancelled: bool = False

    @property
    def ok(self) -> bool:
        return self.error is None


class _Done:
    def __init__(self, outcome: Any, at: float) -> None:
        self.outcome, self.at = outcome, at


async def run_call(
    rt: Runtime,
    ref: ActorRef,
    args: tuple,
    kwargs: dict,
    watcher: RunWatcher | None,
    on_transition: Callable[[dict[str, Any]], Awaitable[None]],
    on_end: Callable[[CallOutcome], None] | None = None,
    on_cancel: Callable[[], None] | None = None,
) -> CallOutcome:
    """Run actor ``ref`` to its end, awaiting ``on_transition(event)`` for every node
    transition of its tree runs; ``on_end(outcome)`` is called however it ended, and
    ``on_cancel()`` as soon as a cancellation starts (``on_end`` follows once it stopped).

    When the awaiting task is cancelled (the client's ``notifications/cancelled``), the
    transaction is cancelled with the engine's cancellation (a tree halts its nodes,
    which cancel their actors), the call waits for it to stop (at most
    :data:`CANCEL_GRACE`), and the cancellation goes on.
    """
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[Any] = asyncio.Queue()

    def hand_over(item: Any) -> None:  # hub thread -> loop
        try:
            loop.call_soon_threadsafe(queue.put_nowait, item)
        except RuntimeError:  # the loop is gone (the server is shutting down)
            pass

    watch = CallWatch(hand_over)
    started: dict[str, float] = {}

    def start() -> Transaction:  # on the hub: registered before its task first runs
        started["sim"] = rt.now()
        txn = dispatch(rt.txns, ref, Mode.ASYNC, args, kwargs, lambda outcome: hand_over(_Done(outcome, rt.now())))
        if watcher is not None:
            watcher.watch(txn.id, watch)
        return txn

    wall0 = time.perf_counter()
    txn = await anyio.to_thread.run_sync(rt.run_on_hub, start)
    try:
        while True:
            item = await queue.get()
            if isinstance(item, _Done):
                break
            await on_transition(item)
    except BaseException:
        txn.cancel("cancelled by the MCP client")
        if on_cancel is not None:
            on_cancel()
        item = None
        with anyio.CancelScope(shield=True), anyio.move_on_after(CANCEL_GRACE):
            while not isinstance(item := await queue.get(), _Done):
                pass
        if on_end is not None:
            if isinstance(item, _Done):
                on_end(_outcome(item, started["sim"], time.perf_counter() - wall0, watch))
            else:  # still stopping after the grace period: say so rather than wait on
                on_end(
                    CallOutcome(
                        error="cancelled: still stopping",
                        cancelled=True,
                        ticks=watch.ticks,
                        trace=watch.events,
                        dropped=watch.dropped,
                    )
                )
        raise
    finally:
        if watcher is not None:
            watcher.unwatch(txn.id)
    outcome = _outcome(item, started["sim"], time.perf_counter() - wall0, watch)
    if on_end is not None:
        on_end(outcome)
    return outcome


def _outcome(done: _Done, sim0: float, wall: float, watch: CallWatch) -> CallOutcome:
    out = CallOutcome(
        sim_time=done.at - sim0, wall_time=wall, ticks=watch.ticks, trace=watch.events, dropped=watch.dropped
    )
    result = done.outcome
    if isinstance(result, Failure):
        error = result.exception
        failure = _tree_failure(error)
        if failure is not None:
            out.failed_at = failure.node_path
            out.error = f"FAILURE at {failure.node_path}" + (f": {failure.reason}" if failure.reason else "")
        elif isinstance(error, (Cancelled, ActorCancelled)):
            out.cancelled = True
            out.error = f"cancelled: {error.reason or 'cancelled'}"
        else:
            out.error = _error_text(error)
    else:
        out.value = to_json(result)
    return out


def _tree_failure(error: BaseException | None) -> TreeFailure | None:
    seen = 0
    while error is not None and seen < 10:
        if isinstance(error, TreeFailure):
            return error
        error, seen = error.__cause__, seen + 1
    return None


def _error_text(error: BaseException | None) -> str:
    """``ActorError``'s own text names the actor and its root cause; others get their type."""
    if error is None:
        return "failed"
    if isinstance(error, ActorError):
        return str(error)
    return f"{type(error).__name__}: {error}"


def result_text(value: Any) -> str:
    """A JSON value as text for the model, cut at :data:`MAX_TEXT` characters."""
    text = json.dumps(value, default=str)
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT] + f"... ({len(text)} characters, cut)"
