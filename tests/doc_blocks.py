"""The fenced code blocks of README.md and docs/*.md, with the mark above each
(tests/test_docs_commands.py and tests/test_docs_run.py read them)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

_FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.S | re.M)
_MARK = re.compile(r"<!--\s*doc-test:\s*(.*?)\s*-->\s*$")


@dataclass(frozen=True)
class Block:
    doc: Path
    line: int  # the fence's line, 1-based
    lang: str
    text: str
    mark: str  # what a `<!-- doc-test: ... -->` line above it says; "" when none

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(ROOT)}:{self.line}"


def blocks_of(doc: Path) -> list[Block]:
    text = doc.read_text(encoding="utf-8")
    out = []
    for fence in _FENCE.finditer(text):
        line = text.count("\n", 0, fence.start()) + 1
        above = text[: fence.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = _MARK.search(above)
        out.append(Block(doc, line, fence.group(1), fence.group(2), mark.group(1) if mark else ""))
    return out
