"""The ROS ways in, as a person meets them: a tree name checked against what the serve
offers (close matches), one line per goal from the server, the warm shell
(``actorbt rshell``), start-up progress of ``actorbt sim run``, a client with no serve
to talk to, and the discovery settings every actorbt process starts with."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
import time

import pytest

pytest.importorskip("rclpy")

from bt_engine import Runtime  # noqa: E402
from bt_ros import host as ros_host  # noqa: E402
from bt_ros.goal_server import one_line, seconds  # noqa: E402
from bt_ros.names import tree_action_name, tree_of_action  # noqa: E402
from bt_ros.remote import NoServeError, Remote, UnknownTreeError, close_matches  # noqa: E402
from bt_ros.server import serve  # noqa: E402
from bt_ros.shell import RemoteShell  # noqa: E402
from bt_ros.transport import RosTransport  # noqa: E402
from bt_ros.yamlio import flow  # noqa: E402
from tests.test_ros_common import ROOT, Work, wait_until, write_trees  # noqa: E402

GID = r"[0-9a-f]{8}"


# -- pieces ------------------------------------------------------------------------------
def test_tree_names_and_action_names_go_both_ways():
    for tree in ["bt_pick", "nav.patrol", "a.b.c"]:
        assert tree_of_action(tree_action_name(tree)) == tree
    assert tree_of_action("/actorbt/call") is None
    assert tree_of_action("/actorbt/tree/") is None


def test_close_matches_put_names_containing_the_text_first():
    served = ["bt_carry", "bt_catch", "bt_pick", "bt_pick_place", "bt_search", "reset"]
    assert close_matches("bt_pik", served) == ["bt_pick", "bt_pick_place"]
    assert close_matches("pick", served)[:2] == ["bt_pick", "bt_pick_place"]
    assert close_matches("nosuchtree", served) == []
    err = UnknownTreeError("bt_pik", served)
    assert str(err) == (
        "no served tree 'bt_pik'; did you mean: bt_pick, bt_pick_place? "
        "(served: bt_carry, bt_catch, bt_pick, bt_pick_place, bt_search, reset)"
    )
    assert str(UnknownTreeError("x", [])) == "no served tree 'x' (served: none)"


def test_announce_line_pieces():
    assert one_line("a\n  b\tc") == "a b c"
    assert one_line("x" * 500).endswith("\u2026") and len(one_line("x" * 500)) == 160
    assert seconds(0.031) == "0.03 s" and seconds(12.34) == "12.3 s"
    assert flow({"category": "can", "place": {"x": 1.0}}) == "{category: can, place: {x: 1.0}}"


def test_no_serve_error_says_how_to_start_one():
    text = str(NoServeError(10.0))
    assert text.startswith("no actorbt serve found within 10 s; start one with `actorbt serve`")


# -- discovery settings --------------------------------------------------------------------
@pytest.fixture
def clean_dds_env(monkeypatch, tmp_path):
    for var in ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE"):
        monkeypatch.setenv(var, "")  # whatever happens to it, it is restored afterwards
        monkeypatch.delenv(var)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(ros_host.tempfile, "gettempdir", lambda: str(tmp_path))
    return monkeypatch


def test_on_this_machine_participants_announce_often(clean_dds_env):
    clean_dds_env.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    ros_host.default_environment()
    path = os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"]
    text = open(path).read()
    assert "<leaseAnnouncement><sec>0</sec><nanosec>250000000</nanosec></leaseAnnouncement>" in text
    ros_host.default_environment()  # again: the same file, unchanged
    assert os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] == path


@pytest.mark.parametrize("setting", ["user profile", "subnet", "profile in the folder"])
def test_a_dds_configuration_of_the_user_is_left_alone(clean_dds_env, setting):
    clean_dds_env.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if setting == "user profile":
        clean_dds_env.setenv("FASTDDS_DEFAULT_PROFILES_FILE", "/somewhere/mine.xml")
    elif setting == "subnet":
        clean_dds_env.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")
    else:
        with open("DEFAULT_FASTRTPS_PROFILES.xml", "w") as f:
            f.write("<dds/>")
    ros_host.default_environment()
    assert "FASTRTPS_DEFAULT_PROFILES_FILE" not in os.environ


# -- a server in this process ------------------------------------------------------------------
@pytest.fixture(scope="module")
def served(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("served")
    lines: list[str] = []
    rt = Runtime(clock="wall", bus=RosTransport)
    remote = server = None
    try:
        rt.add_subsystem("work", Work)
        from bt_engine.trees import register_tree_folder

        register_tree_folder(rt, write_trees(tmp / "trees"))
        server = serve(rt, record_dir=tmp / "goals", on_event=lines.append)
        remote = Remote(wait=10.0)
        remote.wait_for_serve()
        yield rt, remote, lines
    finally:
        if remote is not None:
            remote.close()
        if server is not None:
            server.close()
        rt.close()


def test_served_trees_come_from_the_ros_graph(served):
    rt, remote, lines = served
    assert wait_until(lambda: remote.served_trees() == ["steps_tree"], 5.0), remote.served_actions()
    assert "/actorbt/call" in remote.served_actions()
    remote.check_tree("steps_tree")  # served: returns


def test_a_tree_that_is_not_served_fails_with_close_matches(served):
    rt, remote, lines = served
    t0 = time.monotonic()
    with pytest.raises(UnknownTreeError) as e:
        remote.check_tree("steps_tre")
    assert time.monotonic() - t0 < 5.0
    assert e.value.suggestions == ["steps_tree"] and e.value.served == ["steps_tree"]


def test_the_server_tells_each_goal_in_one_line(served):
    rt, remote, lines = served
    del lines[:]
    assert remote.run_tree("steps_tree", {"steps": 2, "period": 0.01}) == {"count": 2}
    assert remote.call("work.echo", 1, k="v") == {"args": [1], "kwargs": {"k": "v"}}
    g = remote.tree_goal("steps_tree", "{steps: x}")
    assert g.wait(5.0) and g.status == "rejected"
    g = remote.tree_goal("steps_tree", {"steps": 1000, "period": 0.01})
    assert wait_until(lambda: any(line.endswith(": accepted") for line in lines[3:]), 5.0), lines
    g.cancel()
    assert g.wait(5.0) and g.status == "canceled"
    with pytest.raises(Exception):
        remote.call("work.boom")
    assert wait_until(lambda: len(lines) >= 7, 5.0), lines
    patterns = [
        rf"goal ({GID}) steps_tree \{{steps: 2, period: 0\.01\}}: accepted",
        rf"goal ({GID}) steps_tree: succeeded in \d+\.\d+ s \(trace .*steps_tree-{GID}\.jsonl\)",
        rf"call {GID} work\.echo\(1, k='v'\): succeeded in \d+\.\d+ s",
        rf"goal {GID} steps_tree \{{steps: x\}}: refused \(INVALID_GOAL\): .*",
        rf"goal ({GID}) steps_tree \{{steps: 1000, period: 0\.01\}}: accepted",
        rf"goal ({GID}) steps_tree: canceled in \d+\.\d+ s( \(trace .*\.jsonl\))?",
        rf"call {GID} work\.boom\(\): failed: .*kaput in \d+\.\d+ s",
    ]
    assert len(lines) == len(patterns), lines
    found = [re.fullmatch(p, line) for p, line in zip(patterns, lines)]
    assert all(found), list(zip(patterns, lines))
    assert found[0].group(1) == found[1].group(1) and found[4].group(1) == found[5].group(1)


class _Entry:
    def __init__(self, path: str, shown: str, kind: str = "sync", doc: str = "") -> None:
        self.path, self.name, self.shown = path, path.split(".")[-1], shown
        self.kind, self.doc, self.is_tree = kind, doc, kind == "tree"


def test_the_warm_shell_calls_completes_and_describes(served):
    rt, remote, lines = served
    index = [
        _Entry("work.echo", "(*args, **kwargs) -> dict", doc="Echo the arguments."),
        _Entry("work.slow", "(steps: int = 3, period: float = 0.02) -> int"),
        _Entry("steps_tree", "(steps: int = 3, period: float = 0.02) -> dict", kind="tree"),
    ]
    script = (
        "\n".join(
            [
                "work.echo 1 k='v'",
                "echo 2",
                "help echo",
                "help work.ech",
                "list work",
                "work.slow 1 2 3",
                "trees",
                "quit",
                "work.echo 3",
            ]
        )
        + "\n"
    )
    out = io.StringIO()
    shell = RemoteShell(remote, lambda: index, stdin=io.StringIO(script), stdout=out)
    shell.cmdloop()
    text = out.getvalue()
    assert "{'args': [1], 'kwargs': {'k': 'v'}}" in text
    assert "{'args': [2], 'kwargs': {}}" in text  # resolved by the serve
    assert "work.echo(*args, **kwargs) -> dict  [sync]\nEcho the arguments." in text
    assert "error: unknown actor 'work.ech'; did you mean: work.echo" in text
    assert "  work.slow(steps: int = 3, period: float = 0.02) -> int  [sync]" in text
    assert "error: refused (INVALID_GOAL):" in text  # too many arguments
    assert "  steps_tree\n" in text
    assert "{'args': [3]" not in text  # after quit
    assert shell.completenames("work.e") == ["work.echo"]
    assert "steps_tree" in shell.completenames("steps")


def test_the_warm_shell_costs_a_round_trip_per_call(served):
    rt, remote, lines = served
    remote.call("work.echo")  # the client exists
    t0 = time.perf_counter()
    for i in range(10):
        remote.call("work.echo", i)
    per_call = (time.perf_counter() - t0) / 10
    assert per_call < 0.5, f"{per_call * 1e3:.0f} ms per call"  # a cold rcall takes seconds


# -- processes ---------------------------------------------------------------------------------
#: a ROS domain with no serve in it (test_ros_common takes 1..100 for this process)
LONELY = dict(
    os.environ,
    ROS_DOMAIN_ID=str(101 + os.getpid() % 100),
    PYTHONUNBUFFERED="1",
    ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
)


@pytest.mark.parametrize(
    "argv", [["goal", "bt_pick", "--wait", "1"], ["rcall", "get_pose", "--wait", "1"], ["rshell", "--wait", "1"]]
)
def test_with_no_serve_the_clients_say_how_to_start_one(argv):
    proc = subprocess.run(
        [sys.executable, "-m", "bt_cli.main", *argv],
        cwd=ROOT,
        env=LONELY,
        input="",
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "no actorbt serve found within 1 s; start one with `actorbt serve`" in proc.stderr


def test_sim_run_tells_its_start_up_and_loads_no_actors():
    # -X importtime lists every module imported on stderr
    proc = subprocess.run(
        [
            sys.executable,
            "-X",
            "importtime",
            "-m",
            "bt_cli.main",
            "sim",
            "run",
            "--world",
            "house",
            "--bus",
            "ros",
            "--seconds",
            "0.5",
        ],
        cwd=ROOT,
        env=LONELY,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "actorbt sim run: starting world house (seed 0) on the ros bus..." in proc.stderr
    assert re.search(r"world house running on the ros bus, ready in \d+\.\d s", proc.stdout), proc.stdout
    imported = {line.rpartition("|")[2].strip() for line in proc.stderr.splitlines() if line.startswith("import time:")}
    assert "sim.simworld" in imported
    assert not {m for m in imported if m.split(".")[0] in ("actors", "planning")}
    assert "bt_engine.trees" not in imported
