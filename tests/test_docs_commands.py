"""The commands the README and docs/*.md show work as written.

Every `actorbt ...` line of a ```sh block must parse: the command, its sub-command and its
options exist (`[...]` marks optional parts in the docs: they are left out). The quick
ones, which need no robot and no second shell, are run, and must succeed.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import pytest

from bt_cli.main import _config, build_parser
from tests.doc_blocks import DOCS, ROOT, blocks_of


def _command_lines() -> list[tuple[str, str]]:
    """(where, the command line) of every `actorbt` line in a ```sh block."""
    out = []
    for block in (b for doc in DOCS for b in blocks_of(doc) if b.lang == "sh"):
        lines = block.text.splitlines()
        i = 0
        while i < len(lines):
            line, number = lines[i], block.line + 1 + i
            while line.rstrip().endswith("\\") and i + 1 < len(lines):  # continued lines
                i += 1
                line = line.rstrip()[:-1] + " " + lines[i].strip()
            i += 1
            command = re.sub(r"^\.venv/bin/", "", line.strip())
            if command.startswith("actorbt ") or command == "actorbt":
                out.append((f"{block.doc.relative_to(ROOT)}:{number}", command))
    return out


def _argv(command: str) -> list[str]:
    """The arguments of a documented command: comments, '&', pipes and the optional
    `[...]` parts left out."""
    words = shlex.split(command.split(" | ")[0], comments=True)[1:]
    argv, depth = [], 0
    for word in words:
        if word == "&":
            continue
        opens, closes = word.startswith("["), word.endswith("]")
        if depth or opens:
            depth += opens - closes if not (opens and closes) else 0
            if opens and not closes:
                depth = max(depth, 1)
            continue
        argv.append(word)
    return argv


LINES = _command_lines()


def test_the_docs_show_commands():
    assert len(LINES) > 40


@pytest.mark.parametrize("where, command", LINES, ids=[w for w, _ in LINES])
def test_every_documented_command_parses(where, command, monkeypatch):
    monkeypatch.chdir(ROOT)
    argv = _argv(command)
    cfg = _config(argv)
    parser = build_parser(cfg.plugins if cfg is not None else [])
    try:
        parser.parse_args(argv)
    except SystemExit as e:
        pytest.fail(f"{where}: `{command}` does not parse (exit {e.code})")


#: documented commands that need no robot, no second shell and finish in seconds
QUICK = ("actorbt list", "actorbt check", "actorbt catalog --json", "actorbt category list")


@pytest.mark.parametrize("command", QUICK)
def test_the_quick_documented_commands_run_as_written(command):
    assert any(c.startswith(command) for _, c in LINES), f"{command!r} is no longer documented"
    run = subprocess.run(
        [sys.executable, "-m", "bt_cli.main", *shlex.split(command)[1:]],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
