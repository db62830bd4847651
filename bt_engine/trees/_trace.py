"""Recording tree runs as JSON Lines traces.

A trace starts with a header (tree, inputs, seed, versions, the runtime-clock time the
recording started (``start``) and which clock it is (``clock``: ``virtual`` or
``wall``), the host's tick periods (``max_period``, ``behaviour_period``), and the file
and sha256 of every tree the run may use), followed by one event per line, each stamped
with the runtime clock (``t``, seconds):

=========  ===============================================================
``run``     a tree run started: ``run`` (ordinal), ``tree``, ``parent``
``tick``    tick ``n`` of run ``run``
``status``  node ``path`` of run ``run`` went ``old`` -> ``new``
``call``    actor leaf ``path`` started ``actor`` (call ordinal ``call``)
            with ``args``/``kwargs``; ``target`` is its path, ``kind`` its kind
``return``  call ``call`` ended: ``state`` done (``value``), failed
            (``error``) or cancelled (``reason``)
``write``   blackboard ``key`` := ``value``
``end``     run ``run`` ended with ``status`` (``outputs`` or ``error``)
``log``     a log record (``level``, ``logger``, ``msg``)
``txn``     with ``transactions=True``: every runtime transaction's start
            and end (``phase``), from the runtime's recorder hooks
=========  ===============================================================

A recorder records every run of its host unless told to :meth:`TraceRecorder.follow`
one transaction (``serve`` does, for each goal): then only the runs under it, and with
``transactions=True`` only the transactions under it.

Values are stored as JSON: dataclasses, ROS messages and other objects become mappings
with a ``__type__`` key, anything else its ``repr``. Replay (``_replay``) answers actor
calls with these values.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import logging
import math
import platform
import threading
from importlib import metadata
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Callable, Protocol

from py_trees.common import Status

from ..transaction import TxnState
from ._model import Do, PluginNode, walk
from ._run import TreeObserver, TreeRun

if TYPE_CHECKING:
    from ._behaviours import CallSite
    from ._host import TreeHost

__all__ = ["TRACE_FORMAT", "TRACE_VERSION", "EventBuilder", "TraceRecorder", "plugin_modules", "to_json", "tree_files"]

TRACE_FORMAT = "actorbt-trace"
TRACE_VERSION = 1


def to_json(value: Any, _depth: int = 0) -> Any:
    """A JSON-able copy of ``value`` (see the module docstring)."""
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else {"__float__": repr(value)}
    if _depth > 32:
        return {"__repr__": "..."}
    d = _depth + 1
    if isinstance(value, dict):
        return {str(k): to_json(v, d) for k, v in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [to_json(v, d) for v in value]
    if isinstance(value, BaseException):
        return {"__error__": type(value).__name__, "message": str(value)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: to_json(getattr(value, f.name), d) for f in dataclasses.fields(value)}
        return {"__type__": type(value).__qualname__, **fields}
    get_fields = getattr(type(value), "get_fields_and_field_types", None)
    if callable(get_fields):  # a ROS 2 message
        fields = {name: to_json(getattr(value, name), d) for name in get_fields()}
        return {"__type__": f"{type(value).__module__}.{type(value).__name__}", **fields}
    tolist = getattr(value, "tolist", None)
    if callable(tolist):  # numpy arrays and scalars
        return to_json(tolist(), d)
    return {"__repr__": repr(value)[:500]}


def tree_files(host: TreeHost, root: str) -> dict[str, dict[str, str]]:
    """``{tree: {file, sha256}}`` for ``root`` and every library tree it may call."""
    found: dict[str, dict[str, str]] = {}
    todo = [root]
    while todo:
        name = todo.pop()
        if name in found or name not in host.library:
            continue
        mission = host.library[name]
        found[name] = {"file": _portable(mission.file), "sha256": mission.source_hash}
        todo.extend(n.actor for n in walk(mission.root) if isinstance(n, Do))
    return found


def plugin_modules(host: TreeHost, root: str) -> dict[str, str]:
    """``{plugin node: the module that defines it}`` for the controls and decorators
    written in Python that ``root`` and the trees it may call use (replay imports them)."""
    found: dict[str, str] = {}
    for name in tree_files(host, root):
        for node in walk(host.library[name].root):
            if isinstance(node, PluginNode) and node.plugin in host.nodes:
                module = host.nodes[node.plugin].module
                if module is not None:
                    found[node.plugin] = module
    return found


def _portable(file: str) -> str:
    path = Path(file)
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def _versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for dist in ("actorbt", "py_trees", "greenlet"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "unknown"
    return out


class EventBuilder(TreeObserver):
    """Turns what tree runs do into trace events and hands each to ``sink(event)``.

    Runs and calls are numbered in the order they start (``run``, ``call``), so two
    executions of the same tree give the same events whatever the transaction ids.
    """

    def __init__(self, sink: Callable[[dict[str, Any]], None], accept: Callable[[TreeRun], bool] | None = None) -> None:
        self.sink = sink
        self.accept = accept  # which runs to report (None: all)
        self._runs: dict[int, int] = {}
        self._calls: dict[int, int] = {}  # id(txn) -> call number, while the call runs
        self._call_count = 0

    def _run(self, run: TreeRun) -> int:
        return self._runs.setdefault(run.id, len(self._runs) + 1)

    def _emit(self, run: TreeRun, event: dict[str, Any]) -> None:
        self.sink({"t": run.rt.now(), **event})

    def _skip(self, run: TreeRun) -> bool:
        return self.accept is not None and run.id not in self._runs and not self.accept(run)

    def run_started(self, run: TreeRun) -> None:
        if self._skip(run):
            return
        parent = self._runs.get(run.parent.id) if run.parent is not None else None
        self._emit(run, {"type": "run", "run": self._run(run), "tree": run.mission.name, "parent": parent})

    def tick(self, run: TreeRun) -> None:
        if self._skip(run):
            return
        self._emit(run, {"type": "tick", "run": self._run(run), "n": run.ticks})

    def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
        if self._skip(run):
            return
        self._emit(run, {"type": "status", "run": self._run(run), "path": path, "old": old.name, "new": new.name})

    def blackboard_write(self, run: TreeRun, key: str, value: Any) -> None:
        if self._skip(run):
            return
        self._emit(run, {"type": "write", "run": self._run(run), "key": key, "value": to_json(value)})

    def actor_started(self, run: TreeRun, leaf: CallSite, args: tuple, kwargs: dict, txn: Any) -> None:
        if self._skip(run):
            return
        self._call_count += 1
        number = self._calls[id(txn)] = self._call_count
        self._emit(
            run,
            {
                "type": "call",
                "run": self._run(run),
                "path": leaf.path,
                "call": number,
                "actor": leaf.node.actor,
                "target": leaf.actor_path,
                "kind": leaf.actor_kind,
                "args": to_json(list(args)),
                "kwargs": to_json(kwargs),
            },
        )

    def actor_finished(self, run: TreeRun, leaf: CallSite, txn: Any) -> None:
        if self._skip(run):
            return
        event: dict[str, Any] = {
            "type": "return",
            "run": self._run(run),
            "path": leaf.path,
            "call": self._calls.pop(id(txn), 0),
            "actor": leaf.node.actor,
        }
        if txn.state is TxnState.DONE:
            event.update(state="done", value=to_json(txn.result))
        elif txn.state is TxnState.CANCELLED:
            event.update(state="cancelled", reason=txn.reason)
        else:
            event.update(state="failed", error=f"{type(txn.error).__name__}: {txn.error}")
        self._emit(run, event)

    def run_finished(self, run: TreeRun, status: Status, outcome: Any) -> None:
        if self._skip(run):
            return
        event: dict[str, Any] = {"type": "end", "run": self._run(run), "status": status.name}
        if status is Status.SUCCESS:
            event["outputs"] = to_json(outcome)
        else:
            event["error"] = f"{type(outcome).__name__}: {outcome}"
        self._emit(run, event)


class _LogHandler(logging.Handler):
    def __init__(self, recorder: TraceRecorder) -> None:
        super().__init__(logging.INFO)
        self.recorder = recorder

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.recorder.emit(
                {"type": "log", "level": record.levelname, "logger": record.name, "msg": record.getMessage()}
            )
        except Exception:  # a log line must never break the run
            self.handleError(record)


class _RuntimeHooks:
    """What the runtime calls as ``rt.recorder`` (Transaction start and end). The hooks
    that were ``rt.recorder`` before are told too (another recorder, a live view), also
    once this recorder is closed: recorders opened and closed in any order keep the chain."""

    def __init__(self, recorder: TraceRecorder) -> None:
        self.recorder = recorder

    def call_started(self, txn: Any) -> None:
        if self.recorder.transactions and self.recorder.followed(txn):
            parent = txn.parent.id if txn.parent is not None else None
            self.recorder.emit(
                {
                    "type": "txn",
                    "phase": "start",
                    "txn": txn.id,
                    "parent": parent,
                    "actor": txn.path,
                    "mode": txn.mode.value,
                }
            )
        previous = self.recorder._previous_recorder
        if previous is not None:
            previous.call_started(txn)

    def call_finished(self, txn: Any) -> None:
        if self.recorder.transactions and self.recorder.followed(txn):
            self.recorder.emit(
                {"type": "txn", "phase": "end", "txn": txn.id, "actor": txn.path, "state": txn.state.value}
            )
        previous = self.recorder._previous_recorder
        if previous is not None:
            previous.call_finished(txn)

    def emit(self, event: dict[str, Any]) -> None:
        self.recorder.emit(event)


class TextSink(Protocol):
    """An open text stream a trace goes to (a file, ``sys.stdout``, a bag's trace
    topic): each line is written, and it is flushed when the recorder closes."""

    def write(self, text: str, /) -> object: ...

    def flush(self) -> None: ...


class TraceRecorder:
    """Records tree runs of a host to a JSON Lines file (or any text stream).

    Use as a context manager around the runs to record::

        with TraceRecorder("run.jsonl", host, tree="demo_patrol", inputs={}) as rec:
            rt.call("demo_patrol")

    While open it is one of ``host.observers``, it is ``rt.recorder`` (the runtime's
    recorder service: ``rt.recorder.emit(event)`` adds an event), and it records the
    log records of level INFO and above that the logging configuration lets through.

    Args:
        sink: a path or an open text stream.
        host: whose runs to record.
        tree: the tree the recording is about (for the header and replay).
        inputs: the inputs it is called with.
        seed: the world seed, if any.
        transactions: also record every runtime transaction (start and end).
    """

    def __init__(
        self,
        sink: str | Path | TextSink,
        host: TreeHost,
        *,
        tree: str,
        inputs: dict[str, Any] | None = None,
        seed: int | None = None,
        transactions: bool = False,
    ) -> None:
        self.host = host
        self.rt = host.rt
        self.transactions = transactions
        self._out: TextSink
        self._file: IO[str] | None = None  # the file it opened itself, closed with it
        if isinstance(sink, (str, Path)):
            self._out = self._file = open(sink, "w", encoding="utf-8")
        else:
            self._out = sink
        self._follow: int | None = None
        self.builder = EventBuilder(self.emit, self._accept)
        self._hooks = _RuntimeHooks(self)
        self._log = _LogHandler(self)
        self._closed = False
        self._lock = threading.Lock()  # log records may come from other threads
        header = {
            "type": "header",
            "format": TRACE_FORMAT,
            "version": TRACE_VERSION,
            "tree": tree,
            "inputs": to_json(dict(inputs or {})),
            "seed": seed,
            "start": self.rt.now(),
            "clock": "virtual" if getattr(self.rt.clock, "virtual", False) else "wall",
            "recorded": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "max_period": host.max_period,
            "behaviour_period": host.behaviour_period,
            "versions": _versions(),
            "trees": tree_files(host, tree),
            "nodes": plugin_modules(host, tree),
        }
        self._write(header)
        host.observers.append(self.builder)
        self._previous_recorder = self.rt.recorder
        self.rt.recorder = self._hooks
        logging.getLogger().addHandler(self._log)

    def follow(self, txn: Any) -> None:
        """Record only what runs under transaction ``txn`` (or its id) from now on: its
        tree runs and the runs they lead to, not those of other callers of the host."""
        self._follow = txn if isinstance(txn, int) else txn.id

    def followed(self, txn: Any) -> bool:
        """Whether transaction ``txn`` is recorded (under the followed one, if any)."""
        if self._follow is None:
            return True
        while txn is not None:
            if txn.id == self._follow:
                return True
            txn = txn.parent
        return False

    def _accept(self, run: TreeRun) -> bool:
        if self._follow is None:
            return True
        while run.parent is not None:
            run = run.parent
        if run.txn_id is None:  # being built (its inputs are written): the caller's
            task = self.rt.hub.current_task()
            return self.followed(task.txns[-1]) if task is not None and task.txns else False
        if run.txn_id == self._follow:
            return True
        return self.followed(self.rt.txns.live.get(run.txn_id))

    def _write(self, event: dict[str, Any]) -> None:
        line = json.dumps(event, default=repr, separators=(",", ":")) + "\n"
        with self._lock:
            self._out.write(line)

    def emit(self, event: dict[str, Any]) -> None:
        """Add an event; ``t`` (runtime clock) is filled in when missing."""
        if self._closed:
            return
        if "t" not in event:
            event = {"t": self.rt.now(), **event}
        self._write(event)

    def close(self) -> None:
        """Stop recording and close the file."""
        if self._closed:
            return
        self._closed = True
        logging.getLogger().removeHandler(self._log)
        if self.builder in self.host.observers:
            self.host.observers.remove(self.builder)
        if self.rt.recorder is self._hooks:
            self.rt.recorder = self._previous_recorder
        if self._file is not None:
            self._file.close()
        else:
            self._out.flush()

    def __enter__(self) -> TraceRecorder:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
