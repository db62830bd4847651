"""Every file a user writes (mission, world, configuration, recording) that is wrong gives
one located line on stderr and exit status 2, never a traceback."""

from __future__ import annotations

import json
import os
import pathlib
import re
import subprocess
import sys

import pytest

from bt_cli.main import main

REPO = pathlib.Path(__file__).resolve().parents[1]
HOUSE = (REPO / "sim" / "worlds" / "house.yaml").read_text()


@pytest.fixture
def project(tmp_path):
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text(
        "subsystems:\n  tutorial: actors.tutorial:Tutorial\ntrees: null\n"
        "simulator: sim:start_world\nplugins: [sim.cli, demo.cli]\n"
    )
    return tmp_path


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("actorbt: error: ")
    return lines[0][len("actorbt: error: ") :]


def a_world_with(project: pathlib.Path, old: str, new: str) -> pathlib.Path:
    assert old in HOUSE
    world = project / "my_world.yaml"
    world.write_text(HOUSE.replace(old, new, 1))
    return world


def run(project, *argv) -> int:
    return main(["--config", str(project / "actorbt.yaml"), *argv])


# -- worlds ------------------------------------------------------------------------------
def test_an_unknown_category_in_a_world(project, capsys):
    world = a_world_with(project, "category: can", "category: juice")
    line = next(i for i, text in enumerate(world.read_text().splitlines(), 1) if "juice" in text)
    assert run(project, "call", "greet", "--world", str(world)) == 2
    message = one_error_line(capsys)
    assert re.fullmatch(
        rf"{re.escape(str(world))}:{line}:\d+: objects\[\d\]: unknown category 'juice' "
        r"\(one of: bottle, can, carton, box; or others: every category not listed\)",
        message,
    ), message


def test_a_world_with_a_yaml_mistake(project, capsys):
    world = a_world_with(project, "\nwalls:\n", "\nwalls:\n - [0, 0, 1, 0]\n")
    assert run(project, "call", "greet", "--world", str(world)) == 2
    message = one_error_line(capsys)
    assert message.startswith(f"{world}:")
    assert "YAML syntax error" in message and "check the indentation" in message


def test_a_world_that_does_not_exist(project, capsys):
    assert run(project, "call", "greet", "--world", "hosue") == 2
    assert one_error_line(capsys) == "unknown world 'hosue' (known: house, house_hard, open_floor)"


def test_sim_commands_report_world_errors_the_same_way(project, capsys):
    world = a_world_with(project, "category: can", "category: juice")
    assert run(project, "sim", "snapshot", "--world", str(world), "--out", str(project / "x.png")) == 2
    assert "unknown category 'juice'" in one_error_line(capsys)


@pytest.mark.parametrize("command", [["demo"], ["eval", "bt_pick_place", "--seeds", "2", "--jobs", "2"]])
def test_demo_and_eval_check_the_world_before_any_episode(project, capsys, command):
    world = a_world_with(project, "category: can", "category: juice")
    assert run(project, *command, "--world", str(world), "--out", str(project / "out")) == 2
    assert "unknown category 'juice'" in one_error_line(capsys)
    assert not (project / "out").exists()


# -- missions ----------------------------------------------------------------------------
def test_a_mission_with_a_yaml_mistake(project, capsys):
    mission = project / "m.yaml"
    mission.write_text("name: m\nroot:\n  sequence:\n    - {do: greet}\n   - {do: greet}\n")
    assert run(project, "run", str(mission)) == 2
    message = one_error_line(capsys)
    assert message.startswith(f"{mission}:5:4: YAML syntax error")
    assert "check the indentation of this line against the line above" in message


def test_a_mission_with_an_unknown_actor(project, capsys):
    mission = project / "m.yaml"
    mission.write_text("name: m\nroot:\n  sequence:\n    - {do: gret}\n")
    assert run(project, "run", str(mission)) == 2
    assert one_error_line(capsys).startswith(f"{mission}:4:12: unknown actor 'gret' (did you mean 'greet'?)")


# -- the configuration -------------------------------------------------------------------
def test_a_configuration_with_a_yaml_mistake(project, capsys):
    (project / "actorbt.yaml").write_text("subsystems:\n  tutorial: actors.tutorial:Tutorial\n trees: null\n")
    assert run(project, "list") == 2
    message = one_error_line(capsys)
    assert message.startswith(f"{project / 'actorbt.yaml'}:3:2: YAML syntax error")
    assert "the keys of one mapping start in the same column" in message


def test_a_configuration_with_an_unknown_setting(project, capsys):
    (project / "actorbt.yaml").write_text("subsystem:\n  tutorial: actors.tutorial:Tutorial\n")
    assert run(project, "list") == 2
    assert "unknown settings ['subsystem']" in one_error_line(capsys)


# -- recordings --------------------------------------------------------------------------
@pytest.fixture
def recording(project):
    mission = project / "m.yaml"
    mission.write_text("name: m\nroot:\n  sequence:\n    - {do: greet}\n    - {do: sleep, with: [0.5]}\n")
    trace = project / "m.jsonl"
    assert run(project, "run", str(mission), "--record", str(trace), "--quiet") == 0
    return [json.loads(line) for line in trace.read_text().splitlines()]


def write_trace(path: pathlib.Path, records) -> str:
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return str(path)


@pytest.mark.parametrize("command", ["replay", "plot"])
@pytest.mark.parametrize(
    "damage, expected",
    [
        (lambda rs: rs.__setitem__(2, [1, 2]), r":3:1: expected a JSON object \(an event\), got list"),
        (lambda rs: rs[2].pop("run"), r":3:1: \w+ event: missing 'run'"),
        (lambda rs: rs[1].__setitem__("t", "soon"), r":2:1: \w+ event: 't' must be a number \(seconds\), got \"soon\""),
        (lambda rs: rs[0].__setitem__("start", [1]), r":1:1: header: 'start' must be a number"),
        (lambda rs: rs[0].__setitem__("trees", 3), r":1:1: header: 'trees' must be an object, got 3"),
    ],
)
def test_a_damaged_recording(project, recording, capsys, command, damage, expected):
    capsys.readouterr()
    damage(recording)
    trace = write_trace(project / "damaged.jsonl", recording)
    extra = ["--out", str(project / "p.png")] if command == "plot" else []
    assert run(project, command, trace, *extra) == 2
    message = one_error_line(capsys)
    assert re.fullmatch(re.escape(trace) + expected + ".*", message), message


def test_a_recording_that_is_not_json(project, capsys):
    trace = project / "t.jsonl"
    trace.write_text('{"type": "header"}\nnot json\n')
    assert run(project, "replay", str(trace)) == 2
    assert one_error_line(capsys) == f"{trace}:2:1: not JSON: Expecting value"


# -- as a user sees it: a process, no traceback, no banner -------------------------------
def test_a_user_file_error_is_one_line_from_the_command(project):
    world = a_world_with(project, "category: can", "category: juice")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "bt_cli.main",
            "--config",
            str(project / "actorbt.yaml"),
            "call",
            "greet",
            "--world",
            str(world),
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=project,
        timeout=120,
    )
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert "unknown category 'juice'" in done.stderr


def test_a_reader_that_stops_early_is_no_error(project):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "bt_cli.main", "--config", str(project / "actorbt.yaml"), "catalog", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        cwd=project,
    )
    proc.stdout.close()  # as `| head` does when it has read enough, here before any output
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0
    assert "Traceback" not in err and "BrokenPipe" not in err
