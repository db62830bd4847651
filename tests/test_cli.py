"""The actorbt command and its shell."""

from __future__ import annotations

import argparse
import io
import json
import pathlib

import pytest

from bt_engine import Runtime
from bt_cli.config import ConfigError, load_config
from bt_cli.main import main
from bt_cli.shell import ActorShell
from bt_engine.literals import parse_args
from bt_ros.live_options import LiveOptions

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


@pytest.mark.parametrize(
    "section, says",
    [
        ("robot: {body: {size: [0.3, 0.3]}}", "body: expected {size: [x, y, z] in metres"),
        ("robot: {topics: [{name: camera, type: sensor_msgs/msg/Image}]}", "topics: expected {name: /topic"),
        ("robot: {topics: [{name: /cam, type: sensor_msgs/msg/Image, qos: fast}]}", "unknown QoS 'fast'"),
        (
            "robot: {topics: [{name: /info, type: sensor_msgs/msg/CameraInfo, compress: true}]}",
            "only for a sensor_msgs/msg/Image",
        ),
        ("robot: {wheels: 2}", "expected a mapping with body and topics"),
    ],
)
def test_a_bad_robot_section_is_a_clear_error(tmp_path, section, says):
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text(section + "\n")
    with pytest.raises(ConfigError) as e:
        load_config(cfg)
    assert says in str(e.value) and "for example robot: {body:" in str(e.value)


def test_the_robot_section_reaches_the_live_options(tmp_path):
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text(
        "robot:\n  body: {size: [0.2, 0.1, 0.3]}\n"
        "  topics: [{name: /cam, type: sensor_msgs/msg/Image, qos: sensor, compress: true}]\n"
    )
    options = LiveOptions.of(argparse.Namespace(bag="b"), load_config(cfg).robot)
    assert options.body == (0.2, 0.1, 0.3, 0.0)
    assert options.topics == (("/cam", "sensor_msgs/msg/Image", "sensor", True),)
    assert LiveOptions.of(argparse.Namespace()).body is None  # no section: nothing drawn


def test_shell_runs_actors_and_survives_bad_input():
    from actors.tutorial import Tutorial

    with Runtime() as rt:
        rt.add_subsystem("tutorial", Tutorial)
        out = io.StringIO()
        script = io.StringIO("greet amy\nnope 1\ngreet 1 2 3\nhelp greet\ncount 2 0.5\n'unterminated\nlist gre\nquit\n")
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


# -- call --stream and the shell's `stream` (issue [cli-dx] item 3) -------------------------


def test_call_stream_prints_every_value(config, capsys):
    assert main(["--config", config, "call", "tutorial.count", "3", "--stream"]) == 0
    assert capsys.readouterr().out == "0\n1\n2\n"


def test_call_stream_count_stops_early(config, capsys):
    assert main(["--config", config, "call", "tutorial.count", "100", "--stream", "--count", "2"]) == 0
    assert capsys.readouterr().out == "0\n1\n"


def test_call_stream_json(config, capsys):
    assert main(["--config", config, "call", "tutorial.count", "2", "--stream", "--json"]) == 0
    assert [json.loads(line) for line in capsys.readouterr().out.splitlines()] == [0, 1]
    # a sync actor is invoked again for every value (the iterator mode)
    assert main(["--config", config, "call", "greet", "ada", "--stream", "--json", "--count", "2"]) == 0
    assert capsys.readouterr().out.splitlines() == ['"hello, ada"', '"hello, ada"']


def test_call_stream_emit_style_and_timeout(config, capsys):
    assert main(["--config", config, "call", "tutorial.countdown", "3", "period=0.5", "--stream"]) == 0
    assert capsys.readouterr().out == "3\n2\n1\n"
    # --timeout: S seconds of runtime-clock time (values at 0, 1, 2 s; the 3rd sleep ends at 3 s)
    assert main(["--config", config, "call", "tutorial.count", "100", "--stream", "--timeout", "2.5"]) == 0
    assert capsys.readouterr().out == "0\n1\n2\n"


