"""Start-up time of the ROS ways in ([cli-dx] item 12): how long until "ready".

    .venv/bin/python bench/bench_ros_startup.py [--rounds 3] [--calls 5] [--warm 20]

Each command runs as a subprocess of the ``actorbt`` script beside this interpreter, in
the repository folder with its actorbt.yaml, on a private ROS domain (on loopback):

- ``actorbt serve --world none``              (local bus; the node is still a ROS node)
- ``actorbt serve <ros> --world none``        (the ROS transport)
- ``actorbt sim run --world house <ros>``     (the simulator as its own ROS process)

where ``<ros>`` is ``--bus ros`` when ``actorbt serve --help`` offers ``--bus``, else
``--ros``. The time is from ``Popen`` to the line that says the process is ready
(``ready`` for serve; ``ready`` or ``running on the`` for ``sim run``). Then, with a
``sim run`` and a ``serve`` up (both on the ROS transport):

- cold: the wall time of ``actorbt rcall get_pose``, each a new process (``--calls``),
  and of ``actorbt goal nosuchtree`` (a tree the serve does not offer);
- warm: one :class:`bt_ros.remote.Remote` in this process, ``--warm`` calls of
  ``get_pose`` (what ``actorbt rshell`` does per line), after one untimed call.

Figures are median, min and max. One untimed run of ``actorbt --help`` first writes the
byte code.

``--roots DIR...`` compares checkouts (e.g. ``git archive`` of two commits) on this
machine at the same time: every command runs from each root in turn within each round,
so machine noise hits them alike. A root other than this repository is imported ahead
of the editable install (whose import hook is removed in the child process).
"""

from __future__ import annotations

import argparse
import os
import random
import re
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(120, 200)))
ENV = dict(os.environ, PYTHONUNBUFFERED="1")

SERVE_READY = re.compile(r"\bready\b")
SIM_READY = re.compile(r"\bready\b|running on the")


#: runs ``actorbt`` from the checkout in argv[1], not from the editable install
LAUNCH = (
    "import sys; root = sys.argv.pop(1); "
    "sys.meta_path[:] = [f for f in sys.meta_path if not type(f).__module__.startswith('_editable')]; "
    "sys.path.insert(0, root); sys.argv[0] = 'actorbt'; "
    "from bt_cli.main import main; sys.exit(main())"
)


def actorbt(root: Path = ROOT) -> list[str]:
    if root != ROOT:
        return [sys.executable, "-c", LAUNCH, str(root)]
    script = Path(sys.executable).with_name("actorbt")
    return [str(script)] if script.exists() else [sys.executable, "-m", "bt_cli.main"]


def ros_flag(root: Path = ROOT) -> list[str]:
    """``--bus ros`` when the command line has it, else the older ``--ros``."""
    out = subprocess.run(actorbt(root) + ["serve", "--help"], cwd=root, env=ENV, capture_output=True, text=True).stdout
    return ["--bus", "ros"] if "--bus" in out else ["--ros"]


class Process:
    """A long-running ``actorbt`` subprocess whose output is read line by line."""

    def __init__(self, args: list[str], ready: re.Pattern, root: Path = ROOT) -> None:
        self.args = args
        self.lines: list[tuple[float, str]] = []
        self.ready_at: float | None = None
        self._ready = threading.Event()
        self._pattern = ready
        self.t0 = time.perf_counter()
        self.proc = subprocess.Popen(
            actorbt(root) + args, cwd=root, env=ENV, text=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            now = time.perf_counter() - self.t0
            self.lines.append((now, line.rstrip()))
            if self.ready_at is None and self._pattern.search(line):
                self.ready_at = now
                self._ready.set()
        self._ready.set()

    def wait_ready(self, timeout: float = 90.0) -> float:
        self._ready.wait(timeout)
        if self.ready_at is None:
            self.stop()
            raise SystemExit(f"actorbt {' '.join(self.args)} was not ready in {timeout:g} s:\n" + self.output())
        return self.ready_at

    def output(self) -> str:
        return "\n".join(f"{t:7.2f}  {line}" for t, line in self.lines)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)  # as Ctrl-C; SIGINT may be ignored (a background job)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5)


def stats(values: list[float]) -> str:
    return (
        f"median {statistics.median(values):6.2f} s   min {min(values):6.2f} s   "
        f"max {max(values):6.2f} s   (n={len(values)})"
    )


