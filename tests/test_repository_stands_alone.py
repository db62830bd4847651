"""The repository is all a user has: its text points at nothing outside it, and every
link in its Markdown resolves to a file inside it."""

from __future__ import annotations

import os
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
TEXT_SUFFIXES = {".py", ".md", ".yaml", ".yml", ".toml", ".txt", ".cfg"}
#: not the project's text: environments, outputs, and the tools' caches (a second `make test`
#: would otherwise also check .pytest_cache/README.md)
SKIP_DIRS = {
    ".venv",
    ".git",
    "out",
    "build",
    ".actorbt",
    "__pycache__",
    "fixtures",
    "replays",
    ".pytest_cache",
    ".mypy_cache",
    ".ruff_cache",
}
#: what points outside the repository: the planning documents and the work tracker
OUTSIDE = re.compile(r"\.\./shared|DESIGN\.md|ROS_WHEELS\.md|STYLE\.md|the proposal|\bissue \d+\b|seed/", re.IGNORECASE)


def project_files():
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = sorted(d for d in dirs if d not in SKIP_DIRS and not d.endswith(".egg-info"))
        for name in sorted(files):
            path = pathlib.Path(folder, name)
            if path.suffix in TEXT_SUFFIXES or name == "Makefile":
                yield path


def test_no_file_points_outside_the_repository():
    this = pathlib.Path(__file__).resolve()
    found = [
        f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
        for path in project_files()
        if path.resolve() != this
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
        if OUTSIDE.search(line)
    ]
    assert found == []


@pytest.mark.parametrize(
    "doc", [p for p in project_files() if p.suffix == ".md"], ids=lambda p: str(p.relative_to(ROOT))
)
def test_markdown_links_resolve_inside_the_repository(doc):
    broken = []
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", doc.read_text()):
        if re.match(r"[a-z]+://", target):
            continue  # a web page, not a file of the project
        resolved = (doc.parent / target).resolve()
        if not resolved.exists() or ROOT.resolve() not in resolved.parents:
            broken.append(target)
    assert broken == []
