"""`actorbt --help` and every command's: one name per thing, each flag explained in a
full sentence."""

from __future__ import annotations

import argparse
import pathlib

import pytest

from bt_cli.config import load_config
from bt_cli.main import build_parser, main

REPO = pathlib.Path(__file__).resolve().parents[1]


def commands(parser: argparse.ArgumentParser, prefix: str = "actorbt"):
    """(name, parser) of every command and sub-command."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield f"{prefix} {name}", sub
                yield from commands(sub, f"{prefix} {name}")


@pytest.fixture(scope="module")
def parser():
    return build_parser(load_config(REPO / "actorbt.yaml").plugins)


def test_every_flag_is_explained_in_a_full_sentence(parser):
    bad = []
    for name, sub in [("actorbt", parser), *commands(parser)]:
        for action in sub._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            text = action.help
            if text == argparse.SUPPRESS:
                continue
            flag = "/".join(action.option_strings) or action.dest
            if not text or not text[0].isupper() or not text.rstrip().endswith((".", ")")):
                bad.append(f"{name} {flag}: {text!r}")
    assert bad == []


def test_every_command_has_a_description(parser):
    missing = [
        name for name, sub in commands(parser) if not sub.description or not sub.description.rstrip().endswith(".")
    ]
    assert missing == []


def test_one_name_per_thing(parser):
    names = [name for name, _ in commands(parser)]
    assert "actorbt rcall" in names  # calling an actor of a running serve has one name
    call = dict(commands(parser))["actorbt call"]
    shown = {s for a in call._actions if a.help != argparse.SUPPRESS for s in a.option_strings}
    assert "--ros" not in shown and "--bus" in shown


@pytest.mark.parametrize("argv", [["call", "--ros", "greet"], ["serve", "--ros"]])
def test_the_old_ros_flag_says_what_replaced_it(argv, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--config", str(REPO / "actorbt.yaml"), *argv])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "--ros is gone: use --bus ros" in err and "actorbt rcall" in err


def test_the_bus_flag_picks_the_transport(tmp_path):
    from bt_cli.app import App

    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("transport: local\n")
    app = App(argparse.Namespace(bus="ros"), load_config(cfg))
    assert app._transport() is not None  # the ROS transport's factory
    app = App(argparse.Namespace(bus=None), load_config(cfg))
    assert app._transport() is None  # the local bus
