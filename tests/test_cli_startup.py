"""Engine-only ``actorbt`` commands start without the simulator, ROS or OpenCV (issue
[core-2]), and the actor index they read instead of a runtime says what a runtime would.

The timing targets are in bench/bench_cli_startup.py; these tests only look at what a
command imports, in a fresh interpreter.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Iterator

import pytest

from bt_engine import Runtime
from bt_cli.actor_index import ActorIndex
from bt_cli.app import App
from bt_cli.config import load_config
from bt_engine.errors import AmbiguousActorError, UnknownActorError
from bt_engine.trees import TreeLibrary, check_files

REPO = Path(__file__).resolve().parents[1]
BANNER = "pybullet build time"
#: what engine-only commands must not load: the simulator (pybullet, sim's modules beyond
#: the `sim` package and its command plugin), ROS, OpenCV, the robot's code and matplotlib
HEAVY = (
    "pybullet",
    "rclpy",
    "cv2",
    "matplotlib",
    "sensor_msgs",
    "geometry_msgs",
    "nav_msgs",
    "std_msgs",
    "trajectory_msgs",
    "actors",
    "planning",
    "scipy",
)

# Runs main() in a fresh interpreter and prints the modules it loaded as the last line.
PROBE = textwrap.dedent("""
    import contextlib, io, json, sys
    from bt_cli.main import main
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            rc = main(sys.argv[1:])
        except SystemExit as e:
            rc = e.code
    print(json.dumps({"rc": rc, "modules": sorted(sys.modules)}))
""")


def loaded(cwd: Path, *args: str) -> set[str]:
    """The modules ``actorbt ARGS`` loads; fails when it fails or prints the banner."""
    proc = subprocess.run([sys.executable, "-c", PROBE, *args], cwd=cwd, capture_output=True, text=True, timeout=120)
    assert BANNER not in proc.stdout + proc.stderr, (
        f"actorbt {' '.join(args)} imported pybullet (or rebuilt the actor index: was a source "
        "file edited while the test ran?)"
    )
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["rc"] == 0, proc.stderr
    return set(result["modules"])


def heavy(modules: set[str]) -> list[str]:
    found = [m for m in modules if m.split(".")[0] in HEAVY]
    # the plugins: argparse only
    found += [m for m in modules if m.startswith("sim.") and m not in ("sim.cli", "sim.robot_cli")]
    return sorted(found)


@pytest.fixture(scope="module")
def robot_project(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The repository's actorbt.yaml (robot, plugins, trees) in a folder of its own, with
    its actor index built once (that run imports and constructs the robot)."""
    folder = tmp_path_factory.mktemp("project")
    cfg = load_config(REPO / "actorbt.yaml")
    (folder / "actorbt.yaml").write_text(
        json.dumps(
            {
                "subsystems": cfg.subsystems,
                "trees": str(cfg.trees_dir()),
                "world": cfg.world,
                "simulator": cfg.simulator,
                "plugins": cfg.plugins,
            }
        )
    )
    subprocess.run(
        [sys.executable, "-m", "bt_cli.main", "check"], cwd=folder, check=True, capture_output=True, timeout=300
    )
    assert (folder / ".actorbt" / "actors.json").is_file()
    return folder


def test_help_loads_neither_the_simulator_nor_the_tree_layer() -> None:
    modules = loaded(REPO, "--help")
    assert heavy(modules) == []
    assert "py_trees" not in modules  # the tree commands are imported when they run
    assert {"sim.cli", "demo.cli"} <= modules  # the plugins still declare their commands


def test_check_reads_the_actor_index(robot_project: Path) -> None:
    files = sorted(str(p) for p in (REPO / "trees").glob("*.yaml"))
    assert heavy(loaded(robot_project, "check", *files)) == []


@pytest.mark.parametrize(
    "args",
    [
        ["list"],
        ["catalog", "--json"],
        ["show", "bt_pick_place"],
        ["replay", str(REPO / "tests" / "replays" / "demo_patrol.jsonl"), "--trees", str(REPO / "trees")],
    ],
)
def test_engine_only_commands_load_no_robot_code(robot_project: Path, args: list[str]) -> None:
    assert heavy(loaded(robot_project, *args)) == []


def test_plot_loads_matplotlib_only(robot_project: Path, tmp_path: Path) -> None:
    trace = REPO / "tests" / "replays" / "demo_patrol.jsonl"
    modules = loaded(robot_project, "plot", str(trace), "--out", str(tmp_path / "t.png"))
    assert {m.split(".")[0] for m in heavy(modules)} == {"matplotlib"}


