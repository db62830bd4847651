"""Context for bench_core's "external sync call": the cost of handing control from one
CPython thread to another and back with two Locks and no engine at all. An external actor
call needs the same two hand-offs, so this is its floor on the machine at hand.

    .venv/bin/python bench/bench_thread_floor.py
"""

from __future__ import annotations

import statistics
import threading
import time


def round_trip_us(n: int = 3000, repeats: int = 7) -> float:
    ping, pong = threading.Lock(), threading.Lock()
    ping.acquire()
    pong.acquire()
    stop = False

    def server() -> None:
        while True:
            ping.acquire()
            if stop:
                return
            pong.release()

    t = threading.Thread(target=server)
    t.start()
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            ping.release()
            pong.acquire()
        samples.append((time.perf_counter() - t0) / n * 1e6)
    stop = True
    ping.release()
    t.join()
    return statistics.median(samples)


if __name__ == "__main__":
    print(f"bare two-thread Lock round trip: {round_trip_us():.1f} us (median of 7 x 3000)")
