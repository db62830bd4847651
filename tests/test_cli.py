"""The actorbt command and its shell."""
from __future__ import annotations

import io
import json
import pathlib

import pytest

from bt_engine import Runtime
from bt_engine.cli.main import main
from bt_engine.cli.shell import ActorShell
from bt_engine.literals import parse_args

REPO = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture
def config(tmp_path):
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems:\n  tutorial: actors.tutorial:Tutorial\ntrees: null\n")
    return str(cfg)


def test_values_are_literals_never_code():
    args, kwargs = parse_args(["1", "2.5", "[1, 2]", "hello", "name='x'", "__import__('os')"])
    assert args == [1, 2.5, [1, 2], "hello", "__import__('os')"]
    assert kwargs == {"name": "x"}


def test_call_prints_the_result(config, capsys):
    assert main(["--config", config, "call", "greet", "ada"]) == 0
    assert capsys.readouterr().out.strip() == "'hello, ada'"


def test_call_json_and_keywords(config, capsys):
    assert main(["--config", config, "call", "greet", "name=bob", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == "hello, bob"


def test_unknown_actor_exits_nonzero_with_suggestion(config, capsys):
    assert main(["--config", config, "call", "gret"]) == 2
    assert "did you mean: greet" in capsys.readouterr().err


def test_list_and_catalog(config, capsys):
    assert main(["--config", config, "list"]) == 0
    out = capsys.readouterr().out
    assert "tutorial.greet(name: str = 'world') -> str  [sync]" in out
    assert main(["--config", config, "catalog", "--json"]) == 0
    tools = json.loads(capsys.readouterr().out)
    assert {t["name"] for t in tools} >= {"sleep", "tutorial.greet", "tutorial.count"}


def test_bad_config_is_a_clear_error(tmp_path, capsys):
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems:\n  x: actors.nothing_here:Nope\n")
    assert main(["--config", str(cfg), "list"]) == 2
    assert "cannot import subsystem 'x'" in capsys.readouterr().err


def test_shell_runs_actors_and_survives_bad_input():
    from actors.tutorial import Tutorial
    with Runtime() as rt:
        rt.add_subsystem("tutorial", Tutorial)
        out = io.StringIO()
        script = io.StringIO("greet amy\nnope 1\ngreet 1 2 3\nhelp greet\ncount 2 0.5\n"
                             "'unterminated\nlist gre\nquit\n")
        ActorShell(rt, stdin=script, stdout=out).cmdloop()
    text = out.getvalue()
    assert "'hello, amy'" in text
    assert "error: unknown actor 'nope'" in text
    assert "error: bad arguments for actor tutorial.greet" in text
    assert "Return a greeting" in text
    assert "error: cannot split" in text
    assert "tutorial.greet(name: str = 'world')" in text


def test_shell_completes_actor_names():
    from actors.tutorial import Tutorial
    with Runtime() as rt:
        rt.add_subsystem("tutorial", Tutorial)
        sh = ActorShell(rt, stdin=io.StringIO(""), stdout=io.StringIO())
        assert sh.completenames("gr") == ["greet"]
        assert "tutorial.greet" in sh.completenames("tutorial.g")