def test_call_stream_options_are_checked(config, capsys):
    assert main(["--config", config, "call", "tutorial.count", "3", "--count", "2"]) == 2
    assert "--count needs --stream" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--config", config, "call", "tutorial.count", "--stream", "--count", "0"])
    assert "expected a positive count" in capsys.readouterr().err
    assert main(["--config", config, "call", "tutorial.count", "x", "--stream"]) == 2
    assert "actorbt: error:" in capsys.readouterr().err


def test_call_help_says_what_stream_does_to_other_actors(capsys):
    with pytest.raises(SystemExit):
        main(["call", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--stream" in text and "called again for every value" in text


def test_ctrl_c_ends_a_stream_cleanly():
    from bt_cli.shell import INTERRUPTED, print_stream, stream_actor

    def values():
        yield 1
        yield 2
        raise KeyboardInterrupt

    out = io.StringIO()
    assert print_stream(values(), out) == INTERRUPTED == 130
    assert out.getvalue() == "1\n2\n"

    closed = []

    class FakeRuntime:
        def stream(self, name, *args, timeout=None, **kwargs):
            import contextlib

            @contextlib.contextmanager
            def cm():
                try:
                    yield values()
                finally:
                    closed.append((name, args, kwargs, timeout))

            return cm()

    out = io.StringIO()
    assert stream_actor(FakeRuntime(), "x", [1], {"k": 2}, out, as_json=True, timeout=4.0) == 130
    assert out.getvalue() == "1\n2\n"
    assert closed == [("x", (1,), {"k": 2}, 4.0)]  # the source was closed


def test_ctrl_c_on_a_real_stream_exits_130(config):
    import signal
    import subprocess
    import sys

    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bt_cli.main",
            "--config",
            config,
            "call",
            "tutorial.count",
            "1000",
            "0.05",
            "--stream",
            "--clock",
            "wall",
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline() == "0\n"
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130
    assert "Traceback" not in err and "actorbt: interrupted" in err
    assert len(out.splitlines()) < 999


def test_shell_stream_command(capsys):
    from actors.tutorial import Tutorial

    with Runtime() as rt:
        rt.add_subsystem("tutorial", Tutorial)
        sh = ActorShell(rt)
        sh.onecmd("stream tutorial.count 3")
        assert capsys.readouterr().out == "0\n1\n2\n"
        sh.onecmd("stream count 100 --count 2")
        assert capsys.readouterr().out == "0\n1\n"
        sh.onecmd("stream countdown start=2 period=0.5 --json")
        assert capsys.readouterr().out == "2\n1\n"
        sh.onecmd("stream count 100 --timeout=1.5")
        assert capsys.readouterr().out == "0\n1\n"
        sh.onecmd("stream greet amy --count 2")
        assert capsys.readouterr().out == "'hello, amy'\n'hello, amy'\n"
        sh.onecmd("stream nope")
        assert "error: unknown actor 'nope'" in capsys.readouterr().out
        sh.onecmd("stream count --count")
        assert "error: --count needs a value" in capsys.readouterr().out
        sh.onecmd("stream")
        assert capsys.readouterr().out.startswith("usage: stream NAME")
        sh.onecmd("help stream")
        assert "print every value of actor NAME" in capsys.readouterr().out
        sh.onecmd("help")
        assert "stream NAME" in capsys.readouterr().out


def test_shell_completes_the_stream_command():
    from actors.tutorial import Tutorial

    with Runtime() as rt:
        rt.add_subsystem("tutorial", Tutorial)
        sh = ActorShell(rt, stdin=io.StringIO(""), stdout=io.StringIO())
        assert "stream" in sh.completenames("str")
        assert sh.complete_stream("cou", "stream cou", 7, 10) == ["count", "countdown"]
        assert sh.complete_stream("--c", "stream count 3 --c", 15, 18) == ["--count"]
        assert sh.complete_stream("", "stream count ", 13, 13) == []
        assert "stream" in sh.complete_help("st")


@pytest.fixture
def project_with_a_broken_tree(tmp_path):
    """A project whose trees folder holds one good and one broken mission."""
    trees = tmp_path / "trees"
    trees.mkdir()
    (trees / "hello.yaml").write_text(
        "name: hello\noutputs: [g]\nroot: {do: tutorial.greet, with: {name: ada}, out: g}\n"
    )
    (trees / "x.yaml").write_text("name: x\nroot:\n  sequence:\n    - do: nope\n")
    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems: {tutorial: actors.tutorial:Tutorial}\nworld: null\n")
    return cfg


def test_a_broken_tree_does_not_block_other_commands(project_with_a_broken_tree, capsys):
    cfg = str(project_with_a_broken_tree)
    assert main(["--config", cfg, "call", "tutorial.greet", "ada", "--world", "none"]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == "'hello, ada'"
    warnings = captured.err.strip().splitlines()
    assert len(warnings) == 1
    assert warnings[0].startswith("actorbt: warning: skipped ")
    assert warnings[0].endswith("x.yaml:4:11: unknown actor 'nope', expected a registered actor or tree name")
    assert main(["--config", cfg, "run", "hello", "--quiet"]) == 0
    assert "hello, ada" in capsys.readouterr().out
    assert main(["--config", cfg, "list"]) == 0
    captured = capsys.readouterr()
    assert "hello() -> dict  [tree]" in captured.out and "\nx" not in captured.out
    assert "actorbt: warning: skipped" in captured.err


def test_the_broken_tree_itself_fails_with_its_located_error(project_with_a_broken_tree, capsys):
    cfg = str(project_with_a_broken_tree)
    for command in (["run", "x"], ["call", "x"]):
        assert main(["--config", cfg, *command]) == 2
        err = capsys.readouterr().err
        assert "actorbt: error:" in err and "tree 'x' was skipped: " in err
        assert "x.yaml:4:11: unknown actor 'nope'" in err.split("actorbt: error:")[1]


def test_check_still_fails_on_any_broken_file(project_with_a_broken_tree, capsys):
    assert main(["--config", str(project_with_a_broken_tree), "check"]) == 1
    assert "x.yaml:4:11: unknown actor 'nope'" in capsys.readouterr().err


def test_demo_and_eval_build_their_runtime_from_actorbt_yaml(project_with_a_broken_tree, capsys):
    from bt_cli.config import load_config
    from demo.episode import episode_app

    cfg = load_config(project_with_a_broken_tree)
    app = episode_app("open_floor", 3, config=cfg)
    assert app.cfg is cfg and app.world_spec() == {"name": "open_floor", "seed": 3}
    assert app.for_world("house", 1).world_spec() == {"name": "house", "seed": 1}
    assert app.for_world("none", 1).world_spec() is None
    rt = app.runtime(with_world=False, world_first=True)
    try:
        assert rt.call("hello") == {"g": "hello, ada"}  # the config's subsystems and trees
        assert not rt.check_actor("robot.navigate")
    finally:
        app.close(rt)
    assert capsys.readouterr().err.count("actorbt: warning: skipped") == 1
    project = project_with_a_broken_tree
    project.write_text(project.read_text() + "plugins: [demo.cli]\n")
    assert main(["--config", str(project), "demo", "--world", "none"]) == 2
    assert "an episode needs a simulated world" in capsys.readouterr().err


def test_the_readmes_commands_start_localised_where_the_robot_stands(capsys):
    """The simulator tells the localiser where the robot starts, as a user would with
    RViz's "2D Pose Estimate", in every command: `actorbt call get_pose` in the house
    is the start pose (1, 1, 0), and `call goto` leaves from there."""
    repo = pathlib.Path(__file__).resolve().parents[1] / "actorbt.yaml"
    assert main(["--config", str(repo), "call", "get_pose", "--json"]) == 0
    x, y, yaw = json.loads(capsys.readouterr().out)
    assert (x, y) == pytest.approx((1.0, 1.0), abs=0.05) and yaw == pytest.approx(0.0, abs=0.05)
    assert main(["--config", str(repo), "call", "goto", "2.0", "2.0", "0.0", "--json"]) == 0
    x, y, _ = json.loads(capsys.readouterr().out)
    assert (x, y) == pytest.approx((2.0, 2.0), abs=0.1)
