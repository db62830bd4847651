"""The malformed-mission corpus: one defect per file, one one-line error each."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from bt_engine.trees import MissionError, check_files
from bt_engine.trees.testing import DEMO_BEHAVIOURS, demo_resolver

CORPUS = Path(__file__).parent / "bad_missions"
FILES = sorted(CORPUS.glob("*.yaml"))
EXPECT = re.compile(r"#\s*expect:\s*(\d+):(\d+):\s*(.+?)\s*$")


def expectation(path: Path) -> tuple[int, int, str]:
    first = path.read_text(encoding="utf-8").splitlines()[0]
    match = EXPECT.match(first)
    assert match, f"{path.name}: first line must be '# expect: LINE:COL: text'"
    return int(match.group(1)), int(match.group(2)), match.group(3)


def test_corpus_is_large_enough() -> None:
    assert len(FILES) >= 25


def test_each_file_exercises_a_distinct_error() -> None:
    texts = [expectation(p)[2] for p in FILES]
    assert len(set(texts)) == len(texts)


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_bad_mission_gives_one_positioned_error(path: Path) -> None:
    line, column, text = expectation(path)
    errors = check_files([path], demo_resolver(), behaviours=DEMO_BEHAVIOURS)
    assert len(errors) == 1, "\n".join(map(str, errors))
    error = errors[0]
    assert isinstance(error, MissionError)
    message = str(error)
    assert "\n" not in message
    assert re.fullmatch(rf"{re.escape(str(path))}:\d+:\d+: \S.*", message), message
    assert (error.pos.line, error.pos.column) == (line, column), message
    assert text in error.message, message


def test_command_line_prints_one_line_per_file_and_no_traceback() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "bt_engine.trees", "--fake-actors", *map(str, FILES)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=Path(__file__).parent.parent,
    )
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == len(FILES), proc.stderr
    for path, line in zip(FILES, lines):
        assert line.startswith(f"{path}:"), line
