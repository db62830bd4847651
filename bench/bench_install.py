"""What each install costs (issue [engine]): fresh virtual environments, their size on disk
and install time.

    .venv/bin/python bench/bench_install.py [--only engine|all]

- engine: ``pip install .``, the engine alone (greenlet, PyYAML, py_trees);
- all: the ROS interface packages built from interfaces/ and ``pip install .[all]``, every
  front-end and the simulated robot, as a user of all of actorbt has it (the test tools of
  ``[test]`` left out).

Each environment is made in a temporary folder and removed after. Needs the package
registry, as ``make`` does; ``all`` builds the interfaces with cmake (several minutes).
"""

from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys
import tempfile
import time
import venv

ROOT = pathlib.Path(__file__).resolve().parents[1]

INSTALLS = {
    "engine": [[str(ROOT)]],
    "all": [[str(ROOT / "interfaces" / "upstream")], [str(ROOT / "interfaces")], [f"{ROOT}[all]"]],
}


def size_mb(folder: pathlib.Path) -> float:
    return sum(f.lstat().st_size for f in folder.rglob("*") if f.is_file() and not f.is_symlink()) / 1e6


def measure(name: str) -> tuple[float, float, int]:
    """(size in MB, install seconds, distributions installed) of a fresh environment."""
    with tempfile.TemporaryDirectory(prefix=f"actorbt-{name}-") as where:
        env = pathlib.Path(where) / "venv"
        venv.EnvBuilder(with_pip=True).create(env)
        python = str(env / "bin" / "python")
        start = time.perf_counter()
        for args in INSTALLS[name]:
            subprocess.run([python, "-m", "pip", "install", "-q", "--disable-pip-version-check", *args], check=True)
        seconds = time.perf_counter() - start
        listed = subprocess.run(
            [python, "-m", "pip", "list", "--format", "freeze"], check=True, capture_output=True, text=True
        ).stdout.split()
        return size_mb(env), seconds, len(listed)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(INSTALLS))
    args = parser.parse_args()
    names = [args.only] if args.only else list(INSTALLS)
    print(f"{'install':8} {'size':>9} {'time':>8} {'distributions':>14}")
    for name in names:
        size, seconds, count = measure(name)
        print(f"{name:8} {size:7.0f} MB {seconds:6.0f} s {count:14d}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
