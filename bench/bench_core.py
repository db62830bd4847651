"""Engine core micro-benchmarks (issue [core]). Medians over repeated batches, one run.

.venv/bin/python bench/bench_core.py
"""

from __future__ import annotations

import gc
import statistics
import threading
import time

from bt_engine import Runtime, Signal, SubSystem, actor

REPEATS = 15


class Bench(SubSystem):
    @actor
    def add(self, a: int, b: int = 1) -> int:
        return a + b

    @actor
    def numbers(self):
        i = 0
        while True:
            yield i
            i += 1

    @actor("burst", "multi", hub_only=True)
    def burst(self, emit):
        """Emits 64 values per hub turn while open (a fast sensor)."""
        state = {"open": True}

        def produce() -> None:
            if state["open"]:
                for i in range(64):
                    emit(i)
                self.runtime.hub.call_soon(produce)

        self.runtime.hub.call_soon(produce)
        return lambda: state.update(open=False)

    # -- measuring loops (run as actors, on the hub) -----------------------------------
    @actor
    def time_sync_calls(self, n: int) -> float:
        t0 = time.perf_counter()
        for _ in range(n):
            self.run_actor("add", 1)
        return (time.perf_counter() - t0) / n

    @actor
    def time_async_round_trips(self, n: int) -> float:
        sig = Signal(self.runtime)
        cb = lambda result: sig.set()  # noqa: E731
        t0 = time.perf_counter()
        for _ in range(n):
            sig.clear()
            self.run_actor_mode("add", "async", cb, 1)
            sig.wait()
        return (time.perf_counter() - t0) / n

    @actor
    def time_generator_items(self, n: int) -> float:
        with self.run_actor_mode("numbers", "iterator") as it:
            t0 = time.perf_counter()
            for _ in range(n):
                next(it)
            return (time.perf_counter() - t0) / n

    @actor
    def time_emit_items(self, n: int) -> float:
        with self.run_actor_mode("burst", "iterator") as it:
            t0 = time.perf_counter()
            for _ in range(n):
                next(it)
            return (time.perf_counter() - t0) / n

    @actor
    def hold_transactions(self, k: int) -> int:
        txns = [self.run_actor_mode("sleep", "async", None, 10.0) for _ in range(k)]
        self.run_actor("sleep", 1.0)
        live = len(self.runtime.transactions())
        self.set_value("rss_at_peak", rss_mb())
        self.run_actor("sleep", 10.0)
        assert all(t.done for t in txns)
        return live


def rss_mb() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def median_us(fn, n: int) -> float:
    return statistics.median(fn(n) for _ in range(REPEATS)) * 1e6


def external_call(rt: Runtime, n: int) -> float:
    t0 = time.perf_counter()
    for _ in range(n):
        rt.call("add", 1)
    return (time.perf_counter() - t0) / n


def main() -> None:
    with Runtime(watchdog=None) as rt:
        rt.add_subsystem("bench", Bench)
        rows = [
            ("sync actor->actor call", median_us(lambda n: rt.call("time_sync_calls", n), 20000), 5),
            ("async call + callback round trip", median_us(lambda n: rt.call("time_async_round_trips", n), 5000), 30),
            ("external sync call (other thread)", median_us(lambda n: external_call(rt, n), 1000), 60),
            ("iterator item, generator stream", median_us(lambda n: rt.call("time_generator_items", n), 20000), None),
            ("iterator item, emit stream", median_us(lambda n: rt.call("time_emit_items", n), 20000), None),
        ]
        print(f"{'measure':40s} {'median':>10s} {'target':>8s}")
        for name, us, target in rows:
            tgt = f"<= {target}" if target else "-"
            ok = "" if target is None else ("  ok" if us <= target else "  MISSED")
            print(f"{name:40s} {us:8.2f} us {tgt:>8s}{ok}")
    print()
    print(f"{'in-flight transactions':>22s} {'RSS delta':>10s} {'per txn':>9s}")
    for k in (10_000, 50_000, 100_000):
        gc.collect()
        with Runtime(watchdog=None) as rt:
            rt.add_subsystem("bench", Bench)
            base = rss_mb()
            live = rt.call("hold_transactions", k)
            peak = rt.root._children["bench"].get_value("rss_at_peak")
            print(f"{live:22,d} {peak - base:8.1f} MB {1024 * (peak - base) / k:6.2f} kB")
            absolute = peak
        print(f"{'':22s} (process RSS at peak {absolute:.0f} MB)")
    print(f"threads now: {threading.active_count()}")


if __name__ == "__main__":
    main()
