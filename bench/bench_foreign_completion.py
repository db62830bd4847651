"""Async and stream actors completed by a thread (threading.Timer, 50 ms) under a 1 s
deadline: how many of 80 calls complete on each clock (call(timeout=), timed,
timed_iterator, stream(timeout=), 10 rounds x 2 kinds). Both clocks must give 80 of 80:
the virtual clock may not jump past a deadline while such work is pending."""

import threading

from bt_engine import ActorTimeout, Runtime, SubSystem, actor


class F(SubSystem):
    @actor("fd", "async")
    def fd(self, done):
        t = threading.Timer(0.05, done, args=("finished",))
        t.start()
        return t.cancel

    @actor("fe", "multi")
    def fe(self, emit):
        t = threading.Timer(0.05, emit, args=("finished",))
        t.start()
        return t.cancel


def iter_first():
    with rt.run_actor_mode(name, "timed_iterator", 1.0) as it:
        return next(it)


def stream_first():
    with rt.stream(name, timeout=1.0) as it:
        return next(it)


for clock in ("virtual", "wall"):
    ok = total = 0
    with Runtime(clock=clock) as rt:
        rt.add_subsystem("f", F)
        for i in range(10):
            for name in ("fd", "fe"):
                globals().update(rt=rt, name=name)
                tries = [
                    lambda: rt.call(name, timeout=1.0),
                    lambda: rt.run_actor_mode(name, "timed", 1.0),
                    iter_first,
                    stream_first,
                ]
                for f in tries:
                    total += 1
                    try:
                        ok += f() == "finished"
                    except (ActorTimeout, StopIteration):
                        pass
    print(f"{clock}: {ok} of {total} complete")
