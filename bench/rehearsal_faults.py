"""The real-robot rehearsal under faults a real robot has: `actorbt robot --fault ...` in
one process, `actorbt --config actorbt.real.yaml run bt_pick_place` in another, over DDS
on the wall clock (as tests/test_rehearsal.py, once per fault).

For each fault it prints: how the mission ended (its exit status and last lines), wall
time, whether the can reached the pallet (the robot side's truth), and for the faults
with a moment (arm-abort, restart) how long after it the mission printed its first
failure, from the lines both processes print as they go.

    .venv/bin/python bench/rehearsal_faults.py [--only NAME ...] [--timeout 400]
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import queue
import signal
import subprocess
import sys
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
ACTORBT = [sys.executable, "-m", "bt_cli.main"]
ENV = dict(os.environ, ROS_DOMAIN_ID="7", ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", PYTHONUNBUFFERED="1")
PLACE = {"x": 2.0, "y": -2.0, "size_x": 0.6, "size_y": 0.4, "height": 0.12}
SCENARIOS = {
    "none": [],
    "scan": ["scan-drop=0.1", "scan-delay=0.1"],
    "camera": ["camera-drop=0.1", "camera-delay=0.1"],
    "arm-abort": ["arm-abort=3"],
    "restart": ["restart=35"],
}
#: what the robot side prints at a fault's moment
MOMENT = ("fault: the robot side went down", "aborted half way")


class Lines:
    """A process's output lines with their arrival time (wall, epoch)."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.lines: list[tuple[float, str]] = []
        self.q: queue.Queue = queue.Queue()
        threading.Thread(target=self._read, args=(proc,), daemon=True).start()

    def _read(self, proc) -> None:
        for line in proc.stdout:
            item = (time.time(), line.rstrip())
            self.lines.append(item)
            self.q.put(item)

    def wait_for(self, text: str, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                _, line = self.q.get(timeout=0.2)
            except queue.Empty:
                continue
            if text in line:
                return True
        return False


def run(name: str, faults: list[str], timeout: float) -> dict:
    tmp = pathlib.Path(tempfile.mkdtemp(prefix=f"faults_{name}_"))
    truth = tmp / "truth.json"
    args = [*ACTORBT, "robot", "--world", "open_floor", "--seed", "0", "--truth", str(truth)]
    for f in faults:
        args += ["--fault", f]
    robot = subprocess.Popen(args, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    robot_out = Lines(robot)
    out = {"fault": name, "faults": faults}
    try:
        if not robot_out.wait_for("robot ready", 90):
            return {**out, "outcome": "robot side did not start"}
        t0 = time.time()
        mission = subprocess.Popen(
            [
                *ACTORBT,
                "--config",
                str(ROOT / "actorbt.real.yaml"),
                "run",
                "bt_pick_place",
                "--arg",
                "category=can",
                "--arg",
                f"place={json.dumps(PLACE)}",
                "--arg",
                "home={x: 0.0, y: 0.0, yaw: 0.0}",
                "--record",
                str(tmp / "run.jsonl"),
            ],
            cwd=ROOT,
            env=ENV,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        mission_out = Lines(mission)
        try:
            rc = mission.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            mission.send_signal(signal.SIGINT)
            rc = mission.wait(timeout=60)
            out["hung"] = True
        time.sleep(0.5)
        out.update(exit=rc, wall=round(time.time() - t0, 1), last=[line for _, line in mission_out.lines[-4:]])
        moment = next((t for t, line in robot_out.lines if any(m in line for m in MOMENT)), None)
        if moment is not None:
            failed = next(
                (
                    (t, line)
                    for t, line in mission_out.lines
                    if t >= moment and ("failure" in line.lower() or "error" in line.lower())
                ),
                None,
            )
            out["fault_at"] = round(moment - t0, 1)
            out["noticed_after"] = None if failed is None else round(failed[0] - moment, 1)
            out["noticed_by"] = None if failed is None else failed[1].strip()[:160]
    finally:
        if robot.poll() is None:
            robot.send_signal(signal.SIGINT)
            try:
                robot.wait(timeout=30)
            except subprocess.TimeoutExpired:
                robot.kill()
    out["robot_said"] = [line for _, line in robot_out.lines if line.startswith("fault:")]
    try:
        t = json.loads(truth.read_text())
        cans = [o["pose"] for o in t["objects"].values() if o["category"] == "can"]
        out["placed"] = any(
            abs(p[0] - PLACE["x"]) <= 0.3 and abs(p[1] - PLACE["y"]) <= 0.2 and p[2] > 0.12 for p in cans
        )
    except (OSError, ValueError, KeyError):
        out["placed"] = None
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="*", choices=sorted(SCENARIOS), help="run only these")
    ap.add_argument("--timeout", type=float, default=400.0, help="a mission's limit [s, wall]")
    a = ap.parse_args()
    for name in a.only or SCENARIOS:
        print(f"--- {name}: {' '.join(SCENARIOS[name]) or 'no fault'}", flush=True)
        result = run(name, SCENARIOS[name], a.timeout)
        print(json.dumps(result, indent=1), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
