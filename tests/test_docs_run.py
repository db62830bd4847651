"""The README's and docs' examples run as written, in the simulator.

Every ```sh block that shows an `actorbt` command says what it claims, in an HTML comment
on the line before its fence (invisible where the Markdown is rendered):

- ``<!-- doc-test: run -->`` (or ``run, timeout 600``): the block runs, as it is, with
  bash in a scratch project, and must exit 0. Commands left running with ``&`` are
  stopped at its end.
- ``<!-- doc-test: skip: why -->``: it is not run here (a cluster, files of your own, an
  interactive shell); its commands are still parsed by tests/test_docs_commands.py.

Other blocks feed the ones that run: ``<!-- doc-test: write PATH -->`` writes the block
below it to PATH in the scratch project, ``<!-- doc-test: append PATH -->`` appends it
(a line for actorbt.yaml). A document's blocks run in their order, in one scratch
project per document: a copy of actorbt.yaml, the rest of the checkout linked. The files
are written before the commands run.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.doc_blocks import DOCS, ROOT, Block, blocks_of

DEFAULT_TIMEOUT = 300.0


def _timeout(block: Block) -> float:
    found = re.search(r"timeout\s+(\d+)", block.mark)
    return float(found.group(1)) if found else DEFAULT_TIMEOUT


def _shows_actorbt(block: Block) -> bool:
    return block.lang == "sh" and re.search(r"^\s*(\.venv/bin/)?actorbt\b", block.text, re.M) is not None


ALL = [b for doc in DOCS for b in blocks_of(doc)]
RUN_DOCS = sorted({b.doc for b in ALL if b.mark.startswith("run")})


def test_every_command_block_says_whether_it_runs():
    unmarked = [
        b.where for b in ALL if _shows_actorbt(b) and not (b.mark.startswith("run") or b.mark.startswith("skip:"))
    ]
    assert not unmarked, "add <!-- doc-test: run --> or <!-- doc-test: skip: why --> above: " + ", ".join(unmarked)


def test_the_marks_are_known():
    bad = [
        f"{b.where}: {b.mark!r}"
        for b in ALL
        if b.mark and not re.fullmatch(r"run(,\s*timeout\s+\d+)?|skip:\s*\S.*|(write|append)\s+\S+", b.mark)
    ]
    assert not bad, bad


def test_some_blocks_run():
    assert len([b for b in ALL if b.mark.startswith("run")]) >= 8


def _scratch_project(where: Path) -> Path:
    """A project folder like the checkout: actorbt.yaml copied (examples append to it),
    everything else linked, so what a command writes stays here."""
    where.mkdir()
    for entry in ROOT.iterdir():
        if entry.name in ("actorbt.yaml", "out", ".git", ".actorbt", "my_objects"):
            continue
        (where / entry.name).symlink_to(entry)
    shutil.copy(ROOT / "actorbt.yaml", where / "actorbt.yaml")
    return where


def _run(block: Block, project: Path, env: dict) -> None:
    # `set -e` as a user would expect the block to stop at its first failure; the trap
    # stops the commands started with `&` (a robot, a serve) when the block ends.
    script = "set -e\ntrap 'kill $(jobs -p) 2>/dev/null || true; wait' EXIT\n" + block.text
    shell = subprocess.Popen(
        ["bash", "-c", script],
        cwd=project,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = shell.communicate(timeout=_timeout(block))
    except subprocess.TimeoutExpired:
        os.killpg(shell.pid, signal.SIGKILL)  # the block and everything it started
        out, err = shell.communicate()
        pytest.fail(f"{block.where}: still running after {_timeout(block):.0f} s\n{_tail(out)}\n{_tail(err)}")
    if shell.returncode != 0:
        pytest.fail(f"{block.where}: exit {shell.returncode}\n{_tail(out)}\n{_tail(err)}")


def _tail(out: str | None, lines: int = 40) -> str:
    return "\n".join((out or "").splitlines()[-lines:])


@pytest.mark.timeout(1800)
@pytest.mark.parametrize("doc", RUN_DOCS, ids=[str(d.relative_to(ROOT)) for d in RUN_DOCS])
def test_the_documented_examples_run(doc, tmp_path):
    project = _scratch_project(tmp_path / "project")
    env = dict(
        os.environ,
        PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_DOMAIN_ID=str(150 + os.getpid() % 80),
        PYTHONUNBUFFERED="1",
    )
    blocks = blocks_of(doc)
    for block in blocks:  # the files first: a page may show a command before the script it runs
        verb, _, arg = block.mark.partition(" ")
        if verb in ("write", "append"):
            target = project / arg
            target.parent.mkdir(parents=True, exist_ok=True)
            with target.open("a" if verb == "append" else "w", encoding="utf-8") as f:
                f.write(block.text)
    for block in blocks:
        if block.mark.startswith("run"):
            _run(block, project, env)
