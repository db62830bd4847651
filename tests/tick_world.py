"""The tick-table rig of the control-node tests (tests/test_trees_ticks.py,
tests/test_trees_controls.py): scripted actors (``act(tag)`` runs until the test finishes
it), a manual clock, and ``table`` to check statuses tick by tick. The ``w`` fixture in
tests/conftest.py hands one to a test."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any, Callable

from bt_engine import Runtime
from bt_engine.trees import TreeHost
from bt_engine.trees.testing import ManualClock, ScriptedActors

LETTER = {"RUNNING": "R", "SUCCESS": "S", "FAILURE": "F", "INVALID": "I"}


class World:
    def __init__(self, rt: Runtime, clock: ManualClock, folder: Path) -> None:
        self.rt = rt
        self.clock = clock
        self.folder = folder
        self.script: ScriptedActors = rt.add_subsystem("script", ScriptedActors)
        self.host = TreeHost(rt)

    def tree(self, body: str, **inputs: Any):
        text = textwrap.dedent(body)
        name = text.split("name:", 1)[1].split()[0]
        path = self.folder / f"{name}.yaml"
        path.write_text(text)
        self.host.load_file(path)
        return self.host.prepare(name, **inputs)

    # actions, run on the hub before a tick
    def finish(self, tag: str, result: Any = True) -> Callable[[], None]:
        return lambda: self.script.finish(tag, result)

    def fail(self, tag: str) -> Callable[[], None]:
        return lambda: self.script.fail(tag)

    def write(self, run, key: str, value: Any) -> Callable[[], None]:
        return lambda: run.bb.set(key, value)

    def table(self, run, columns: str, rows: list[tuple]) -> None:
        names = columns.split()
        for i, (action, *expected) in enumerate(rows, 1):
            if isinstance(action, (int, float)):  # let runtime-clock time pass
                self.clock.advance(self.rt, action)
            elif action is not None:
                self.rt.run_on_hub(action)
            self.rt.run_on_hub(run.tick)
            by_name = {path.rsplit("/", 1)[-1]: LETTER[s.name] for path, s in run.statuses().items()}
            got = [by_name[n] for n in names]
            assert got == list(expected), f"tick {i}: {dict(zip(names, got))} != {dict(zip(names, expected))}"
