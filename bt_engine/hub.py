"""The hub: one thread, one greenlet per running task, timers on the runtime clock.

Every actor runs on the hub thread. A blocking primitive (a sync call, the next item of
an iterator, ``sleep``, waiting for a message) parks the calling task on a
:class:`Waiter` and switches to the hub greenlet, which runs whatever is ready next.
Other threads never touch hub state; they post work with ``call_soon_threadsafe``.

Under the virtual clock the hub decides when time jumps; the rule it follows is stated
once, in :class:`bt_engine.clock.VirtualClock`, and implemented in :meth:`Hub._idle`.
"""

from __future__ import annotations

import collections
import heapq
import logging
import threading
import time
from typing import Any, Callable

import greenlet

from .clock import Clock
from .errors import Cancelled, HubBlockingError

log = logging.getLogger("actorbt")


class TimerHandle:
    """A scheduled call on the hub. ``cancel()`` is cheap: the heap entry is skipped."""

    __slots__ = ("when", "fn", "args", "period", "cancelled")

    def __init__(self, when: float, fn: Callable, args: tuple, period: float | None) -> None:
        self.when = when
        self.fn = fn
        self.args = args
        self.period = period
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class Task(greenlet.greenlet):
    """A greenlet running actor code.

    ``txns`` is the stack of transactions executing in this greenlet (sync calls run
    directly in the caller's greenlet, so one task may hold several, innermost last).
    """

    def __init__(self, hub: "Hub", fn: Callable[[], Any]) -> None:
        super().__init__(run=self._main, parent=hub.glet)
        self._fn = fn
        self.hub = hub
        hub.tasks_alive += 1
        self.txns: list = []
        self.waiter: Waiter | None = None
        self.pending_cancel: Cancelled | None = None

    def _main(self) -> None:
        try:
            self._fn()
        finally:
            self.hub.tasks_alive -= 1

    def deliver_cancel(self, exc: Cancelled) -> None:
        """Arrange for ``exc`` to be raised at this task's next blocking point.

        When two cancellations are pending, the outer transaction's wins, so the
        exception unwinds every frame that was cancelled.
        """
        if self.dead:
            return
        cur = self.pending_cancel
        if cur is None or _is_ancestor(exc.transaction, cur.transaction):
            self.pending_cancel = exc
        waiter = self.waiter
        if waiter is not None and not waiter.fired:
            waiter.fired = True
            self.hub.ready.append((self._resume, ()))

    def _resume(self) -> None:
        self.hub.switch_to(self)

    def raise_pending(self) -> None:
        exc = self.pending_cancel
        if exc is not None:
            self.pending_cancel = None
            raise exc


def _is_ancestor(a: Any, b: Any) -> bool:
    """True when transaction ``a`` is ``b`` or one of its ancestors."""
    while b is not None:
        if b is a:
            return True
        b = b.parent
    return False


class Waiter:
    """A one-shot wake-up for the task that created it.

    The first ``wake`` wins; later ones are ignored, so a timer and a result can race
    safely.
    """

    __slots__ = ("task", "fired", "value")

    def __init__(self, task: Task) -> None:
        self.task = task
        self.fired = False
        self.value: Any = None

    def wake(self, value: Any = None) -> None:
        if self.fired:
            return
        self.fired = True
        self.value = value
        task = self.task
        if task.waiter is self:
            task.hub.ready.append((task._resume, ()))

    def wait(self) -> Any:
        """Park the task until woken; raises a pending cancellation first."""
        task = self.task
        task.raise_pending()
        if not self.fired:
            hub_glet = task.hub.glet
            if hub_glet is None:
                raise RuntimeError("a task waits only while its hub runs (Hub.run)")
            task.waiter = self
            try:
                hub_glet.switch()
            finally:
                task.waiter = None
            task.raise_pending()
        return self.value


