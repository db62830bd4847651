"""Seeded fuzz of the mission loader: every mutation of ``trees/*.yaml`` loads as a valid
mission or fails with one located one-line MissionError. Nothing else may escape.

The mutations are the crash classes an external fuzz found (control characters, bad
UTF-8, huge integers, deep nesting, deep ``check:`` expressions) and their neighbours
(truncation, line shuffles, indentation, aliases, tags, BOMs, odd scalars and keys).
A failure lists the first few mutants with how to rebuild them: ``mutant(TREES[i], index)``.
"""

from __future__ import annotations

import os
import random
import re
from pathlib import Path
from typing import Callable

import pytest

from bt_engine.trees import MissionError, TreeLibrary, check_files, read_mission
from bt_engine.trees.testing import DEMO_BEHAVIOURS, demo_resolver

REPO = Path(__file__).resolve().parents[1]
TREES = sorted((REPO / "trees").glob("*.yaml"))
SOURCES = {path: path.read_bytes() for path in TREES}
SEED = 20240611
# 2,800 mutants, about 15 s on one core; ACTORBT_FUZZ_PER_FILE=1500 gives 10,500
MUTANTS_PER_FILE = int(os.environ.get("ACTORBT_FUZZ_PER_FILE", "400"))

Mutator = Callable[[random.Random, bytes], bytes]

# ---------------------------------------------------------------- mutations

_CONTROL = [bytes([c]) for c in (*range(0x00, 0x09), 0x0B, 0x0C, 0x1B, 0x7F)] + [
    "\x85".encode(),
    "\u2028".encode(),
    "\ufeff".encode(),
    "\ufffe".encode(),
    "\uffff".encode(),
    b"\xed\xa0\x80",  # an encoded surrogate: not UTF-8
    b"\xc3",
    b"\xff",
    b"\xfe\xff",
    b"\r",
    b"\t",
    b"\t\t",
]
_DEPTHS = (10, 63, 64, 65, 99, 100, 101, 300, 1000, 3000, 5000)
_NUMBERS = (
    "9" * 101,
    "9" * 4300,
    "9" * 4301,
    "-" + "9" * 5000,
    "0x" + "f" * 5000,
    "0b" + "1" * 20000,
    "0o" + "7" * 5000,
    "0" + "7" * 5000,
    "1_" * 3000 + "1",
    ":".join(["59"] * 2000),
    "1" * 5000 + ".5",
    "1e99999",
    ".nan",
    "-.inf",
    "2001-02-30",
    "0000-01-01",
    "2001-01-01 00:00:00 +99:99",
    "2001-1-1T1:1:1.5Z",
)
_EXPRESSIONS = (
    lambda n: "(" * n + "1" + ")" * n + " > 0",
    lambda n: "(" * n,
    lambda n: "not " * n + "flag",
    lambda n: "-" * n + "1 > 0",
    lambda n: "[" * n,
    lambda n: "[" * n + "]" * n + " == []",
    lambda n: "a or " * n + "a",
    lambda n: "a and " * n + "b or " * n + "c",
    lambda n: "x." * n + "y > 1",
    lambda n: "9" * (n * 2) + " > 1",
    lambda n: "1." + "9" * (n * 2) + " > 1",
    lambda n: "'" + "x" * n + "' == name",
    lambda n: "1__0 > 1",
    lambda n: "1_ > 0",
    lambda n: "1_.5 > 0",
    lambda n: "1e" + "9" * n + " > 0",
    lambda n: "a in [" + "1, " * n + "]",
)
_SNIPPETS = (
    "a: &a [1, 2]\nb: *a",
    "lol0: &l0 [x, x, x, x, x, x, x, x, x, x]\n"
    + "".join(f"lol{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 10)}]\n" for i in range(1, 9))
    + "root: {set: {bomb: *l8}}",
    "x: &r [*r]",
    "x: *undefined",
    "x: !!python/object/apply:os.system [echo]",
    "x: !!set {a}",
    "x: !foo bar",
    "<<: {a: 1}",
    "? [a, b]\n: c",
    "1: x",
    "null: x",
    "~: y",
    "? {a: 1}\n: b",
    "x: !!binary '###'",
    "x: =",
    "x: !!timestamp today",
    "%YAML 1.1\n---",
    "---",
    "...",
    "--- !!map\n",
    "x: |\n  block\n    text",
    "x: 'unterminated",
    'x: "\\xZZ"',
    'x: "\\ud800"',
    'x: "\\U0010FFFF"',
    'x: "\\x00"',
    "x: " + "y" * 20000,
    "inputs: {class: int}",
    "inputs: {None: {type: str, default: x}}",
    "x: {{y}}",
    "x: [",
    "x: {",
    "\t- a",
    "x: 07:30",
    "x: 1:2:3:4",
    "x: !!int 1e3",
    "x: !!float abc",
    "x: !!str [a]",
)
_WORDS = (
    "sequence",
    "selector",
    "parallel",
    "retry",
    "repeat",
    "timeout",
    "invert",
    "do",
    "set",
    "check",
    "wait",
    "behaviour",
    "with",
    "out",
    "name",
    "root",
    "inputs",
    "outputs",
    "doc",
    "type",
    "default",
    "child",
    "children",
    "policy",
    "selected",
    "times",
    "seconds",
    "forever",
    "success_on_selected",
    "class",
    "def",
    "None",
    "True",
    "__class__",
    "_private",
    "yes",
    "no",
    "on",
    "~",
    "null",
    "'{x}'",
    '"{x}"',
    "{x}",
    "{{",
    "}}",
    "-1",
    "0",
    ".nan",
    "[]",
    "{}",
    "''",
    "int",
    "any",
    "dict",
    "bt_search",
    "bt_catch",
    "reset",
)


