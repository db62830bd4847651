"""Warn when actor code holds the hub thread too long (a stray ``time.sleep``, a
blocking socket read), naming the actor and where it blocked, like asyncio's debug mode.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
import traceback
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .hub import Hub

log = logging.getLogger("actorbt.watchdog")


class Watchdog:
    """A monitor thread that samples the hub every ``threshold / 4`` seconds."""

    def __init__(self, hub: "Hub", threshold: float) -> None:
        self.hub = hub
        self.threshold = threshold
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="actorbt-watchdog", daemon=True)
        self._warned_for = 0.0
        #: warnings issued, for tests and `actorbt` diagnostics
        self.warnings: list[str] = []

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)

    def _run(self) -> None:
        period = max(0.005, self.threshold / 4)
        while not self._stop.wait(period):
            since = self.hub.busy_since
            if not since or since == self._warned_for:
                continue
            held = time.monotonic() - since
            if held >= self.threshold:
                self._warned_for = since
                self._warn(held)

    def _warn(self, held: float) -> None:
        hub = self.hub
        task = hub.busy_task
        who = "a hub callback"
        if task is not None and task.txns:
            who = f"actor {task.txns[-1].path}"
        elif hub.busy_callback is not None:
            who = f"hub callback {getattr(hub.busy_callback, '__qualname__', hub.busy_callback)}"
        frame = sys._current_frames().get(hub.thread_id or -1)
        where = ""
        if frame is not None:
            last = traceback.extract_stack(frame)[-1]
            where = f" at {last.filename}:{last.lineno} in {last.name}: {last.line}"
        msg = (
            f"hub blocked for {held:.2f} s by {who}{where}; use runtime.offload() or "
            "sleep on the runtime clock instead of blocking the hub"
        )
        self.warnings.append(msg)
        log.warning(msg)
