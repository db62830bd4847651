"""Shared pieces of the ROS tests (real rclpy over Fast DDS, on loopback): test actors,
test missions, leak checks for threads and /dev/shm segments, and ``actorbt serve`` in a
subprocess.

This module holds no tests itself. ``actorbt serve`` subprocesses import ``Work`` from
here (through a temporary actorbt.yaml).
"""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import threading
import time

from bt_engine import Cancelled, SubSystem, actor

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
# Test runs on one machine must not see each other's servers (two servers for one
# action name both execute a goal): each pytest process takes its own ROS domain.
os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))

ROOT = pathlib.Path(__file__).resolve().parents[1]


class Work(SubSystem):
    """Actors the ROS tests call: slow work that counts cancellations, and friends."""

    def __init__(self) -> None:
        super().__init__()
        self.set_value("stats", {"started": 0, "finished": 0, "cancelled": 0})

    @actor
    def slow(self, steps: int = 3, period: float = 0.02) -> int:
        """Sleep ``steps`` times ``period`` [s]; count starts, ends and cancellations."""
        st = self.get_value("stats")
        st["started"] += 1
        try:
            for _ in range(steps):
                self.run_actor("sleep", period)
        except Cancelled:
            st["cancelled"] += 1
            raise
        st["finished"] += 1
        return steps

    @actor
    def stats(self) -> dict:
        """The counters of ``slow``, and the live transactions of the runtime."""
        live = [t.path for t in self.transactions() if t.path != "work.stats"]
        return {**self.get_value("stats"), "live": live}

    @actor
    def echo(self, *args, **kwargs) -> dict:
        return {"args": list(args), "kwargs": kwargs}

    @actor
    def boom(self) -> None:
        raise ValueError("kaput")

    @actor
    def opaque(self) -> object:
        return object()


STEPS_TREE = """\
name: steps_tree
doc: Count steps slowly, then mark the run done.
inputs:
  steps: {type: int, default: 3}
  period: {type: float, default: 0.02}
outputs: [count]
root:
  sequence:
    - name: counting
      do: work.slow
      with: {steps: "{steps}", period: "{period}"}
      out: count
    - set: {finished: true}
"""


def write_trees(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "steps_tree.yaml").write_text(STEPS_TREE)
    return folder


def write_config(tmp: pathlib.Path) -> pathlib.Path:
    """An actorbt.yaml with the Work subsystem and the test trees, on the ROS bus."""
    write_trees(tmp / "trees")
    cfg = tmp / "actorbt.yaml"
    cfg.write_text(
        textwrap.dedent(f"""\
        subsystems:
          work: tests.test_ros_common:Work
        trees: {tmp / "trees"}
        world: null
        transport: ros
        clock: wall
        """)
    )
    return cfg


# -- leak checks ---------------------------------------------------------------------------
def shm_mapped(pid: "int | str" = "self") -> set[str]:
    """The Fast DDS shared-memory files a process has mapped now."""
    try:
        with open(f"/proc/{pid}/maps") as f:
            return {line.split()[-1] for line in f if "/dev/shm/fastrtps_" in line}
    except OSError:
        return set()


def shm_files() -> set[str]:
    d = pathlib.Path("/dev/shm")
    return {str(p) for p in d.glob("*fastrtps_*")}


def _mapped_by_anyone() -> set[str]:
    found: set[str] = set()
    for p in pathlib.Path("/proc").iterdir():
        if p.name.isdigit():
            found |= shm_mapped(p.name)
    return found


def shm_leaks(segments: set[str]) -> set[str]:
    """Which of ``segments`` still exist although no process maps them any more.

    (Port segments are shared with other DDS processes on the machine; one that another
    live process still maps is theirs, not a leak.)"""
    left = {s for s in segments if os.path.exists(s)}
    if not left:
        return set()
    return left - _mapped_by_anyone()


def os_threads() -> int:
    return len(os.listdir("/proc/self/task"))


def python_threads() -> set[str]:
    return {t.name for t in threading.enumerate()}


def wait_until(cond, timeout: float = 5.0, step: float = 0.01) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return True
        time.sleep(step)
    return bool(cond())


#: the environment of actorbt subprocesses: DDS on this machine, output unbuffered
SUBPROCESS_ENV = dict(
    os.environ,
    ROS_AUTOMATIC_DISCOVERY_RANGE=os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
    PYTHONUNBUFFERED="1",
)


def actorbt(*args: str, **kw) -> subprocess.Popen:
    """``actorbt ARGS`` in a subprocess, stdout and stderr merged into one text pipe."""
    return subprocess.Popen(
        [sys.executable, "-m", "bt_cli.main", *args],
        cwd=ROOT,
        env=SUBPROCESS_ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        **kw,
    )


class ServeProcess:
    """``actorbt --config CFG serve SERVE_ARGS`` in a subprocess; its output lines are
    collected, and ``ready`` is set when it says it is ready."""

    def __init__(self, tmp: pathlib.Path, *serve_args: str) -> None:
        self.tmp = tmp
        self.cfg = write_config(tmp)
        self.lines: list[str] = []
        self.proc = actorbt("--config", str(self.cfg), "serve", *serve_args)
        self.ready = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())
            if "ready in" in line:
                self.ready.set()

    def output(self) -> str:
        return "\n".join(self.lines)

    def stop(self) -> int:
        """Ctrl-C, then kill after 15 s; the exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(15)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5)
        return self.proc.returncode
