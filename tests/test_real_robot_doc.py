"""docs/real-robot.md's interfaces table is what `actorbt robot` offers: every topic and
action the simulated robot and the navstack publish, subscribe to or serve has its row,
with the same type, and no row names one they do not offer."""

from __future__ import annotations

import contextlib
import io
import json
import re
from pathlib import Path

import pytest

from bt_cli.main import main

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "real-robot.md"
ROW = re.compile(r"^\| `(?P<name>/[^`]+)` \| `(?P<type>[^`]+)` \|")


def documented() -> dict[str, str]:
    text = DOC.read_text()
    section = text[text.index("## The interfaces actorbt uses") :]
    section = section[: section.index("\n## ", 3)]
    rows = [ROW.match(line) for line in section.splitlines()]
    return {m["name"]: m["type"] for m in rows if m}


@pytest.fixture(scope="module")
def offered() -> dict[str, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(
            [
                "--config",
                str(REPO / "actorbt.yaml"),
                "robot",
                "--world",
                "house",
                "--interfaces",
                "--json",
                "--bus",
                "local",
            ]
        )
    assert rc == 0
    data = json.loads(out.getvalue())
    return {i["name"]: i["type"] for i in data["topics"] + data["actions"]}


def test_the_table_lists_what_the_robot_side_offers(offered):
    table = documented()
    assert len(table) >= 15, table
    missing = {n: t for n, t in offered.items() if n not in table}
    extra = {n: t for n, t in table.items() if n not in offered}
    wrong = {n: (table[n], t) for n, t in offered.items() if n in table and table[n] != t}
    assert not missing, f"offered but not in docs/real-robot.md: {missing}"
    assert not extra, f"in docs/real-robot.md but not offered: {extra}"
    assert not wrong, f"documented type differs (doc, offered): {wrong}"


def test_each_row_names_its_upstream_source():
    text = DOC.read_text()
    section = text[text.index("## The interfaces actorbt uses") :]
    section = section[: section.index("\n## ", 3)]
    for line in section.splitlines():
        if ROW.match(line):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            assert len(cells) == 5 and cells[4], f"a row without its source: {line}"
