"""Mission (tree layer) benchmarks (issue [trees]). Medians over repeated batches, one run.

    .venv/bin/python bench/bench_trees.py

1. Tick overhead against bare py_trees 2.6 on the same 50- and 500-node trees. One
   generated shape (a mix of sequence / selector / parallel composites, all with py_trees'
   memory/synchronise settings that the mission format uses) is written both as a YAML
   mission whose leaves are ``do:`` actor leaves and as a plain py_trees tree. Neither side
   has visitors, observers, snapshots or a trace recorder. Our side is ticked with
   ``TreeRun.tick()`` (the tick itself, from ``host.prepare``; not the event-driven wait
   loop of ``TreeRun.run``), on the hub thread, inside one hub callback so that nothing else
   runs between ticks (bare py_trees is timed the same way, on the hub thread). Cases:

   * *done*: every tick completes the whole tree. Bare leaves are
     ``py_trees.behaviours.Success``; our actor leaves find their actor already done, i.e.
     ``ActorLeaf.initialise`` runs (argument resolution, done-token, ``start_actor``) and
     ``update`` reads a finished transaction and succeeds. The host's ``start_actor`` (the
     override point replay uses) hands back one real, already finished Transaction, so the
     actor engine's call cost is *not* included: this is the tree layer's overhead.
   * *instant actor* (information only): the same, but every leaf really starts an
     async-kind actor that calls ``done()`` at once, so each tick also pays one engine
     transaction per leaf (see bench_core for that cost alone).
   * *running*: steady state while waiting. Bare leaves are ``py_trees.behaviours.Running``;
     ours poll a started transaction that is still pending (an async-kind actor that never
     finishes). The first tick (starting the actors) is not timed.
   * *all-parallel* variants of *done* and *running*: the same node and leaf counts, but
     every composite a parallel, so every node is ticked on every tick (with the mixed
     shape, memory sequences and selectors leave much of the tree unticked).

   Baseline for the ratio is ``root.tick_once()``, the same primitive ``TreeRun.tick``
   calls; ``BehaviourTree.tick()`` is shown too (it walks the whole tree again after each
   tick for visitors even when there are none, so it is slower and flatters us). The
   script asserts that both sides have the same size and tick the same number of nodes.
2. Idle cost: a tree whose only leaf is ``do: sleep, with: {seconds: 60}`` on the virtual
   clock, registered with ``register_tree_folder``; ticks counted by a TreeObserver, CPU
   time (``time.process_time``, all threads) of the whole ``rt.call``. Also ``wait: 60``,
   and, for contrast, the sleep with ``max_period=1`` (information only).
3. Load time of a 500-node mission (actor calls with arguments, ``set``, ``check``,
   references, decorators): parse only, parse + validate (TreeLibrary), and parse +
   validate + register (``TreeHost.load_folder``, what ``register_tree_folder`` does).
"""

from __future__ import annotations

import collections
import gc
import itertools
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import ParallelPolicy, Status

from bt_engine import Runtime, SubSystem, actor
from bt_engine.trees import TreeHost, TreeLibrary, TreeObserver, read_mission, register_tree_folder, walk

REPEATS = 15
SIZES = (50, 500)
KINDS = ("sequence", "selector", "parallel")
BATCH_SECONDS = 0.03  # target length of one timed batch
TICK_TARGET = 1.3
IDLE_SECONDS = 60.0


class BenchActors(SubSystem):
    @actor("instant", "async", hub_only=True)
    def instant(self, done):
        """Finishes at once, inside the call that starts it."""
        done(None)

    @actor("pending", "async", hub_only=True)
    def pending(self, done):
        """Never finishes by itself; cancelling it just drops it."""
        return lambda: None


# ---------------------------------------------------------------------------- tree shapes


def make_shape(n: int, kinds: tuple[str, ...] = KINDS) -> Any:
    """A tree of exactly ``n`` nodes: ``"leaf"`` or ``(kind, [children])``; composite kinds
    cycle through ``kinds`` (sequence / selector / parallel), about 4 children each."""
    counter = itertools.count()

    def make(budget: int) -> Any:
        if budget == 1:
            return "leaf"
        kind = kinds[next(counter) % len(kinds)]
        rest = budget - 1
        if rest <= 6:
            return (kind, ["leaf"] * rest)
        return (kind, [make(s) for s in _split(rest)])

    return make(n)


