"""`make bench`: run every bench/bench_*.py in its own process, one after another."""

from __future__ import annotations

import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
#: hours, not minutes: run only when named (`python bench/run_all.py acceptance`)
LONG = {"bench_acceptance", "bench_real_maps"}


def main() -> int:
    only = sys.argv[1:]
    failed = []
    for script in sorted(HERE.glob("bench_*.py")):
        if only and not any(o in script.stem for o in only):
            continue
        if not only and script.stem in LONG:
            print(f"\n=== {script.stem}: skipped (hours; `python bench/run_all.py {script.stem}`) ===")
            continue
        print(f"\n=== {script.stem} ===", flush=True)
        rc = subprocess.call([sys.executable, str(script)], cwd=HERE.parent)
        if rc:
            failed.append(script.stem)
    if failed:
        print(f"\nbenchmarks that failed to run: {', '.join(failed)}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