def _line_bounds(data: bytes, rng: random.Random) -> tuple[int, int]:
    """Start and end (after the newline) of a random line."""
    starts = [0] + [i + 1 for i, b in enumerate(data) if b == 0x0A and i + 1 < len(data)]
    start = rng.choice(starts)
    end = data.find(b"\n", start)
    return start, len(data) if end < 0 else end + 1


def flip_byte(rng: random.Random, data: bytes) -> bytes:
    i = rng.randrange(len(data)) if data else 0
    return data[:i] + bytes([rng.randrange(256)]) + data[i + 1 :]


def insert_control(rng: random.Random, data: bytes) -> bytes:
    i = rng.randrange(len(data) + 1)
    return data[:i] + rng.choice(_CONTROL) + data[i:]


def truncate(rng: random.Random, data: bytes) -> bytes:
    return data[: rng.randrange(len(data) + 1)]


def duplicate_line(rng: random.Random, data: bytes) -> bytes:
    start, end = _line_bounds(data, rng)
    return data[:end] + data[start:end] + data[end:]


def delete_line(rng: random.Random, data: bytes) -> bytes:
    start, end = _line_bounds(data, rng)
    return data[:start] + data[end:]


def swap_lines(rng: random.Random, data: bytes) -> bytes:
    lines = data.split(b"\n")
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    lines[i], lines[j] = lines[j], lines[i]
    return b"\n".join(lines)


def reindent(rng: random.Random, data: bytes) -> bytes:
    start, end = _line_bounds(data, rng)
    line = data[start:end]
    if rng.random() < 0.5:
        line = rng.choice((b" ", b"  ", b"    ", b"\t", b" \t")) + line
    else:
        line = line[rng.randint(1, 4) :] if line.startswith(b" ") else line
    return data[:start] + line + data[end:]


def _replace_value(rng: random.Random, data: bytes, value: str) -> bytes:
    """Put ``value`` after the first ': ' of a random line, or after ``root: `` if none."""
    start, end = _line_bounds(data, rng)
    colon = data.find(b": ", start, end)
    if colon < 0:
        colon = data.find(b"root: ") + 4
        end = len(data)
    return data[: colon + 2] + value.encode() + b"\n" + data[end:]


def _replace_node(rng: random.Random, data: bytes, value: str) -> bytes:
    """Put the node ``value`` in place of a random one-line ``- {...}`` list item."""
    items = [m.span(1) for m in re.finditer(rb"(?m)^ *- (\{.*\}) *$", data)]
    if not items:
        return _replace_value(rng, data, value)
    start, end = rng.choice(items)
    return data[:start] + value.encode() + data[end:]


def deep_nesting(rng: random.Random, data: bytes) -> bytes:
    n = rng.choice(_DEPTHS)
    shape = rng.randrange(4)
    if shape == 0:
        value = "[" * n + "]" * n
    elif shape == 1:
        value = "{a: " * n + "1" + "}" * n
    elif shape == 2:
        value = "{invert: " * n + "{wait: 0}" + "}" * n
    else:  # block style: one indented mapping per line
        value = "\n" + "".join(" " * (2 * k + 2) + "invert:\n" for k in range(n)) + " " * (2 * n + 2) + "wait: 0"
        return _replace_value(rng, data, value)
    return _replace_node(rng, data, value)


def huge_number(rng: random.Random, data: bytes) -> bytes:
    number = rng.choice(_NUMBERS)
    found = [m.span() for m in re.finditer(rb"(?<![\w.])\d+(\.\d+)?(?![\w.])", data)]
    if not found:
        return _replace_value(rng, data, number)
    start, end = rng.choice(found)
    return data[:start] + number.encode() + data[end:]


