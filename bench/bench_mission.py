"""The headline figures (issue [mission]): success rate of bt_pick_place over N seeds for
each of can, bottle and mixed, the real-time factor of whole episodes under the virtual
clock, and the median wall time per episode.

    .venv/bin/python bench/bench_mission.py [SEEDS] [JOBS] [CATEGORIES]
        # default 50 seeds, 2 jobs, can,bottle,mixed

Each episode is a fresh house from its seed; traces and a CSV per category go to
out/bench_mission/. With 50 seeds this takes tens of minutes on two cores.
"""

from __future__ import annotations

import sys
import time

from demo.evaluate import evaluate, print_rates, print_table


TARGET_RATE = 0.95  # success per category (issue [senses])
TARGET_RTF = 10.0  # real-time factor of whole episodes, with all noise on


def main(seeds: int = 50, jobs: int = 2, categories: tuple = ("can", "bottle", "mixed")) -> None:
    rows = []
    t0 = time.perf_counter()
    for category in categories:
        print(f"\n--- {category}: {seeds} seeds ---", flush=True)
        eps = evaluate(
            "bt_pick_place", seeds, "house", category, jobs, f"out/bench_mission/{category}", first_seed=1000
        )
        print_table(eps)
        rows.append((category, eps))
    print_rates(rows, "category", TARGET_RATE, TARGET_RTF)
    print(f"\ntotal wall time {time.perf_counter() - t0:.0f} s with {jobs} parallel jobs")


if __name__ == "__main__":
    main(
        int(sys.argv[1]) if len(sys.argv) > 1 else 50,
        int(sys.argv[2]) if len(sys.argv) > 2 else 2,
        *([tuple(sys.argv[3].split(","))] if len(sys.argv) > 3 else []),
    )
