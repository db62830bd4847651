"""The headline figures (issue [mission]): success rate of bt_pick_place over N seeds for
each of can, bottle and mixed, the real-time factor of whole episodes under the virtual
clock, and the median wall time per episode.

    .venv/bin/python bench/bench_mission.py [SEEDS] [JOBS] [CATEGORIES]
        # default 50 seeds, 2 jobs, can,bottle,mixed

Each episode is a fresh house from its seed; traces and a CSV per category go to
out/bench_mission/. With 50 seeds this takes tens of minutes on two cores.
"""
from __future__ import annotations

import statistics
import sys
import time

from demo.evaluate import evaluate, print_table


TARGET_RATE = 0.95    # success per category (issue [senses])
TARGET_RTF = 10.0     # real-time factor of whole episodes, with all noise on


def main(seeds: int = 50, jobs: int = 2, categories: tuple = ("can", "bottle", "mixed")) -> None:
    rows = []
    t0 = time.perf_counter()
    for category in categories:
        print(f"\n--- {category}: {seeds} seeds ---", flush=True)
        eps = evaluate("bt_pick_place", seeds, "house", category, jobs,
                       f"out/bench_mission/{category}", first_seed=1000)
        print_table(eps)
        ok = sum(e.success for e in eps)
        rows.append((category, len(eps), ok, statistics.median(e.realtime_factor for e in eps),
                     statistics.median(e.wall_time for e in eps),
                     statistics.median(e.sim_time for e in eps)))
    print(f"\n{'category':8s} {'success':>12s} {'rate':>7s} {'RTF median':>11s} "
          f"{'wall/episode':>13s} {'sim/episode':>12s}")
    for cat, n, ok, rtf, wall, sim in rows:
        flag = "ok" if ok / n >= TARGET_RATE else "MISSED"
        print(f"{cat:8s} {ok:5d}/{n:<6d} {100 * ok / n:6.1f}% {rtf:10.1f}x {wall:11.1f} s "
              f"{sim:10.1f} s   target >= {TARGET_RATE:.0%}: {flag}; "
              f"RTF >= {TARGET_RTF:g}x: {'ok' if rtf >= TARGET_RTF else 'MISSED'}")
    print(f"\ntotal wall time {time.perf_counter() - t0:.0f} s with {jobs} parallel jobs")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50, int(sys.argv[2]) if len(sys.argv) > 2 else 2,
         *([tuple(sys.argv[3].split(","))] if len(sys.argv) > 3 else []))