def deep_check(rng: random.Random, data: bytes) -> bytes:
    expr = rng.choice(_EXPRESSIONS)(rng.choice(_DEPTHS))
    return _replace_node(rng, data, '{check: "' + expr + '"}')


def yaml_snippet(rng: random.Random, data: bytes) -> bytes:
    start, _ = _line_bounds(data, rng)
    return data[:start] + rng.choice(_SNIPPETS).encode() + b"\n" + data[start:]


def replace_word(rng: random.Random, data: bytes) -> bytes:
    words = [m.span() for m in re.finditer(rb"[A-Za-z_]+", data)]
    if not words:
        return data
    start, end = rng.choice(words)
    return data[:start] + rng.choice(_WORDS).encode() + data[end:]


def splice(rng: random.Random, data: bytes) -> bytes:
    other = SOURCES[TREES[rng.randrange(len(TREES))]] if rng.random() < 0.3 else data
    a = rng.randrange(len(other) + 1)
    chunk = other[a : a + rng.randint(1, 80)]
    i = rng.randrange(len(data) + 1)
    return data[:i] + chunk + data[i:]


def whole_file(rng: random.Random, data: bytes) -> bytes:
    """Encodings, BOMs, emptiness and size."""
    choice = rng.randrange(7)
    if choice == 0:
        return b"\xef\xbb\xbf" + data
    if choice == 1:
        return data.decode("utf-8", "replace").encode("utf-16")
    if choice == 2:
        return rng.choice((b"", b"\n", b"# only a comment\n", b"---\n", b"...\n", b"~\n", b"[]\n", b"\xef\xbb\xbf"))
    if choice == 3:
        return data * rng.randint(2, 4)
    if choice == 4:
        return data.replace(b"\n", rng.choice((b"\r\n", b"\r", "\u2028".encode())))
    if choice == 5:
        return data + b"#" * (1_100_000)  # larger than any mission should be
    return data.replace(b"  ", b"\t")


MUTATORS: tuple[Mutator, ...] = (
    flip_byte,
    flip_byte,
    insert_control,
    insert_control,
    truncate,
    duplicate_line,
    delete_line,
    swap_lines,
    reindent,
    reindent,
    deep_nesting,
    huge_number,
    deep_check,
    deep_check,
    yaml_snippet,
    yaml_snippet,
    replace_word,
    replace_word,
    splice,
    whole_file,
)


def mutant(path: Path, index: int) -> bytes:
    """The ``index``-th mutant of ``path``: 1 to 3 mutations, reproducible from the seed."""
    rng = random.Random(f"{SEED}:{path.name}:{index}")
    data = SOURCES[path]
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        data = rng.choice(MUTATORS)(rng, data)
    return data


# ---------------------------------------------------------------- loading


def _located(error: BaseException, path: Path, data: bytes) -> str | None:
    """Why ``error`` is not a one-line located MissionError for ``path``, or None."""
    if not isinstance(error, MissionError):
        return f"{type(error).__name__}: {error}"
    text = str(error)
    if len(text.splitlines()) != 1:
        return f"not one line: {text[:200]!r}"
    match = re.match(rf"{re.escape(str(path))}:(\d+):(\d+): \S", text)
    if match is None:
        return f"not 'file:line:col: message': {text[:200]!r}"
    lines = len(data.decode("utf-8", "replace").splitlines()) + 1
    if not (1 <= int(match.group(1)) <= lines and int(match.group(2)) >= 1):
        return f"position outside the file ({lines} lines): {text[:200]!r}"
    return None


def load(path: Path, data: bytes, library: TreeLibrary) -> tuple[bool, str | None]:
    """Load ``data`` as the mission file ``path`` with ``library``: whether it is a valid
    mission, and what went wrong if the outcome is not that or located one-line errors."""
    path.write_bytes(data)
    try:
        errors = check_files([path], library=library)
        for error in errors:
            problem = _located(error, path, data)
            if problem is not None:
                return False, problem
        if not errors:
            for mission in library:  # what registering the trees as actors does
                mission.signature()
    except Exception as exc:  # noqa: BLE001 - anything escaping is what this test looks for
        return False, _located(exc, path, data)
    return not errors, None


def libraries() -> list[Callable[[Path], TreeLibrary]]:
    """Two ways to load a mutant of a tree: against the fake actor catalogue, and
    structure-only next to the other repository trees (so ``do:`` calls between trees
    are followed)."""
    missions = {p: read_mission(p) for p in TREES}

    def with_other_trees(source: Path) -> TreeLibrary:
        library = TreeLibrary()
        for path, mission in missions.items():
            if path != source:
                library.add(mission)
        return library

    return [lambda source: TreeLibrary(demo_resolver(), DEMO_BEHAVIOURS), with_other_trees]


