"""The Runtime: one object owning the hub, clock, root SubSystem, transaction table,
trace recorder and bus. Nothing in the engine is module-global.

    with Runtime() as rt:                     # virtual clock, local bus
        rt.add_subsystem("robot", Robot)
        rt.call("robot.goto", 1.0, 2.0, 0.0)  # from any thread
"""
from __future__ import annotations

import concurrent.futures
import logging
import queue
import threading
import time
from typing import Any, Callable, Iterator

import greenlet

from .actor import ActorRef, actor
from .api import CallApi
from .bus.local import LocalBus
from .bus.transport import Transport
from .clock import Clock, make_clock
from .errors import Cancelled, RuntimeClosedError
from .hub import Hub, Task, TimerHandle, Waiter
from .modes import Mode
from .subsystem import SubSystem
from .transaction import Transaction

log = logging.getLogger("actorbt")


class RootSystem(SubSystem):
    """The root scope. It holds the built-in actors."""

    @actor
    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` [s] on the runtime clock (virtual time jumps)."""
        self._rt.sleep(seconds)


class Runtime(CallApi):
    """The engine: hub thread, clock, actors, transactions, bus.

    Args:
        clock: ``"virtual"`` (default), ``"wall"`` or a Clock.
        bus: ``"local"`` (default), a Transport, or a factory ``f(runtime) -> Transport``.
        watchdog: warn when actor code holds the hub longer than this [s, wall]; None
            disables it.
    """

    def __init__(self, clock: "str | Clock | None" = None,
                 bus: "str | Transport | Callable[[Runtime], Transport] | None" = None,
                 watchdog: float | None = 0.5) -> None:
        self.clock = make_clock(clock)
        self._live: dict[int, Transaction] = {}
        self._topology_version = 0
        self._closed = False
        self._executor: concurrent.futures.ThreadPoolExecutor | None = None
        #: trace recorder service, or None (see bt_engine.trace)
        self.recorder: Any = None
        self.hub = Hub(self.clock, is_idle_world=lambda: not self._live)
        self.hub.rt = self
        started = threading.Event()

        def hub_main() -> None:
            self.hub.thread_id = threading.get_ident()
            started.set()
            self.hub.run()
        self._thread = threading.Thread(target=hub_main, name="actorbt-hub", daemon=True)
        self._thread.start()
        started.wait()
        if bus is None or bus == "local":
            self.bus: Transport = LocalBus(self.hub)
        elif isinstance(bus, Transport):
            self.bus = bus
        else:
            self.bus = bus(self)  # type: ignore[operator]
        self.root: SubSystem = self.run_on_hub(RootSystem._create, self, "", None)
        self._watchdog = None
        if watchdog:
            from .watchdog import Watchdog
            self._watchdog = Watchdog(self.hub, watchdog)
            self._watchdog.start()

    # -- scope -----------------------------------------------------------------------
    @property
    def _rt(self) -> "Runtime":
        return self

    def _call_scope(self) -> SubSystem:
        return self.root

    def _topology_changed(self) -> None:
        self._topology_version += 1

    def add_subsystem(self, name: str, cls: type[SubSystem], *args: Any, **kwargs: Any) -> SubSystem:
        """Create subsystem ``name`` of class ``cls`` under the root."""
        return self.run_on_hub(self.root.add_subsystem, name, cls, *args, **kwargs)

    register_subsystem = add_subsystem

    def resolve(self, name: str) -> ActorRef:
        """The actor ``name`` seen from the root."""
        return self.root.resolve(name)

    def transactions(self) -> list[Transaction]:
        """Live transactions, oldest first."""
        return list(self._live.values())

    def stats(self) -> dict[str, int]:
        """Counts for leak checks: live transactions and tasks (greenlets)."""
        return {"transactions": len(self._live), "tasks": self.hub.tasks_alive}

    # -- time --------------------------------------------------------------------------
    def now(self) -> float:
        """Seconds on the runtime clock."""
        return self.clock.now()

    def sleep(self, seconds: float) -> None:
        """Block the calling actor for ``seconds`` on the runtime clock."""
        self.hub.sleep(seconds)

    def call_later(self, delay: float, fn: Callable, *args: Any) -> TimerHandle:
        """Run ``fn(*args)`` on the hub after ``delay`` [s]; it must not block."""
        return self.hub.call_at(self.clock.now() + delay, fn, *args)

    def call_every(self, period: float, fn: Callable, *args: Any) -> TimerHandle:
        """Run ``fn(*args)`` on the hub every ``period`` [s]. Under the virtual clock a
        periodic timer alone does not advance time: it runs while work is live."""
        return self.hub.call_at(self.clock.now() + period, fn, *args, period=period)

    def call_soon_threadsafe(self, fn: Callable, *args: Any) -> None:
        self.hub.call_soon_threadsafe(fn, *args)

    # -- threads -----------------------------------------------------------------------
    def run_on_hub(self, fn: Callable, *args: Any, **kwargs: Any) -> Any:
        """Run a non-blocking ``fn`` on the hub thread and return its result."""
        if self.hub.in_hub_thread():
            return fn(*args, **kwargs)
        self._check_open()
        c = _Completion()
        self.hub.call_soon_threadsafe(c.run, fn, args, kwargs)
        return c.wait(self)

    def offload(self, fn: Callable, *args: Any) -> Any:
        """Run blocking library code in a worker thread; the calling actor waits.

        Under the virtual clock, time does not jump while offloaded work runs.
        """
        hub = self.hub
        task = hub.require_task("offload")
        if self._executor is None:
            self._executor = concurrent.futures.ThreadPoolExecutor(
                max_workers=4, thread_name_prefix="actorbt-offload")
        w = Waiter(task)
        hub.outside_pending += 1

        def settle(f: concurrent.futures.Future) -> None:
            hub.outside_pending -= 1
            w.wake(f)
        fut = self._executor.submit(fn, *args)
        fut.add_done_callback(lambda f: hub.call_soon_threadsafe(settle, f))
        return w.wait().result()

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeClosedError("the runtime is closed")

    def _external(self, scope: SubSystem, name: str, mode: Mode, args: tuple, kwargs: dict,
                  cb: Callable | None, seconds: float | None) -> Any:
        """A call from a thread other than the hub: hand it over and wait."""
        from .invoke import dispatch
        self._check_open()
        if mode in (Mode.ITERATOR, Mode.TIMED_ITERATOR):
            return ExternalIterator(self, scope, name, mode, args, kwargs, seconds)
        c = _Completion()
        hub = self.hub
        if mode in (Mode.SYNC, Mode.TIMED):
            def body() -> None:
                try:
                    c.set(dispatch(self, scope.resolve(name), mode, args, kwargs, cb, seconds))
                except BaseException as e:  # delivered to the calling thread
                    c.set_error(e)

            def begin() -> None:
                c.task = Task(hub, body)
                hub.switch_to(c.task)
            hub.call_soon_threadsafe(begin)
        else:
            hub.call_soon_threadsafe(c.run, lambda: dispatch(
                self, scope.resolve(name), mode, args, kwargs, cb, seconds), (), {})
        return c.wait(self)

    # -- lifecycle ---------------------------------------------------------------------
    def close(self, grace: float = 5.0) -> None:
        """Cancel all live work, then stop the hub and every thread the runtime made."""
        if self._closed:
            return
        try:
            self.run_on_hub(self._cancel_all, "runtime closing")
            t0 = time.monotonic()
            while self.run_on_hub(lambda: bool(self._live or self.hub.tasks_alive)):
                if time.monotonic() - t0 > grace:
                    log.warning("runtime closing with %d live transactions", len(self._live))
                    break
                time.sleep(0.001)
        finally:
            self._closed = True
            self.bus.close()
            self.hub.stop()
            self._thread.join(timeout=grace)
            if self._watchdog is not None:
                self._watchdog.stop()
            if self._executor is not None:
                # Offloaded work cannot be interrupted; give it the grace period to end.
                self._executor.shutdown(wait=False, cancel_futures=True)
                for worker in list(getattr(self._executor, "_threads", ())):
                    worker.join(timeout=grace)

    def _cancel_all(self, reason: str) -> None:
        for txn in list(self._live.values()):
            if txn.parent is None:
                txn.cancel(reason)

    def __enter__(self) -> "Runtime":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class _Completion:
    """A one-shot result handed from the hub to a waiting outside thread."""

    __slots__ = ("_lock", "value", "error", "task")

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._lock.acquire()
        self.value: Any = None
        self.error: BaseException | None = None
        self.task: Task | None = None

    def set(self, value: Any) -> None:
        self.value = value
        self._lock.release()

    def set_error(self, error: BaseException) -> None:
        self.error = error
        self._lock.release()

    def run(self, fn: Callable, args: tuple, kwargs: dict) -> None:
        try:
            value = fn(*args, **kwargs)
        except BaseException as e:
            self.set_error(e)
        else:
            self.set(value)

    def wait(self, rt: Runtime) -> Any:
        try:
            self._lock.acquire()
        except KeyboardInterrupt:
            # Ctrl-C in the caller cancels the work it was waiting for, then re-raises.
            task = self.task
            if task is not None:
                rt.hub.call_soon_threadsafe(_interrupt, task)
                self._lock.acquire(timeout=5.0)
            raise
        if self.error is not None:
            raise self.error
        return self.value


def _interrupt(task: Task) -> None:
    if task.txns:
        task.txns[0].cancel("interrupted")
    else:
        task.deliver_cancel(Cancelled(None, "interrupted"))


class ExternalIterator:
    """Iterate an actor from a thread other than the hub.

    A pump task on the hub pulls one item per request, so the source is never read
    ahead of the consumer.
    """

    _END = object()

    def __init__(self, rt: Runtime, scope: SubSystem, name: str, mode: Mode, args: tuple,
                 kwargs: dict, seconds: float | None) -> None:
        self._rt = rt
        self._q: queue.SimpleQueue = queue.SimpleQueue()
        self._requests = 0
        self._waiter: Waiter | None = None
        self._it: Any = None
        self._closed = False
        self._task: Task | None = None

        def pump() -> None:
            from .invoke import dispatch
            try:
                self._it = it = dispatch(rt, scope.resolve(name), mode, args, kwargs, None, seconds)
                while True:
                    # While the consumer thread works on an item, virtual time stands
                    # still: the consumer counts as outside work the hub waits for.
                    if self._requests == 0:
                        rt.hub.outside_pending += 1
                        try:
                            while self._requests == 0:
                                self._waiter = Waiter(self._task)  # type: ignore[arg-type]
                                self._waiter.wait()
                        finally:
                            rt.hub.outside_pending -= 1
                    self._requests -= 1
                    try:
                        self._q.put(("v", next(it)))
                    except StopIteration:
                        self._q.put(("end", None))
                        return
            except BaseException as e:
                self._q.put(("err", e))
            finally:
                if self._it is not None:
                    self._it.close()

        def begin() -> None:
            self._task = Task(rt.hub, pump)
            rt.hub.switch_to(self._task)
        rt.run_on_hub(begin)

    def _request(self) -> None:
        self._requests += 1
        if self._waiter is not None:
            self._waiter.wake()

    def __iter__(self) -> "ExternalIterator":
        return self

    def __next__(self) -> Any:
        if self._closed:
            raise StopIteration
        self._rt.hub.call_soon_threadsafe(self._request)
        kind, value = self._q.get()
        if kind == "v":
            return value
        self._closed = True
        if kind == "err":
            if isinstance(value, Cancelled):
                raise StopIteration
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
        self._rt.run_on_hub(stop)

    def __enter__(self) -> "ExternalIterator":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def current_runtime() -> Runtime:
    """The runtime whose actor is running now (inside an actor or hub callback)."""
    g = greenlet.getcurrent()
    hub = getattr(g, "hub", None)
    if hub is not None:
        return hub.rt
    from .errors import ActorbtError
    raise ActorbtError("current_runtime() is only known inside an actor; pass the Runtime explicitly")
