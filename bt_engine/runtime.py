"""The Runtime: one object owning the hub, clock, root SubSystem, transaction table,
trace recorder and bus. Nothing in the engine is module-global.

    with Runtime() as rt:                     # virtual clock, local bus
        rt.add_subsystem("robot", Robot)
        rt.call("robot.goto", 1.0, 2.0, 0.0)  # from any thread
"""

from __future__ import annotations

import concurrent.futures
import logging
import threading
import time
from typing import Any, Callable, TypeVar

import greenlet

from .actor import ActorRef, actor
from .api import CallApi
from .bus.local import LocalBus
from .bus.transport import Transport
from .clock import Clock, make_clock
from .errors import ActorbtError, BadModeError
from .external import run_on_hub
from .hub import Hub, TimerHandle, Waiter
from .subsystem import SubSystem
from .transaction import Transaction, TransactionTable
from .watchdog import Watchdog

_S = TypeVar("_S", bound=SubSystem)  # add_subsystem returns what it was given

log = logging.getLogger("actorbt")


class RootSystem(SubSystem):
    """The root scope. It holds the built-in actors."""

    @actor(read_only=True)
    def sleep(self, seconds: float) -> None:
        """Wait ``seconds`` [s] on the runtime clock (virtual time jumps).

        Args:
            seconds: how long to wait [s]
        """
        self._rt.sleep(seconds)


class Runtime(CallApi):
    """The engine: hub thread, clock, actors, transactions, bus.

    Args:
        clock: ``"virtual"`` (default), ``"wall"`` or a Clock.
        bus: ``"local"`` (default), a Transport, or a factory ``f(runtime) -> Transport``.
        watchdog: warn when actor code holds the hub longer than this [s, wall]; None
            disables it.
    """

    def __init__(
        self,
        clock: "str | Clock | None" = None,
        bus: "str | Transport | Callable[[Runtime], Transport] | None" = None,
        watchdog: float | None = 0.5,
    ) -> None:
        self.clock = make_clock(clock)
        self._topology_version = 0
        self._executor: concurrent.futures.ThreadPoolExecutor | None = None
        self._extensions: dict[str, Any] = {}
        self.hub = Hub(self.clock, is_idle_world=self._nothing_live)
        self.hub.rt = self
        #: the live transactions (and the trace recorder hook)
        self.txns = TransactionTable(self.hub, self.clock)
        started = threading.Event()

        def hub_main(hub: Hub = self.hub) -> None:
            hub.thread_id = threading.get_ident()
            started.set()
            hub.run()

        self._thread = threading.Thread(target=hub_main, name="actorbt-hub", daemon=True)
        self._thread.start()
        started.wait()
        if bus is None or bus == "local":
            self.bus: Transport = LocalBus(self.hub)
        elif isinstance(bus, Transport):
            self.bus = bus
        elif isinstance(bus, str):
            raise BadModeError(f"unknown bus {bus!r}; expected 'local', a Transport or a function making one")
        else:
            self.bus = bus(self)
        self.root: SubSystem = self.run_on_hub(RootSystem._create, self, "", None)
        self._watchdog: Watchdog | None = None
        if watchdog:
            self._watchdog = Watchdog(self.hub, watchdog)
            self._watchdog.start()

    def _nothing_live(self) -> bool:
        return not self.txns.live

    # -- scope -----------------------------------------------------------------------
    @property
    def _rt(self) -> "Runtime":
        return self

    def _call_scope(self) -> SubSystem:
        return self.root

    def _txns(self) -> TransactionTable:
        return self.txns

    def _topology_changed(self) -> None:
        self._topology_version += 1

    @property
    def recorder(self) -> Any:
        """The trace recorder hook (``call_started``/``call_finished``), or None."""
        return self.txns.recorder

    @recorder.setter
    def recorder(self, value: Any) -> None:
        self.txns.recorder = value

    def extension(self, key: str, factory: Callable[[], Any] | None = None) -> Any:
        """A service a layer above the engine keeps per runtime (the trees of this
        runtime, for one), made by ``factory()`` on first use; None without a factory.

        Registries belong to their runtime, not to modules: they go when it goes.
        """
        value = self._extensions.get(key)
        if value is None and factory is not None:
            value = self._extensions[key] = factory()
        return value

    def add_subsystem(self, name: str, cls: type[_S], *args: Any, **kwargs: Any) -> _S:
        """Create subsystem ``name`` of class ``cls`` under the root."""
        return self.run_on_hub(self.root.add_subsystem, name, cls, *args, **kwargs)

    register_subsystem = add_subsystem

    def resolve(self, name: str) -> ActorRef:
        """The actor ``name`` seen from the root."""
        return self.root.resolve(name)

    def transactions(self) -> list[Transaction]:
        """Live transactions, oldest first."""
        return list(self.txns.live.values())

    def stats(self) -> dict[str, int]:
        """Counts for leak checks: live transactions and tasks (greenlets)."""
        return {"transactions": len(self.txns.live), "tasks": self.hub.tasks_alive}

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
        if kwargs:
            return run_on_hub(self.hub, lambda: fn(*args, **kwargs))
        return run_on_hub(self.hub, fn, *args)

    def offload(self, fn: Callable, *args: Any) -> Any:
        """Run blocking library code in a worker thread; the calling actor waits.

        Under the virtual clock, time stands still while offloaded work runs.
        """
        hub = self.hub
        task = hub.require_task("offload")
        if self._executor is None:
            self._executor = concurrent.futures.ThreadPoolExecutor(max_workers=4, thread_name_prefix="actorbt-offload")
        w = Waiter(task)
        hub.outside_pending += 1

        def settle(f: concurrent.futures.Future) -> None:
            hub.outside_pending -= 1
            w.wake(f)

        fut = self._executor.submit(fn, *args)
        fut.add_done_callback(lambda f: hub.call_soon_threadsafe(settle, f))
        return w.wait().result()

    # -- lifecycle ---------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self.hub.stopped

    def close(self, grace: float = 5.0) -> None:
        """Cancel all live work, then stop the hub and every thread the runtime made."""
        if self.hub.stopped:
            return
        try:
            self.run_on_hub(self._cancel_all, "runtime closing")
            t0 = time.monotonic()
            while self.run_on_hub(lambda: bool(self.txns.live or self.hub.tasks_alive)):
                if time.monotonic() - t0 > grace:
                    log.warning("runtime closing with %d live transactions", len(self.txns.live))
                    break
                time.sleep(0.001)
        finally:
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
            self._extensions.clear()

    def _cancel_all(self, reason: str) -> None:
        for txn in self.txns.roots():
            txn.cancel(reason)

    def __enter__(self) -> "Runtime":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def current_runtime() -> Runtime:
    """The runtime whose actor is running now (inside an actor or hub callback)."""
    g = greenlet.getcurrent()
    hub = getattr(g, "hub", None)
    if hub is not None:
        return hub.rt
    raise ActorbtError("current_runtime() is only known inside an actor; pass the Runtime explicitly")