def run_fuzz(folder: Path, per_file: int = MUTANTS_PER_FILE) -> tuple[int, int, list[str]]:
    """Load ``per_file`` mutants of every tree: how many, how many were valid missions,
    and the problems found."""
    makers = libraries()
    problems: list[str] = []
    count = valid = 0
    for source in TREES:
        path = folder / source.name
        for index in range(per_file):
            ok, problem = load(path, mutant(source, index), makers[index % 2](source))
            count += 1
            valid += ok
            if problem is not None:
                problems.append(f"mutant(TREES[{TREES.index(source)}], {index}): {problem[:300]}")
    return count, valid, problems


def test_every_mutant_loads_or_fails_with_one_located_line(tmp_path: Path) -> None:
    count, valid, problems = run_fuzz(tmp_path)
    assert count >= 2800
    assert valid >= count // 25, "too few mutants get past the parser to the validator"
    assert not problems, f"{len(problems)} of {count} mutants escaped:\n" + "\n".join(problems[:10])


def test_the_unmutated_trees_load(tmp_path: Path) -> None:
    makers = libraries()
    for source in TREES:
        assert load(tmp_path / source.name, source.read_bytes(), makers[1](source)) == (True, None)


# ---------------------------------------------------------------- the command line

NASTY = {
    "control.yaml": b"name: a\nroot: {wait: 1}\n# \x7f\n",
    "nul.yaml": b"name: a\x00\nroot: {wait: 1}\n",
    "latin1.yaml": b"name: caf\xe9\nroot: {wait: 1}\n",
    "utf16.yaml": "name: a\nroot: {wait: 1}\n".encode("utf-16"),
    "huge_int.yaml": b"name: a\nroot: {wait: " + b"9" * 5000 + b"}\n",
    "huge_int_check.yaml": b"name: a\nroot: {check: " + b"9" * 5000 + b" > 1}\n",
    "deep_parens.yaml": b"name: a\nroot: {check: '" + b"(" * 5000 + b"1" + b")" * 5000 + b" > 0'}\n",
    "deep_not.yaml": b"name: a\nroot: {check: '" + b"not " * 5000 + b"true'}\n",
    "deep_minus.yaml": b"name: a\nroot: {check: '" + b"-" * 5000 + b"1 > 0'}\n",
    "deep_list.yaml": b"name: a\nroot: {check: '" + b"[" * 5000 + b"'}\n",
    "long_or.yaml": b"name: a\nroot: {check: '" + b"true or " * 5000 + b"true'}\n",
    "deep_yaml.yaml": b"name: a\nroot: " + b"[" * 5000 + b"]" * 5000 + b"\n",
    "laughs.yaml": _SNIPPETS[1].encode(),
    "python_tag.yaml": b"name: a\nroot: {do: x, with: [!!python/object/apply:os.system [echo]]}\n",
    "bad_date.yaml": b"name: a\nroot: {set: {day: 2001-02-30}}\n",
    "keyword_input.yaml": b"name: a\ninputs: {class: int}\nroot: {wait: 1}\n",
    "huge.yaml": b"name: a\nroot: {wait: 1}\n" + b"#" * 2_000_000 + b"\n",
}


@pytest.fixture
def nasty(tmp_path: Path) -> tuple[str, list[str]]:
    """A config with an empty trees folder, and the nastiest files (plus a directory)."""
    (tmp_path / "trees").mkdir()
    config = tmp_path / "actorbt.yaml"
    config.write_text("subsystems: {}\ntrees: trees\n")
    files = []
    for name, data in NASTY.items():
        (tmp_path / name).write_bytes(data)
        files.append(str(tmp_path / name))
    (tmp_path / "folder.yaml").mkdir()
    files.append(str(tmp_path / "folder.yaml"))
    return str(config), files


def test_actorbt_check_prints_one_line_per_nasty_file(nasty: tuple[str, list[str]], capsys) -> None:
    from bt_cli.main import main

    config, files = nasty
    # check reports mission errors itself (exit status 1), one line each
    assert main(["--config", config, "check", *files]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == len(files), err
    for line, path in zip(lines, sorted(files)):  # errors come sorted by file
        assert re.match(rf"{re.escape(path)}:\d+:\d+: \S", line), line


@pytest.mark.parametrize(
    "name",
    [
        "control.yaml",
        "huge_int.yaml",
        "deep_parens.yaml",
        "deep_yaml.yaml",
        "laughs.yaml",
        "bad_date.yaml",
        "keyword_input.yaml",
    ],
)
def test_actorbt_show_fails_with_one_line_and_status_2(nasty: tuple[str, list[str]], name: str, capsys) -> None:
    from bt_cli.main import main

    config, files = nasty
    path = next(f for f in files if f.endswith(name))
    assert main(["--config", config, "show", path]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"actorbt: error: {path}:"), err
