"""Calls from threads other than the hub (a Python program, the CLI, a ROS executor).

The call is handed to the hub and the calling thread waits on a
``concurrent.futures.Future``. Ctrl-C in the waiting thread cancels the work it waited
for, then re-raises.
"""

from __future__ import annotations

import concurrent.futures
import queue
from typing import Any, Callable

from .errors import Cancelled, RuntimeClosedError
from .hub import Hub, Task, Waiter
from .invoke import dispatch
from .modes import Mode
from .transaction import TransactionTable

#: how long an interrupted caller waits for the cancelled work to wind down [s, wall]
INTERRUPT_GRACE = 5.0


def check_open(hub: Hub) -> None:
    if hub.stopped:
        raise RuntimeClosedError("the runtime is closed")


class _HandOff:
    """One call handed to the hub, and its outcome handed back."""

    __slots__ = ("hub", "future", "task")

    def __init__(self, hub: Hub) -> None:
        self.hub = hub
        self.future: concurrent.futures.Future = concurrent.futures.Future()
        self.task: Task | None = None

    def settle(self, fn: Callable, *args: Any) -> None:
        """Run ``fn(*args)`` and hand its result or exception to the waiting thread."""
        try:
            value = fn(*args)
        except BaseException as e:  # delivered to the calling thread
            self.future.set_exception(e)
        else:
            self.future.set_result(value)

    def wait(self) -> Any:
        try:
            return self.future.result()
        except KeyboardInterrupt:
            task = self.task
            if task is not None:
                self.hub.call_soon_threadsafe(_interrupt, task)
                concurrent.futures.wait([self.future], timeout=INTERRUPT_GRACE)
            raise


def _interrupt(task: Task) -> None:
    if task.txns:
        task.txns[0].cancel("interrupted")
    else:
        task.deliver_cancel(Cancelled(None, "interrupted"))


def run_on_hub(hub: Hub, fn: Callable, *args: Any) -> Any:
    """Run a non-blocking ``fn(*args)`` on the hub thread and return its result."""
    if hub.in_hub_thread():
        return fn(*args)
    check_open(hub)
    h = _HandOff(hub)
    hub.call_soon_threadsafe(h.settle, fn, *args)
    return h.wait()


def call_from_thread(
    table: TransactionTable,
    scope: Any,
    name: str,
    mode: Mode,
    args: tuple,
    kwargs: dict,
    cb: Callable | None,
    seconds: float | None,
) -> Any:
    """Call actor ``name`` (resolved from ``scope``) in ``mode`` from an outside thread.

    Blocking modes run in a new task on the hub while this thread waits; iterator modes
    return an :class:`ExternalIterator`; async modes return the Transaction at once.
    """
    hub = table.hub
    check_open(hub)
    if mode in (Mode.ITERATOR, Mode.TIMED_ITERATOR):
        return ExternalIterator(table, scope, name, mode, args, kwargs, seconds)
    h = _HandOff(hub)

    def run() -> Any:
        return dispatch(table, scope.resolve(name), mode, args, kwargs, cb, seconds)

    if mode in (Mode.SYNC, Mode.TIMED):

        def begin() -> None:
            h.task = Task(hub, lambda: h.settle(run))
            hub.switch_to(h.task)

        hub.call_soon_threadsafe(begin)
    else:
        hub.call_soon_threadsafe(h.settle, run)
    return h.wait()


class ExternalIterator:
    """Iterate an actor from a thread other than the hub.

    A pump task on the hub pulls one item per request, so the source is never read
    ahead of the consumer. While the consumer works on an item, virtual time stands
    still (the consumer counts as outside work).
    """

    def __init__(
        self,
        table: TransactionTable,
        scope: Any,
        name: str,
        mode: Mode,
        args: tuple,
        kwargs: dict,
        seconds: float | None,
    ) -> None:
        self._hub = hub = table.hub
        self._q: queue.SimpleQueue = queue.SimpleQueue()
        self._requests = 0
        self._waiter: Waiter | None = None
        self._closed = False
        self._task: Task | None = None

        def pump() -> None:
            it = None
            try:
                task = self._task
                if task is None:
                    raise RuntimeError("the pump runs as the task begin() made")
                it = dispatch(table, scope.resolve(name), mode, args, kwargs, None, seconds)
                while True:
                    if self._requests == 0:
                        hub.outside_pending += 1
                        try:
                            while self._requests == 0:
                                self._waiter = Waiter(task)
                                self._waiter.wait()
                        finally:
                            hub.outside_pending -= 1
                    self._requests -= 1
                    try:
                        self._q.put(("v", next(it)))
                    except StopIteration:
                        self._q.put(("end", None))
                        return
            except BaseException as e:
                self._q.put(("err", e))
            finally:
                if it is not None:
                    it.close()

        def begin() -> None:
            self._task = Task(hub, pump)
            hub.switch_to(self._task)

        run_on_hub(hub, begin)

    def _request(self) -> None:
        self._requests += 1
        if self._waiter is not None:
            self._waiter.wake()

    def __iter__(self) -> "ExternalIterator":
        return self

    def __next__(self) -> Any:
        if self._closed:
            raise StopIteration
        self._hub.call_soon_threadsafe(self._request)
        kind, value = self._q.get()
        if kind == "v":
            return value
        self._closed = True
        if kind == "err" and not isinstance(value, Cancelled):
            raise value
        raise StopIteration

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True

        def stop() -> None:
            task = self._task
            if task is not None and not task.dead:
                task.deliver_cancel(Cancelled(None, "iterator closed"))

        if not self._hub.stopped:
            run_on_hub(self._hub, stop)

    def __enter__(self) -> "ExternalIterator":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
