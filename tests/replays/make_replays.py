"""Regenerate the recorded runs in this folder (from the repository root):

    .venv/bin/python tests/replays/make_replays.py

Each ``.jsonl`` here is replayed by ``tests/test_trees_trace.py`` with no actors
loaded; the tree files are found at the paths the traces recorded.

``bt_pick_place_house_seed0.jsonl`` is a whole simulated episode; re-record it with
``.venv/bin/actorbt demo --seed 0 --out /tmp/demo`` and copy ``/tmp/demo/trace.jsonl`` here
after changing a mission tree.
"""

from __future__ import annotations

from pathlib import Path

from bt_engine import Runtime
from bt_engine.trees import TreeHost
from bt_engine.trees._trace import TraceRecorder
from bt_engine.trees.testing import ScriptedActors

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]

RECORDINGS = [
    ("demo_patrol.jsonl", "demo_patrol", {"rounds": 1}),
    ("fetch_scripted.jsonl", "fetch_scripted", {"target": "can"}),
]


def main() -> None:
    with Runtime(clock="virtual") as rt:
        rt.add_subsystem("script", ScriptedActors)
        host = TreeHost(rt)
        host.load_folder(REPO / "trees", strict=False)  # trees needing robot actors are skipped
        host.load_folder(HERE)
        for file, tree, inputs in RECORDINGS:
            with TraceRecorder(HERE / file, host, tree=tree, inputs=inputs):
                rt.call(tree, **inputs)
            print(f"recorded {file}")


if __name__ == "__main__":
    main()