def stats_ms(values: list[float]) -> str:
    return (
        f"median {statistics.median(values) * 1e3:7.1f} ms   min {min(values) * 1e3:7.1f} ms   "
        f"max {max(values) * 1e3:7.1f} ms   (n={len(values)})"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3, help="Start-ups of each command (default 3).")
    ap.add_argument("--calls", type=int, default=5, help="Cold `actorbt rcall get_pose` runs (default 5).")
    ap.add_argument("--warm", type=int, default=20, help="Calls through one warm Remote (default 20).")
    ap.add_argument("--show", action="store_true", help="Print the first run's output, timed.")
    ap.add_argument(
        "--roots",
        nargs="+",
        type=Path,
        default=[ROOT],
        metavar="DIR",
        help="Checkouts to measure side by side (default: this repository).",
    )
    opts = ap.parse_args()
    roots = [r.resolve() for r in opts.roots]

    flags = {}
    for root in roots:
        subprocess.run(actorbt(root) + ["--help"], cwd=root, env=ENV, capture_output=True)
        flags[root] = ros_flag(root)
    print(
        f"ROS_DOMAIN_ID={ENV['ROS_DOMAIN_ID']}  rounds: {opts.rounds}  "
        f"PYTHONDONTWRITEBYTECODE={os.environ.get('PYTHONDONTWRITEBYTECODE', '')}",
        flush=True,
    )

    def commands(root: Path) -> list[tuple[str, list[str], re.Pattern]]:
        ros = flags[root]
        return [
            ("serve --world none", ["serve", "--world", "none"], SERVE_READY),
            ("serve <ros> --world none", ["serve", *ros, "--world", "none"], SERVE_READY),
            ("sim run --world house <ros>", ["sim", "run", "--world", "house", *ros], SIM_READY),
        ]

    times: dict[tuple[Path, str], list[float]] = {}
    for i in range(opts.rounds):
        for index in range(3):
            for root in roots:
                label, args, ready = commands(root)[index]
                p = Process(args, ready, root)
                try:
                    times.setdefault((root, label), []).append(p.wait_ready())
                finally:
                    p.stop()
                if opts.show and i == 0:
                    print(f"-- {root}: actorbt {' '.join(args)}\n{p.output()}", flush=True)
    for root in roots:
        print(f"\n== {root} (transport flag {' '.join(flags[root])})")
        for label, _, _ in commands(root):
            print(f"actorbt {label:30s} to ready: {stats(times[(root, label)])}", flush=True)

    for root in roots:
        print(f"\n== {root}: calls against a running sim + serve", flush=True)
        calls(root, flags[root], opts)
    return 0


def calls(root: Path, ros: list[str], opts: argparse.Namespace) -> None:
    sim = Process(["sim", "run", "--world", "house", *ros], SIM_READY, root)
    serve = None
    try:
        sim.wait_ready()
        serve = Process(["serve", *ros, "--world", "none", "--no-record"], SERVE_READY, root)
        serve.wait_ready()
        cold = []
        for _ in range(opts.calls):
            t0 = time.perf_counter()
            proc = subprocess.run(
                actorbt(root) + ["rcall", "get_pose"], cwd=root, env=ENV, capture_output=True, text=True
            )
            cold.append(time.perf_counter() - t0)
            if proc.returncode != 0:
                raise SystemExit(f"rcall get_pose failed ({proc.returncode}):\n{proc.stdout}{proc.stderr}")
        print(f"actorbt rcall get_pose (cold, a process each)   {stats(cold)}", flush=True)
        unknown = []
        for _ in range(opts.calls):
            t0 = time.perf_counter()
            proc = subprocess.run(
                actorbt(root) + ["goal", "nosuchtree"], cwd=root, env=ENV, capture_output=True, text=True
            )
            unknown.append(time.perf_counter() - t0)
        print(f"actorbt goal nosuchtree (exit {proc.returncode})               {stats(unknown)}", flush=True)

        from bt_ros.remote import Remote  # this checkout's client, in this process

        t0 = time.perf_counter()
        with Remote() as remote:
            remote.call("get_pose", timeout=30)
            first = time.perf_counter() - t0
            warm = []
            for _ in range(opts.warm):
                t1 = time.perf_counter()
                remote.call("get_pose", timeout=30)
                warm.append(time.perf_counter() - t1)
        print(f"Remote: first get_pose (node + discovery)        {first:6.2f} s", flush=True)
        print(f"Remote: get_pose once warm (as in rshell)        {stats_ms(warm)}", flush=True)
    finally:
        if serve is not None:
            serve.stop()
        sim.stop()


if __name__ == "__main__":
    sys.exit(main())
