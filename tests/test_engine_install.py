"""``pip install actorbt`` without extras is the engine alone (docs/install.md).

In a fresh virtual environment: the install pulls in no ROS, MCP, simulator or planning
package; ``bt_engine`` imports; a YAML mission calling Python actors loads and runs from
Python and from ``actorbt run``; a command whose extra is missing says which extra it needs.
Needs the package registry (pip), as ``make`` does.
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import subprocess
import sys
import textwrap
import venv

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: distributions of the extras, none of which the engine alone may bring (lower case)
FRONT_END_PACKAGES = (
    "ros-",
    "rclpy",
    "rosbags",
    "foxglove",
    "mcp",
    "jsonschema",
    "pybullet",
    "opencv",
    "moderngl",
    "ompl",
    "ruckig",
    "numpy",
    "scipy",
    "matplotlib",
    "graphviz",
    "ray",
)

ACTORS = '''
from bt_engine import SubSystem, actor


class Counter(SubSystem):
    @actor
    def add(self, a: int, b: int) -> int:
        """Add two numbers."""
        self.run_actor("sleep", 0.2)
        return a + b
'''

MISSION = """
name: adder
doc: Add 2 to x with a Python actor, and check the sum.
inputs:
  x: {type: int}
outputs: {total: int}
root:
  sequence:
    - {name: add, do: counter.add, with: {a: "{x}", b: 2}, out: total}
    - check: total > x
"""

RUN_FROM_PYTHON = """
import json, sys
from bt_engine import Runtime
from bt_engine.trees import register_tree_folder
from counter import Counter

with Runtime() as rt:
    rt.add_subsystem("counter", Counter)
    register_tree_folder(rt, "trees")
    print(json.dumps(rt.call("adder", x=40)))
print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in
                        ("rclpy", "numpy", "mcp", "pybullet", "bt_ros", "bt_cli", "bt_mcp", "bt_xml"))))
"""


@pytest.fixture(scope="module")
def engine_env(tmp_path_factory):
    """A fresh virtual environment with ``pip install <repository>`` and no extra."""
    where = tmp_path_factory.mktemp("engine")
    venv.EnvBuilder(with_pip=True).create(where / "venv")
    python = where / "venv" / "bin" / "python"
    done = subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", str(ROOT)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    project = where / "project"
    (project / "trees").mkdir(parents=True)
    (project / "counter.py").write_text(textwrap.dedent(ACTORS))
    (project / "trees" / "adder.yaml").write_text(textwrap.dedent(MISSION).lstrip())
    (project / "actorbt.yaml").write_text("subsystems:\n  counter: counter:Counter\ntrees: trees\n")
    return python, project


def run(python: pathlib.Path, project: pathlib.Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PYTHONPATH"] = str(project)  # the user's own actors; the engine comes from the venv
    return subprocess.run([str(python), *args], cwd=project, env=env, capture_output=True, text=True, timeout=120)


def test_installs_no_front_end_package(engine_env):
    python, project = engine_env
    listed = json.loads(run(python, project, "-m", "pip", "list", "--format", "json").stdout)
    names = sorted(re.sub(r"[-_.]+", "-", p["name"]).lower() for p in listed)  # PEP 503
    assert "actorbt" in names and "py-trees" in names
    assert [n for n in names if n.startswith(FRONT_END_PACKAGES)] == []


def test_the_engine_comes_from_the_environment(engine_env):
    python, project = engine_env
    where = run(python, project, "-c", "import bt_engine; print(bt_engine.__file__)").stdout
    assert "site-packages" in where and not where.startswith(str(ROOT)), where


def test_a_mission_of_python_actors_runs_from_python(engine_env):
    python, project = engine_env
    done = run(python, project, "-c", RUN_FROM_PYTHON)
    assert done.returncode == 0, done.stderr
    result, loaded = (json.loads(line) for line in done.stdout.splitlines())
    assert result == {"total": 42}
    assert loaded == []


def test_a_mission_runs_from_the_command_line(engine_env):
    python, project = engine_env
    actorbt = str(python.parent / "actorbt")
    done = run(python, project, actorbt, "run", "adder", "--arg", "x=1", "--json", "--quiet")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == {"total": 3}
    done = run(python, project, actorbt, "check")
    assert done.returncode == 0, done.stderr


def test_a_command_without_its_extra_says_which_extra(engine_env):
    python, project = engine_env
    actorbt = str(python.parent / "actorbt")
    listed = run(python, project, actorbt, "--help").stdout
    assert "[needs actorbt[ros]]" in listed and "[needs actorbt[mcp]]" in listed
    for command, extra in [(["serve"], "ros"), (["topic", "list"], "ros"), (["mcp"], "mcp")]:
        done = run(python, project, actorbt, *command)
        assert done.returncode == 2, (command, done.stdout, done.stderr)
        assert f"actorbt[{extra}]" in done.stderr, (command, done.stderr)
        assert "Traceback" not in done.stderr
    done = run(python, project, actorbt, "show", "adder", "--out", "adder.png")
    assert done.returncode == 2 and "[draw]" in done.stderr and "Traceback" not in done.stderr, done.stderr


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