# -- the actor index --------------------------------------------------------------------
ACTORS = '''
from __future__ import annotations

from bt_engine import SubSystem, actor


class Marker:
    def __repr__(self) -> str:
        return "Marker()"


class Arm(SubSystem):
    @actor
    def move(self, *q: float) -> list[float]:
        """Move the joints."""
        return list(q)

    @actor
    def where(self) -> tuple[float, float, float]:
        return (0.0, 0.0, 0.0)

    @actor
    def stop(self, hard: bool = False, *, how: Marker = Marker()) -> dict | None:
        return None


class Base(SubSystem):
    @actor
    def goto(self, x: float, y: float, yaw: float = 0.0, frame: str = "map") -> bool:
        return True

    @actor
    def stop(self) -> None:
        pass


class Robot(SubSystem):
    def __init__(self) -> None:
        super().__init__()
        self.add_subsystem("arm", Arm)
        self.add_subsystem("base", Base)
'''

MISSION = """
name: probe
root:
  sequence:
    - do: where
      out: pose
    - do: goto
      with: {x: "{pose}", y: 1}
    - do: goto
      with: {x: 1, y: 2, heading: 3}
    - do: goto
      with: [1, 2, 3, "map", 5]
    - do: move
      with: [0.1, "far"]
    - do: stop
    - do: robot.arm.stop
      with: {hard: 1}
    - do: gotoo
"""


@pytest.fixture
def project(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    (tmp_path / "probe_actors.py").write_text(ACTORS)
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "actorbt.yaml").write_text("subsystems:\n  robot: probe_actors:Robot\ntrees: null\n")
    (tmp_path / "probe.yaml").write_text(MISSION)
    yield tmp_path
    sys.modules.pop("probe_actors", None)  # the next test's module is another file


def app_for(project: Path) -> App:
    import argparse

    return App(argparse.Namespace(config=str(project / "actorbt.yaml")))


def test_index_validates_as_the_runtime_does(project: Path) -> None:
    app = app_for(project)
    app.actor_index()  # built from a runtime and stored
    index = ActorIndex.load(app.index_path(), app.cfg.subsystems)  # read back from JSON
    assert index is not None
    with Runtime() as rt:
        rt.add_subsystem("robot", __import__("probe_actors").Robot)
        expected = [str(e) for e in check_files([project / "probe.yaml"], rt.root.resolve)]
        assert [str(e) for e in check_files([project / "probe.yaml"], index.resolve)] == expected
        assert len(expected) >= 6  # each do: above but the first is wrong in its own way
        shown = {r.path: str(r.signature) for r in rt.root.all_actors()}
    assert {e.path: e.shown for e in index.entries} == shown


def test_index_resolves_as_the_root_scope(project: Path) -> None:
    index = app_for(project).actor_index()
    assert index.resolve("goto").path == "robot.base.goto"
    assert index.resolve("robot.arm.stop").path == "robot.arm.stop"
    with pytest.raises(AmbiguousActorError, match="robot.arm.stop, robot.base.stop"):
        index.resolve("stop")
    with pytest.raises(UnknownActorError) as err:
        index.resolve("gotoo")
    assert "goto" in err.value.suggestions
    lib = TreeLibrary(index.resolve)
    lib.load_file(project / "probe.yaml")
    assert lib.resolve("probe").is_tree


def test_index_is_rebuilt_when_its_sources_or_subsystems_change(project: Path) -> None:
    app = app_for(project)
    app.actor_index()
    path, subsystems = app.index_path(), app.cfg.subsystems
    assert path == project / ".actorbt" / "actors.json"
    assert ActorIndex.load(path, subsystems) is not None
    assert ActorIndex.load(path, {**subsystems, "more": "probe_actors:Base"}) is None
    source = project / "probe_actors.py"
    stat = source.stat()
    os.utime(source, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000))
    assert ActorIndex.load(path, subsystems) is None
    app.actor_index()  # rebuilt and stored again
    assert ActorIndex.load(path, subsystems) is not None
    path.write_text("{not json")
    assert ActorIndex.load(path, subsystems) is None


# -- --config is read by argparse before the full parser exists --------------------------
def test_plugins_come_from_the_config_option_in_either_spelling(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from bt_cli.main import main

    cfg = tmp_path / "actorbt.yaml"
    cfg.write_text("subsystems: {}\ntrees: null\nplugins: [sim.cli]\n")
    for option in (["--config", str(cfg)], [f"--config={cfg}"]):
        assert main([*option, "sim", "worlds"]) == 0
        assert "house" in capsys.readouterr().out.split()
    cfg.write_text("subsystems: {}\ntrees: null\nplugins: []\n")
    with pytest.raises(SystemExit):
        main(["--config", str(cfg), "sim", "worlds"])
    assert "invalid choice: 'sim'" in capsys.readouterr().err


def test_a_missing_or_broken_config_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from bt_cli.main import main

    assert main(["--config", str(tmp_path / "nope.yaml"), "list"]) == 2
    err = capsys.readouterr().err
    assert err == f"actorbt: error: cannot read {tmp_path / 'nope.yaml'}: No such file or directory\n"
    with pytest.raises(SystemExit):
        main(["--config"])
    assert "argument --config: expected one argument" in capsys.readouterr().err