class Hub:
    """The scheduler loop. Runs in its own thread, owned by a Runtime."""

    def __init__(self, clock: Clock, is_idle_world: Callable[[], bool]) -> None:
        self.clock = clock
        self.ready: collections.deque = collections.deque()
        self._timers: list = []
        self._seq = 0
        self._inbox: collections.deque = collections.deque()
        self._wake = threading.Lock()
        self._wake.acquire()
        self._stopping = False
        self._is_idle_world = is_idle_world
        #: outside work virtual time stands still for (offloads, an outside consumer
        #: working on an item).
        self.outside_pending = 0
        #: started work that may complete from another thread (async and stream
        #: implementations not declared hub_only); virtual time is paced to wall time.
        self.foreign_pending = 0
        #: (wall, virtual) time when pacing last started: virtual time may not get
        #: further ahead of that point than wall time has.
        self._pace_from: tuple[float, float] | None = None
        self.glet: greenlet.greenlet | None = None
        self.thread_id: int | None = None
        #: what the hub is running now, for the watchdog: (monotonic start, label source)
        self.busy_since = 0.0
        self.busy_task: Task | None = None
        self.busy_callback: Callable | None = None
        #: tasks created and not yet ended (leak checks)
        self.tasks_alive = 0
        #: the owning Runtime, for code that finds it from the current task
        self.rt: Any = None

    # -- scheduling ---------------------------------------------------------------
    def call_soon(self, fn: Callable, *args: Any) -> None:
        """Run ``fn(*args)`` on the hub soon. Hub thread only."""
        self.ready.append((fn, args))

    def call_soon_threadsafe(self, fn: Callable, *args: Any) -> None:
        """Run ``fn(*args)`` on the hub; safe from any thread."""
        self._inbox.append((fn, args))
        try:
            self._wake.release()
        except RuntimeError:  # already signalled
            pass

    def call_at(self, when: float, fn: Callable, *args: Any, period: float | None = None) -> TimerHandle:
        """Run ``fn(*args)`` at runtime-clock time ``when`` (every ``period`` s after).
        Safe from any thread."""
        h = TimerHandle(when, fn, args, period)
        if self.in_hub_thread():
            self._push_timer(h)
        else:
            self.call_soon_threadsafe(self._push_timer, h)
        return h

    def _push_timer(self, h: TimerHandle) -> None:
        self._seq += 1
        heapq.heappush(self._timers, (h.when, self._seq, h))

    def switch_to(self, task: Task) -> None:
        """Resume a task until it blocks or ends (the watchdog names it meanwhile)."""
        self.busy_task = task
        try:
            task.switch()
        finally:
            self.busy_task = None

    def in_hub_thread(self) -> bool:
        return threading.get_ident() == self.thread_id

    def current_task(self) -> Task | None:
        g = greenlet.getcurrent()
        return g if isinstance(g, Task) else None

    def require_task(self, what: str) -> Task:
        g = greenlet.getcurrent()
        if isinstance(g, Task):
            return g
        raise HubBlockingError(
            f"{what} blocks, but it was called from a hub callback, which must not block; "
            "use an async call mode (start / run_actor_mode(..., 'async', cb)) instead"
        )

    def sleep(self, seconds: float) -> None:
        """Block the current task for ``seconds`` of runtime-clock time."""
        task = self.require_task("sleep")
        w = Waiter(task)
        h = self.call_at(self.clock.now() + max(0.0, seconds), w.wake)
        try:
            w.wait()
        finally:
            h.cancel()

    def yield_now(self) -> None:
        """Let every other ready task run once before continuing."""
        task = self.require_task("yield")
        w = Waiter(task)
        self.ready.append((w.wake, ()))
        w.wait()

    def foreign_work_started(self) -> None:
        """Work that may complete from another thread began. Hub thread only.

        Every start re-anchors the pacing, so each such job gets at least as much
        wall time as virtual time passes while it runs.
        """
        self.foreign_pending += 1
        self._pace_from = (time.monotonic(), self.clock.now())

    def foreign_work_ended(self) -> None:
        """That work completed or was cancelled. Hub thread only."""
        self.foreign_pending -= 1
        if self.foreign_pending == 0:
            self._pace_from = None

    # -- loop -----------------------------------------------------------------------
    @property
    def stopped(self) -> bool:
        """True once ``stop()`` was called: the hub takes no more work."""
        return self._stopping

    def stop(self) -> None:
        self._stopping = True
        self.call_soon_threadsafe(lambda: None)

    def run(self) -> None:
        """The loop; returns after ``stop()``."""
        self.glet = greenlet.getcurrent()
        self.thread_id = threading.get_ident()
        ready, inbox, timers, clock = self.ready, self._inbox, self._timers, self.clock
        while not self._stopping:
            while inbox:
                ready.append(inbox.popleft())
            while ready:
                fn, args = ready.popleft()
                self._run_callback(fn, args)
                while inbox:
                    ready.append(inbox.popleft())
            # due timers
            now = clock.now()
            fired = False
            while timers and timers[0][0] <= now:
                _, _, h = heapq.heappop(timers)
                if h.cancelled:
                    continue
                fired = True
                if h.period is not None:
                    h.when += h.period
                    if h.when < now - 10 * h.period:  # fell far behind real time: resync
                        h.when = now + h.period
                    self._seq += 1
                    heapq.heappush(timers, (h.when, self._seq, h))
                self._run_callback(h.fn, h.args)
            if fired or ready:
                continue
            while timers and timers[0][2].cancelled:
                heapq.heappop(timers)
            if self._stopping:
                break
            self._idle(now)

    def _idle(self, now: float) -> None:
        timers, clock = self._timers, self.clock
        if clock.virtual:
            # Jump only while work is live, nothing is posted and no outside work holds
            # time still; while foreign work may still complete, no faster than wall time.
            if timers and not self._inbox and self.outside_pending == 0 and not self._is_idle_world():
                due = timers[0][0]
                if self._pace_from is not None:
                    wall0, virtual0 = self._pace_from
                    allowed = virtual0 + (time.monotonic() - wall0)
                    if due > allowed:
                        # Keep pace: move to where wall time allows, wait for the timer
                        # or for something posted, then catch up with the wall time spent.
                        clock.advance_to(allowed)
                        self._wake.acquire(timeout=due - allowed)
                        clock.advance_to(min(due, virtual0 + (time.monotonic() - wall0)))
                        return
                clock.advance_to(due)
                return
            self._wake.acquire()
            return
        if timers:
            delay = timers[0][0] - now
            if delay > 0:
                self._wake.acquire(timeout=delay)
        else:
            self._wake.acquire()

    def _run_callback(self, fn: Callable, args: tuple) -> None:
        self.busy_since = time.monotonic()
        self.busy_callback = fn
        try:
            fn(*args)
        except Exception:  # a hub callback must never take the hub down
            log.exception("error in hub callback %s", getattr(fn, "__qualname__", fn))
        finally:
            self.busy_since = 0.0
            self.busy_callback = None