def _split(rest: int, k: int = 4) -> list[int]:
    """``rest`` nodes in ``k`` near-equal subtrees; a 2 becomes two leaves (no composite
    with a single child)."""
    sizes = [rest // k + (1 if i < rest % k else 0) for i in range(k)]
    return [p for s in sizes for p in ((1, 1) if s == 2 else (s,))]


def count(shape: Any) -> tuple[int, int]:
    """(composites, leaves)."""
    if shape == "leaf":
        return 0, 1
    composites, leaves = 1, 0
    for child in shape[1]:
        cc, cl = count(child)
        composites, leaves = composites + cc, leaves + cl
    return composites, leaves


def shape_yaml(name: str, shape: Any, leaf: str) -> str:
    lines = [f"name: {name}", "root:"]

    def emit(node: Any, indent: int, item: bool) -> None:
        pad = " " * indent
        lead = f"{pad}- " if item else pad
        if node == "leaf":
            lines.append(f"{lead}{leaf}")
            return
        kind, children = node
        lines.append(f"{lead}{kind}:")
        for child in children:
            emit(child, indent + (4 if item else 2), True)

    emit(shape, 2, False)
    return "\n".join(lines) + "\n"


def bare_tree(shape: Any, leaf_cls: type) -> py_trees.behaviour.Behaviour:
    ids = itertools.count()

    def make(node: Any) -> py_trees.behaviour.Behaviour:
        name = f"n{next(ids)}"
        if node == "leaf":
            return leaf_cls(name=name)
        kind, children = node
        kids = [make(c) for c in children]
        if kind == "sequence":
            return py_trees.composites.Sequence(name, memory=True, children=kids)
        if kind == "selector":
            return py_trees.composites.Selector(name, memory=True, children=kids)
        return py_trees.composites.Parallel(name, policy=ParallelPolicy.SuccessOnAll(synchronise=True), children=kids)

    return make(shape)


def visited(root: py_trees.behaviour.Behaviour) -> int:
    """Nodes ticked by the last tick(s) from a fresh tree (those no longer INVALID)."""
    return sum(1 for b in root.iterate() if b.status is not Status.INVALID)


def size_of(root: py_trees.behaviour.Behaviour) -> int:
    return sum(1 for _ in root.iterate())


# ---------------------------------------------------------------------------- tick timing


class BenchHost(TreeHost):
    """A TreeHost whose actor leaves, in the runs listed in ``done_runs``, are handed an
    already finished (real) Transaction instead of starting their actor."""

    def __init__(self, rt: Runtime) -> None:
        super().__init__(rt)
        self.finished_txn: Any = None
        self.done_runs: set[int] = set()
        self.real_starts: dict[int, int] = {}  # run id -> actors really started

    def start_actor(self, run, leaf, args, kwargs, on_done):  # type: ignore[override]
        if run.id in self.done_runs:
            return self.finished_txn
        self.real_starts[run.id] = self.real_starts.get(run.id, 0) + 1
        return super().start_actor(run, leaf, args, kwargs, on_done)


def timed_ticks(rt: Runtime, tick: Any, n: int) -> float:
    """Seconds per call of ``tick``, ``n`` calls in one hub callback (every variant, bare or
    ours, is timed on the hub thread with nothing else running in between)."""

    def body() -> float:
        t0 = time.perf_counter()
        for _ in range(n):
            tick()
        return (time.perf_counter() - t0) / n

    gc.collect()
    return rt.run_on_hub(body)


def tick_bench(rt: Runtime, host: BenchHost, folder: Path, n_nodes: int) -> dict[str, Any]:
    shape = make_shape(n_nodes)
    flat = make_shape(n_nodes, kinds=("parallel",))  # every leaf ticked on every tick
    composites, leaves = count(shape)
    trees = {
        f"done_{n_nodes}": (shape, "instant"),
        f"wait_{n_nodes}": (shape, "pending"),
        f"flat_{n_nodes}": (flat, "pending"),
        f"flatdone_{n_nodes}": (flat, "instant"),
    }
    for name, (sh, leaf) in trees.items():
        (folder / f"{name}.yaml").write_text(shape_yaml(name, sh, f"{{do: {leaf}}}"))
        host.load_file(folder / f"{name}.yaml")
    host.finished_txn = rt.run_on_hub(lambda: rt.start("instant"))
    assert host.finished_txn.done

    # Bare py_trees: completing each tick; leaves running; all-parallel with leaves running.
    bare_done = bare_tree(shape, py_trees.behaviours.Success)
    bt_done = py_trees.trees.BehaviourTree(bare_done)
    bare_run = bare_tree(shape, py_trees.behaviours.Running)
    bare_flat = bare_tree(flat, py_trees.behaviours.Running)
    bare_flatdone = bare_tree(flat, py_trees.behaviours.Success)
    # Ours: leaves already done (handed one real finished Transaction, no engine call);
    # instant actor (one engine transaction per leaf per tick); pending transactions.
    run_done = host.prepare(f"done_{n_nodes}")
    run_flatdone = host.prepare(f"flatdone_{n_nodes}")
    host.done_runs = {run_done.id, run_flatdone.id}
    run_inst = host.prepare(f"done_{n_nodes}")
    run_wait = host.prepare(f"wait_{n_nodes}")
    run_flat = host.prepare(f"flat_{n_nodes}")
    # First ticks (untimed): completing trees complete, waiting trees start their actors.
    for root, want in (
        (bare_done, Status.SUCCESS),
        (bare_run, Status.RUNNING),
        (bare_flat, Status.RUNNING),
        (bare_flatdone, Status.SUCCESS),
    ):
        root.tick_once()
        assert root.status is want
    for run, want in (
        (run_done, Status.SUCCESS),
        (run_inst, Status.SUCCESS),
        (run_wait, Status.RUNNING),
        (run_flat, Status.RUNNING),
        (run_flatdone, Status.SUCCESS),
    ):
        assert rt.run_on_hub(run.tick) is want

    # Fairness checks: same size, same nodes ticked.
    assert size_of(bare_done) == size_of(run_done.root) == size_of(run_flat.root) == n_nodes
    v_done, v_run, v_flat = visited(bare_done), visited(bare_run), visited(bare_flat)
    assert visited(run_done.root) == visited(run_inst.root) == v_done
    assert visited(run_wait.root) == v_run and visited(run_flat.root) == v_flat == n_nodes
    assert visited(bare_flatdone) == visited(run_flatdone.root) == n_nodes
    pending = len(rt.transactions())

    n = max(5, int(BATCH_SECONDS / max(timed_ticks(rt, bare_done.tick_once, 20), 1e-7)))
    variants = {
        "bare_done": bare_done.tick_once,
        "bare_done_bt": bt_done.tick,
        "ours_done": run_done.tick,
        "ours_instant": run_inst.tick,
        "bare_run": bare_run.tick_once,
        "ours_run": run_wait.tick,
        "bare_flatdone": bare_flatdone.tick_once,
        "ours_flatdone": run_flatdone.tick,
        "bare_flat": bare_flat.tick_once,
        "ours_flat": run_flat.tick,
    }
    samples: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(REPEATS):  # interleaved, so drift hits every variant alike
        for k, tick in variants.items():
            samples[k].append(timed_ticks(rt, tick, n))
    # Still in the state measured, and the already-done run never called the engine.
    assert rt.run_on_hub(run_done.tick) is Status.SUCCESS and bare_done.status is Status.SUCCESS
    assert rt.run_on_hub(run_flatdone.tick) is Status.SUCCESS
    assert run_done.id not in host.real_starts and run_flatdone.id not in host.real_starts
    inst_starts = host.real_starts[run_inst.id] / run_inst.ticks
    for run in (run_wait, run_flat):
        assert rt.run_on_hub(run.tick) is Status.RUNNING
        assert host.real_starts[run.id] == sum(
            1 for b in run.root.iterate() if b.status is Status.RUNNING and not b.children
        )  # started once, then polled
    for run in (run_done, run_inst, run_wait, run_flat, run_flatdone):
        rt.run_on_hub(run.close)
    return {
        "nodes": n_nodes,
        "composites": composites,
        "leaves": leaves,
        "visited_done": v_done,
        "visited_run": v_run,
        "visited_flat": v_flat,
        "flat_composites": count(flat)[0],
        "ticks_per_batch": n,
        "pending_txns": pending,
        "instant_starts_per_tick": inst_starts,
        "left_txns": len(rt.transactions()),
        **{k: statistics.median(v) * 1e6 for k, v in samples.items()},
    }


# ---------------------------------------------------------------------------- idle cost


class TickCounter(TreeObserver):
    def __init__(self) -> None:
        self.ticks = 0
        self.runs = 0

    def run_started(self, run) -> None:
        self.runs += 1

    def tick(self, run) -> None:
        self.ticks += 1


def idle_bench(folder: Path, max_period: float | None, repeats: int = 5) -> dict[str, Any]:
    (folder / "idle_actor.yaml").write_text(
        f"name: idle_actor\nroot:\n  do: sleep\n  with: {{seconds: {IDLE_SECONDS}}}\n"
    )
    (folder / "idle_wait.yaml").write_text(f"name: idle_wait\nroot:\n  wait: {IDLE_SECONDS}\n")
    out: dict[str, Any] = {}
    with Runtime(watchdog=None) as rt:
        host = register_tree_folder(rt, folder, max_period=max_period)
        for tree in ("idle_actor", "idle_wait"):
            cpu, wall, ticks, virtual = [], [], set(), set()
            for _ in range(repeats):
                counter = TickCounter()
                host.observers[:] = [counter]
                gc.collect()
                v0, w0, c0 = rt.now(), time.perf_counter(), time.process_time()
                rt.call(tree)
                c1, w1, v1 = time.process_time(), time.perf_counter(), rt.now()
                cpu.append(c1 - c0)
                wall.append(w1 - w0)
                ticks.add(counter.ticks)
                virtual.add(round(v1 - v0, 6))
                assert counter.runs == 1
            host.observers.clear()
            out[tree] = {
                "ticks": sorted(ticks),
                "cpu_ms": statistics.median(cpu) * 1e3,
                "wall_ms": statistics.median(wall) * 1e3,
                "virtual_s": sorted(virtual),
            }
    return out


# ---------------------------------------------------------------------------- load time


def load_yaml(n_nodes: int) -> str:
    """A realistic mission of exactly ``n_nodes`` nodes: all composites and some decorators
    around actor calls with arguments and references, set, check and wait leaves."""
    counter = itertools.count()
    kinds = ("sequence", "selector", "parallel", "reactive_sequence", "retry", "timeout", "force_success")

    def make(budget: int) -> Any:
        if budget == 1:
            return "leaf"
        kind = kinds[next(counter) % len(kinds)]
        if kind in ("retry", "timeout", "force_success"):
            return (kind, [make(budget - 1)])
        rest = budget - 1
        if rest <= 6:
            return (kind, ["leaf"] * rest)
        return (kind, [make(s) for s in _split(rest)])

    leaf_no = itertools.count()

    def leaf(i: int) -> str:
        m = i % 5
        if m == 0:
            return f'{{name: call{i}, do: sleep, with: {{seconds: "{{pause}}"}}, out: r{i}}}'
        if m == 1:
            return f'{{set: {{k{i - 1}: {i}, w{i}: [a, "{{pause}}"]}}}}'
        if m == 2:
            return f'{{check: "k{i - 2} >= 0 and limit < 10 or r{i - 2} == null"}}'
        if m == 3:
            return "{do: sleep, with: [0.01]}"
        return 'wait: "{pause}"'

    lines = [
        "name: load_500",
        "doc: generated for bench_trees",
        "inputs:",
        "  pause: {type: float, default: 0.01}",
        "  limit: {type: int, default: 3}",
        "outputs: [k0]",
        "root:",
    ]

    def emit(node: Any, indent: int, item: bool) -> None:
        pad = " " * indent
        lead = f"{pad}- " if item else pad
        inner = indent + (4 if item else 2)
        if node == "leaf":
            lines.append(f"{lead}{leaf(next(leaf_no))}")
            return
        kind, children = node
        if kind in ("retry", "timeout"):
            lines.append(f"{lead}{kind}:")
            param = 'times: "{limit}"' if kind == "retry" else "seconds: 30"
            lines.append(" " * inner + param)
            lines.append(f"{' ' * inner}child:")
            emit(children[0], inner + 2, False)
            return
        if kind == "force_success":
            lines.append(f"{lead}{kind}:")
            emit(children[0], inner, False)
            return
        lines.append(f"{lead}{kind}:")
        for child in children:
            emit(child, inner, True)

    emit(make(n_nodes), 2, False)
    return "\n".join(lines) + "\n"


def load_bench(folder: Path, repeats: int = REPEATS) -> dict[str, Any]:
    path = folder / "load_500.yaml"
    path.write_text(load_yaml(500))
    out: dict[str, Any] = {}
    with Runtime(watchdog=None) as rt:
        rt.add_subsystem("bench", BenchActors)
        mission = read_mission(path)
        out["nodes"] = sum(1 for _ in walk(mission.root))
        kinds = collections.Counter(type(node).__name__ for node in walk(mission.root))
        out["mix"] = ", ".join(f"{k} {v}" for k, v in sorted(kinds.items(), key=lambda kv: -kv[1]))
        out["lines"] = len(path.read_text().splitlines())

        def resolver(name: str) -> Any:
            return rt.run_on_hub(rt.root.resolve, name)

        def parse() -> None:
            read_mission(path)

        def validate() -> None:
            lib = TreeLibrary(resolver=resolver, behaviours=None)
            lib.load_folder(folder)
            lib.check()

        def register() -> None:
            TreeHost(rt).load_folder(folder)

        steps = {"parse": parse, "validate": validate, "register": register}
        times: dict[str, list[float]] = {key: [] for key in steps}
        for fn in steps.values():
            fn()  # warm
        for _ in range(repeats):  # interleaved, like the tick batches
            for key, fn in steps.items():
                gc.collect()
                t0 = time.perf_counter()
                fn()
                times[key].append(time.perf_counter() - t0)
        for key, ts in times.items():
            out[key] = statistics.median(ts) * 1e3
    return out


# ---------------------------------------------------------------------------- report


def verdict(value: float | None, target: float | None) -> str:
    if target is None or value is None:
        return ""
    return "ok" if value <= target else "MISSED"


def main() -> None:
    t_start = time.perf_counter()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        tmpdir = Path(tmp)
        tick_dir, idle_dir, idle_dir2, load_dir = (tmpdir / d for d in ("tick", "idle", "idle_p", "load"))
        for d in (tick_dir, idle_dir, idle_dir2, load_dir):
            d.mkdir()
        with Runtime(watchdog=None) as rt:
            rt.add_subsystem("bench", BenchActors)
            host = BenchHost(rt)
            for n in SIZES:
                results.append(tick_bench(rt, host, tick_dir, n))
        idle = idle_bench(idle_dir, None)
        idle_p = idle_bench(idle_dir2, 1.0, repeats=3)
        load = load_bench(load_dir)

    print(
        "1. Tick overhead vs bare py_trees 2.6 (median of "
        f"{REPEATS} interleaved batches; no visitors, observers or recorder)"
    )
    for r in results:
        print(
            f"\n  {r['nodes']}-node tree: {r['composites']} composites (sequence/selector/parallel), "
            f"{r['leaves']} leaves; {r['ticks_per_batch']} ticks per batch"
        )
        print(
            f"  nodes ticked per tick: {r['visited_done']} when every leaf completes (selectors stop at "
            f"their first success), {r['visited_run']} when leaves run (memory sequences/selectors stop "
            f"at their running child); all-parallel variant ({r['flat_composites']} parallels): "
            f"all {r['visited_flat']}"
        )
        print(f"  {'case':58s} {'us/tick':>9s} {'us/node':>8s} {'ratio':>6s} {'target':>7s}")
        rows = [
            ("done: bare Success leaves, root.tick_once() [baseline]", "bare_done", "visited_done", None, None),
            ("done: bare Success leaves, BehaviourTree.tick()", "bare_done_bt", "visited_done", "bare_done", None),
            (
                "done: actor leaves, actor already done, TreeRun.tick()",
                "ours_done",
                "visited_done",
                "bare_done",
                TICK_TARGET,
            ),
            ("done: actor leaves, instant actor (engine call/leaf)", "ours_instant", "visited_done", "bare_done", None),
            ("done, all-parallel: bare Success leaves [baseline]", "bare_flatdone", "visited_flat", None, None),
            (
                "done, all-parallel: actor leaves, actor already done",
                "ours_flatdone",
                "visited_flat",
                "bare_flatdone",
                TICK_TARGET,
            ),
            ("running: bare Running leaves [baseline]", "bare_run", "visited_run", None, None),
            ("running: actor leaves polling a pending transaction", "ours_run", "visited_run", "bare_run", TICK_TARGET),
            ("running, all-parallel: bare Running leaves [baseline]", "bare_flat", "visited_flat", None, None),
            (
                "running, all-parallel: actor leaves, pending transaction",
                "ours_flat",
                "visited_flat",
                "bare_flat",
                TICK_TARGET,
            ),
        ]
        for name, key, nodes_key, base, target in rows:
            us = r[key]
            ratio = us / r[base] if base else None
            ratio_s = f"{ratio:5.2f}x" if ratio is not None else "     -"
            target_s = f"<= {target}x" if target else "-"
            ok = verdict(ratio, target) if ratio is not None else ""
            print(f"  {name:58s} {us:9.1f} {us / r[nodes_key]:8.2f} {ratio_s:>6s} {target_s:>7s}  {ok}")
        print(
            f"  already-done vs BehaviourTree.tick(): {r['ours_done'] / r['bare_done_bt']:.2f}x; engine calls "
            f"per tick: 0 already-done, {r['instant_starts_per_tick']:.0f} instant; {r['pending_txns']} pending "
            f"transactions while timing 'running', {r['left_txns']} left after closing the runs"
        )

    print(
        f"\n2. Idle cost: one run of a tree waiting {IDLE_SECONDS:.0f} s of virtual time "
        "(median CPU of 5 runs; CPU = time.process_time, all threads)"
    )
    print(f"  {'tree':44s} {'ticks':>6s} {'target':>7s} {'CPU ms':>8s} {'wall ms':>8s} {'virtual s':>9s}")
    for label, data, target in (
        ("do: sleep 60 s (event-driven, default host)", idle["idle_actor"], 2),
        ("wait: 60 s (deadline timer, default host)", idle["idle_wait"], 2),
        ("do: sleep 60 s, max_period=1 s (information)", idle_p["idle_actor"], None),
    ):
        ticks = data["ticks"]
        tick_s = "/".join(str(t) for t in ticks)
        target_s = f"== {target}" if target is not None else "-"
        ok = "" if target is None else ("ok" if ticks == [target] else "MISSED")
        virt = "/".join(f"{v:g}" for v in data["virtual_s"])
        print(
            f"  {label:44s} {tick_s:>6s} {target_s:>7s} {data['cpu_ms']:8.2f} {data['wall_ms']:8.2f} {virt:>9s}  {ok}"
        )

    print(
        f"\n3. Load time of a {load['nodes']}-node mission ({load['lines']} YAML lines; "
        f"median of {REPEATS}; no target in the issue)"
    )
    print(f"  nodes: {load['mix']}")
    print(f"  {'step':58s} {'ms':>8s}")
    print(f"  {'parse only (read_mission: YAML with positions -> model)':58s} {load['parse']:8.1f}")
    print(f"  {'parse + validate (TreeLibrary.load_folder + check)':58s} {load['validate']:8.1f}")
    print(f"  {'parse + validate + register (TreeHost.load_folder)':58s} {load['register']:8.1f}")
    print(f"\n(total bench time {time.perf_counter() - t_start:.0f} s)")


if __name__ == "__main__":
    main()
