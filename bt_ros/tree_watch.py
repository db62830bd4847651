"""Watch the trees folder of ``actorbt serve``: a tree file added, edited or removed
while it runs reloads the folder, and the server then serves what loaded.

Polling, not inotify: every :data:`PERIOD` seconds a thread compares the folder's
``*.yaml``/``*.yml`` names, sizes and modification times with the last look (a few
``stat`` calls; no dependency, works on every file system). On a change the folder is
loaded again on the hub (:meth:`bt_engine.trees.TreeHost.reload_folder`), and
``on_reloaded`` hears which tree files do not load (``file:line:column: message``).
"""

from __future__ import annotations

import logging
import pathlib
import threading
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from bt_engine import Runtime

log = logging.getLogger("actorbt.ros.server")

__all__ = ["PERIOD", "TreeFolderWatch", "folder_state"]

#: seconds between two looks at the folder
PERIOD = 1.0


def folder_state(folder: pathlib.Path) -> dict[str, tuple[int, int]]:
    """Each tree file of ``folder``: name -> (modification time [ns], size)."""
    state: dict[str, tuple[int, int]] = {}
    try:
        entries = list(folder.iterdir())
    except OSError:
        return state
    for p in entries:
        if p.suffix in (".yaml", ".yml"):
            try:
                st = p.stat()
            except OSError:  # removed while we looked
                continue
            state[p.name] = (st.st_mtime_ns, st.st_size)
    return state


class TreeFolderWatch:
    """Reloads ``folder``'s trees into ``rt`` when the folder changes.

    Args:
        rt: the runtime whose TreeHost holds the folder's trees.
        folder: the trees folder.
        on_reloaded: called (on the watch thread) after each reload with the errors of
            the folder's files that did not load, each ``file:line:column: message``.
        period: seconds between two looks.
    """

    def __init__(
        self,
        rt: Runtime,
        folder: "str | pathlib.Path",
        on_reloaded: Callable[[list[str]], None],
        period: float = PERIOD,
    ) -> None:
        self.rt = rt
        self.folder = pathlib.Path(folder)
        self.on_reloaded = on_reloaded
        self.period = period
        self._state = folder_state(self.folder)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="actorbt-tree-watch", daemon=True)

    def start(self) -> "TreeFolderWatch":
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(5.0)

    def _loop(self) -> None:
        while not self._stop.wait(self.period):
            state = folder_state(self.folder)
            if state == self._state:
                continue
            self._state = state
            try:
                errors = self.reload()
            except Exception:  # the runtime closed, or a surprise: keep watching
                if self._stop.is_set():
                    return
                log.exception("reloading the trees folder %s failed", self.folder)
                continue
            try:
                self.on_reloaded(errors)
            except Exception:
                log.exception("serving the reloaded trees failed")

    def reload(self) -> list[str]:
        """Load the folder again now; the errors of its files that did not load."""
        from bt_engine.trees import tree_host

        host = tree_host(self.rt, create=True)
        assert host is not None
        self.rt.run_on_hub(host.reload_folder, self.folder)
        where = self.folder.resolve()
        errors = [e for e in host.library.broken.values() if pathlib.Path(e.pos.file).resolve().parent == where]
        return [str(e) for e in sorted(errors, key=lambda e: (e.pos.file, e.pos.line, e.pos.column))]
