"""Live progress of tree runs for a terminal, and ``--arg k=v`` parsing.

``actorbt run TREE`` adds a :class:`ProgressPrinter` to the host's observers and turns
its ``--arg`` pairs into inputs with :func:`parse_inputs`.
"""

from __future__ import annotations

import sys
from typing import Any, Iterable, TextIO

from py_trees.common import Status

from bt_engine.trees import InputError, Mission, TreeObserver, TreeRun, suggest

__all__ = ["ProgressPrinter", "parse_inputs"]


def parse_inputs(mission: Mission, pairs: Iterable[str]) -> dict[str, Any]:
    """``["rounds=3", "room=kitchen"]`` -> typed inputs of ``mission``.

    Values are parsed by the input's declared type (lists, dicts and ``any`` as YAML).

    Raises:
        InputError: a pair without ``=``, an unknown input, or a value of the wrong type.
    """
    names = [spec.name for spec in mission.inputs]
    values: dict[str, Any] = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"--arg {pair!r}: expected NAME=VALUE")
        spec = mission.input(key)
        if spec is None:
            raise InputError(
                f"tree {mission.name!r} has no input {key!r}{suggest(key, names)}, "
                f"expected one of: {', '.join(names) or '(none)'}"
            )
        try:
            values[key] = spec.type.coerce(text)
        except ValueError as exc:
            raise InputError(f"input {key!r} of tree {mission.name!r}: {exc}") from None
    return values


_SHOWN = {Status.RUNNING: "running", Status.SUCCESS: "success", Status.FAILURE: "FAILURE"}


class ProgressPrinter(TreeObserver):
    """Prints status changes as they happen, and the active node path when it moves
    (tree and node path, e.g. ``demo_patrol: active: sequence/repeat x2/round/wait 0.5s``).

    Resets to INVALID after a finished node are not shown; a running node stopped by
    its parent is shown as ``halted``. Nested runs are indented under their caller.

    Args:
        stream: where to print (stdout by default).
        ticks: also print one line per tick.
        outcomes: print how the outermost run ended (``SUCCESS {outputs}`` or ``FAILURE:
            why``); False when the caller prints the outcome itself (``actorbt run``
            does). Nested runs, and a stopped outermost run, are always shown.
    """

    def __init__(self, stream: TextIO | None = None, ticks: bool = False, outcomes: bool = True) -> None:
        self.stream = stream or sys.stdout
        self.ticks = ticks
        self.outcomes = outcomes
        self._tips: dict[int, str | None] = {}

    def _line(self, run: TreeRun, text: str) -> None:
        print(f"[{run.rt.now():8.2f}s] {'  ' * run.depth}{run.mission.name}: {text}", file=self.stream, flush=True)

    def run_started(self, run: TreeRun) -> None:
        args = ", ".join(f"{k}={v!r}" for k, v in run.inputs.items())
        self._line(run, f"started ({args})" if args else "started")

    def tick(self, run: TreeRun) -> None:
        if self.ticks:
            self._line(run, f"tick {run.ticks}")

    def status_changed(self, run: TreeRun, path: str, old: Status, new: Status) -> None:
        if new is Status.INVALID:
            if old is Status.RUNNING:
                self._line(run, f"{path} halted")
            return
        if new is Status.RUNNING and old is Status.RUNNING:
            return
        node_feedback = ""
        if new is Status.FAILURE:
            for behaviour, p in run.paths.items():
                if p == path and behaviour.feedback_message:
                    node_feedback = f" ({behaviour.feedback_message})"
                    break
        self._line(run, f"{path} {_SHOWN[new]}{node_feedback}")

    def tick_finished(self, run: TreeRun) -> None:
        tip = run.tip_path() if run.status is Status.RUNNING else None
        if tip is not None and tip != self._tips.get(run.id):
            self._line(run, f"active: {tip}")
        self._tips[run.id] = tip

    def run_finished(self, run: TreeRun, status: Status, outcome: Any) -> None:
        self._tips.pop(run.id, None)
        if not self.outcomes and run.depth == 0 and status in (Status.SUCCESS, Status.FAILURE):
            return  # the caller prints the outcome
        if status is Status.SUCCESS:
            self._line(run, f"SUCCESS {outcome}")
        elif status is Status.FAILURE:
            self._line(run, f"FAILURE: {outcome}")
        else:
            self._line(run, f"stopped: {getattr(outcome, 'reason', None) or type(outcome).__name__}")
