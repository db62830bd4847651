"""Every ```yaml example in docs/missions.md is a complete mission that loads and runs."""

from __future__ import annotations

import re
from pathlib import Path


from bt_engine import Runtime
from bt_engine.trees import NODE_TYPES, TreeHost, parse_mission, walk

DOC = Path(__file__).parent.parent / "docs" / "missions.md"
EXAMPLES = re.findall(r"^```yaml\n(.*?)^```", DOC.read_text(encoding="utf-8"), flags=re.S | re.M)


def test_there_is_an_example_for_every_node_type() -> None:
    kinds: set[str] = set()
    for text in EXAMPLES:
        for node in walk(parse_mission(text, "doc").root):
            kinds.add(node.kind)
    assert {t for t in NODE_TYPES if t not in ("fallback", "reactive_fallback")} <= kinds


def test_every_example_loads_and_runs(rt: Runtime, tmp_path: Path) -> None:
    names = []
    for text in EXAMPLES:
        name = parse_mission(text, "doc").name
        (tmp_path / f"{name}.yaml").write_text(text)
        names.append(name)
    host = TreeHost(rt)
    host.load_folder(tmp_path)
    for name in names:
        assert isinstance(rt.call(name), dict), name
    assert rt.stats() == {"transactions": 0, "tasks": 0}
