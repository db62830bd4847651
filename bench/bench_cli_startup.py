"""Start-up time of the engine-only ``actorbt`` commands (issue [core-2]), against the
baseline ``python -c "import yaml, py_trees"``. One run, ratios only.

    .venv/bin/python bench/bench_cli_startup.py [--rounds 7] [--strict]

Each command runs as a subprocess of the ``actorbt`` script beside this interpreter, in
the repository folder with its actorbt.yaml (plugins sim.cli and demo.cli). Every round
runs the baseline and then the command, for each command in turn, so machine noise hits
both alike; a command's ratio is its median wall time over the median of the baseline
runs paired with it. One untimed run of each command first writes the byte code and the
actor index (``.actorbt/actors.json``; rebuilding it, once after the robot's code
changes, imports and constructs the robot: see the last line).

Targets: ``--help`` <= 2x and ``check trees/*.yaml`` <= 3x the baseline; the other
commands are shown for information. "quiet" says no output of the command carried
pybullet's ``pybullet build time`` banner (the simulator was not imported).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = [sys.executable, "-c", "import yaml, py_trees"]
BANNER = "pybullet build time"
#: command line -> target ratio (None: information only)
COMMANDS: list[tuple[list[str], float | None]] = [
    (["--help"], 2.0),
    (["check", *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "trees").glob("*.yaml"))], 3.0),
    (["list"], None),
    (["show", "bt_pick_place"], None),
    (["catalog", "--json"], None),
]


def actorbt() -> list[str]:
    script = Path(sys.executable).with_name("actorbt")
    return [str(script)] if script.exists() else [sys.executable, "-m", "bt_cli.main"]


def timed(cmd: list[str]) -> tuple[float, str]:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    return elapsed, proc.stdout + proc.stderr


def shown(args: list[str]) -> str:
    return "check trees/*.yaml" if args[0] == "check" else " ".join(args)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7, help="timed runs of each command (default 7)")
    ap.add_argument("--strict", action="store_true", help="exit 1 when a target is missed")
    opts = ap.parse_args()

    exe = actorbt()
    cold: list[str] = []
    for args, _ in COMMANDS:  # byte code, actor index
        _, out = timed(exe + args)
        if BANNER in out:
            cold.append(shown(args))
    samples = {shown(a): [] for a, _ in COMMANDS}
    paired = {shown(a): [] for a, _ in COMMANDS}
    quiet = {shown(a): True for a, _ in COMMANDS}
    for _ in range(opts.rounds):
        for args, _ in COMMANDS:
            paired[shown(args)].append(timed(BASELINE)[0])
            elapsed, out = timed(exe + args)
            samples[shown(args)].append(elapsed)
            quiet[shown(args)] = quiet[shown(args)] and BANNER not in out

    base = statistics.median(t for ts in paired.values() for t in ts)
    print(
        f'baseline `python -c "import yaml, py_trees"`: {base * 1e3:.0f} ms '
        f"(median of {opts.rounds * len(COMMANDS)}); {opts.rounds} rounds, medians"
    )
    print(f"{'command':<22} {'ms':>6} {'base ms':>8} {'ratio':>6} {'target':>7}  {'quiet':<5} result")
    missed = 0
    for args, target in COMMANDS:
        name = shown(args)
        t, b = statistics.median(samples[name]), statistics.median(paired[name])
        ratio = t / b
        result = "-" if target is None else ("PASS" if ratio <= target else "FAIL")
        missed += result == "FAIL"
        goal = "-" if target is None else f"<={target:g}x"
        print(
            f"{name:<22} {t * 1e3:6.0f} {b * 1e3:8.0f} {ratio:5.2f}x {goal:>7}  "
            f"{'yes' if quiet[name] else 'NO':<5} {result}"
        )
    if cold:
        print(f"(the untimed first run rebuilt the actor index: {', '.join(cold)} printed the banner)")
    return 1 if missed and opts.strict else 0


if __name__ == "__main__":
    sys.exit(main())
