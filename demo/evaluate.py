"""`actorbt eval`: a mission over many seeds, each in a fresh world, with a table and CSV."""

from __future__ import annotations

import collections
import csv
import json
import math
import multiprocessing
import pathlib
import pickle
import statistics
import sys
import threading
import time
from dataclasses import asdict
from typing import TextIO

import categories
from bt_cli import App, Config
from bt_engine.errors import ActorbtError

from .episode import Episode, episode_app, run_episode

CSV_FIELDS = [
    "tree",
    "world",
    "seed",
    "category",
    "success",
    "tree_status",
    "failed_node",
    "reason",
    "placed_object",
    "pose",
    "support",
    "sim_time",
    "wall_time",
    "loc_rmse_m",
    "loc_max_m",
    "grasp_tilt_deg",
    "pushed",
    "objects",
    "placed",
    "trace",
    "target",
    "end_pose",
    "end_support",
    "tree_failure",
]

#: each episode's live progress, in its folder
PROGRESS_LOG = "progress.log"

#: this process's App (one per worker, so each skipped tree is reported once per process)
_app: App | None = None


def _one(job: tuple) -> Episode:
    global _app
    tree, world, seed, category, out, config, locations, mapping = job
    if _app is None or _app.cfg != config:
        _app = episode_app(world, seed, config=config)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    # the episode's progress, which the evaluation's heartbeat reads (Progress.watch)
    with open(out / PROGRESS_LOG, "w", encoding="utf-8") as log:
        return run_episode(
            tree, world, seed, category, out_dir=out, app=_app, locations=locations, mapping=mapping, progress=log
        )


def _run_job(job: tuple) -> Episode:
    """:func:`_one` in a worker process or Ray task: an error that would not survive the
    trip back (an exception class whose ``__init__`` takes other arguments than its message
    breaks multiprocessing's result thread, and the pool waits forever) comes back as an
    :class:`EvalError` with its type and message."""
    try:
        return _one(job)
    except Exception as exc:
        try:
            pickle.loads(pickle.dumps(exc))
        except Exception:
            raise EvalError(f"seed {job[2]} ({job[3]}): {type(exc).__name__}: {exc}") from None
        raise


def _jobs(
    tree: str,
    world: str,
    seeds: int,
    first_seed: int,
    category: str,
    out: pathlib.Path,
    config: Config | None = None,
    locations: str | None = None,
    mapping: bool = False,
) -> list[tuple]:
    cats = categories.names() if category == "mixed" else [category]
    jobs = []
    for i in range(seeds):
        seed = first_seed + i
        # mixed: alternate which category is asked for, so the table shows every strategy
        cat = cats[i % len(cats)]
        jobs.append((tree, world, seed, cat, out / f"{cat}_seed{seed}", config, locations, mapping))
    return jobs


class EvalError(ActorbtError):
    """An evaluation that cannot start as asked: ``--resume`` on another run's CSV."""


def evaluate(
    tree: str,
    seeds: int,
    world: str = "house",
    category: str = "mixed",
    jobs: int = 1,
    out_dir: str | pathlib.Path = "out/eval",
    first_seed: int = 0,
    progress: TextIO | None = sys.stdout,
    config: Config | None = None,
    locations: str | None = None,
    mapping: bool = False,
    resume: bool = False,
    ray: bool | str | None = None,
    ray_runtime_env: dict | None = None,
) -> list[Episode]:
    """Run ``tree`` for ``seeds`` seeds; returns the episodes in seed order. ``locations``:
    a locations YAML for a world built from a map_server map (see sim/map_world.py);
    ``mapping``: the world has no map server, the robot maps it (see :func:`run_episode`).

    Each episode's runtime is built from ``config`` (actorbt.yaml; by default the
    nearest one), as ``actorbt`` builds every runtime: see :func:`run_episode`.

    ``out_dir/episodes.csv`` is rewritten after every episode, so a run cut off keeps what it
    finished. ``resume``: keep the episodes that CSV already has (same tree and world, the
    same seed and category) and run only the others; rows of other seeds or categories stay
    in the CSV (not in the returned list); a CSV of another tree, world or map settings is an
    :class:`EvalError`. ``jobs``: episodes at once, each in its own process on this machine.
    ``ray``: run them as Ray tasks instead (``True``: ``ray.init()``; a string: the cluster's
    address), with ``ray_runtime_env`` for ``ray.init``; see :mod:`demo.eval_ray`.
    ``progress`` gets one line that updates on a terminal, a line per episode otherwise.
    """
    if ray:
        from .eval_ray import _ray

        _ray()  # not installed: say so before anything runs
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if config is None:
        config = episode_app(world, first_seed).cfg
    work = _jobs(tree, world, seeds, first_seed, category, out, config, locations, mapping)
    total = len(work)
    csv_path, settings = out / "episodes.csv", out / SETTINGS
    kept: list[Episode] = []
    others: list[Episode] = []  # rows of the CSV this run does not ask for: kept in the CSV
    note = ""
    if resume:
        previous = _resumable(csv_path, tree, world, locations, mapping)
        wanted = {(job[2], job[3]) for job in work}
        kept = [e for e in previous if (e.seed, e.category) in wanted]
        others = [e for e in previous if (e.seed, e.category) not in wanted]
        done = {(e.seed, e.category) for e in kept}
        work = [job for job in work if (job[2], job[3]) not in done]
        note = (
            f"resuming: {len(kept)} of {total} episodes kept from {csv_path}, {len(work)} to run"
            if csv_path.exists()
            else f"resuming: no {csv_path} yet, {len(work)} episodes to run"
        )
        if others:
            note += f" ({len(others)} other rows stay in the CSV)"
    elif csv_path.exists():
        note = f"{csv_path} is rewritten (--resume keeps its episodes)"
    episodes: list[Episode] = list(kept)
    bar = Progress(progress, total)
    bar.watch(work, episodes)

    def save() -> None:  # the CSV so far: a run cut off keeps the episodes it finished
        write_csv(sorted(episodes + others, key=_order), csv_path)
        settings.write_text(
            json.dumps({"tree": tree, "world": world, "locations": locations, "mapping": mapping}, indent=1) + "\n"
        )

    def finished(ep: Episode) -> None:
        with bar.lock:
            episodes.append(ep)
        save()
        bar.episode(ep, episodes)

    try:
        if ray and work:
            from .eval_ray import RayRunner

            # on a cluster the traces are written on the node that ran the episode, so at
            # an absolute path (that of this machine's --out)
            work = [job[:4] + (pathlib.Path(job[4]).absolute(),) + job[5:] for job in work]
            with RayRunner(ray, ray_runtime_env) as runner:
                bar.start(runner.slots, f"{runner.describe()}; {note}" if note else runner.describe(), episodes)
                for ep in runner.run(work, _run_job):
                    finished(ep)
        else:
            bar.start(max(1, min(jobs, len(work))), note, episodes)
            if jobs > 1 and len(work) > 1:
                ctx = multiprocessing.get_context("spawn")  # each worker its own runtime and sim
                with ctx.Pool(min(jobs, len(work))) as pool:
                    for ep in pool.imap_unordered(_run_job, work):
                        finished(ep)
            else:
                for job in work:
                    finished(_one(job))
    finally:  # end the progress line, also when an episode could not start
        bar.end()
    episodes.sort(key=_order)
    save()
    return episodes


def _order(e: Episode) -> tuple:
    return (e.seed, e.category)


class Progress:
    """The progress of an evaluation on ``out``: episodes done, successes so far and the time
    left (the median wall time of an episode, times the rounds of ``slots`` episodes still to
    run). On a terminal one line that updates; otherwise (a CI log, a file) a line per episode."""

    #: [s] of wall time without a line after which the running episodes are told
    HEARTBEAT = 10.0

    def __init__(self, out: TextIO | None, total: int) -> None:
        self.out, self.total = out, total
        isatty = getattr(out, "isatty", None)
        self.tty = bool(isatty and isatty())
        self.slots = 1
        self.t0 = time.perf_counter()
        self._width = 0
        self._walls: list[float] = []
        self.lock = threading.Lock()
        self._said = time.monotonic()
        self._stop = threading.Event()
        self._watcher: threading.Thread | None = None

    def watch(self, work: list[tuple], episodes: list[Episode]) -> None:
        """Every HEARTBEAT seconds without a line, tell what the running episodes of ``work``
        (the jobs) are doing: the last line of each one's progress log."""
        if self.out is None or not work:
            return
        folders = {pathlib.Path(job[4]): f"seed {job[2]} {job[3]}" for job in work}

        def loop() -> None:
            while not self._stop.wait(min(1.0, self.HEARTBEAT)):
                if time.monotonic() - self._said >= self.HEARTBEAT:
                    with self.lock:
                        done = {(e.seed, e.category) for e in episodes}
                        self._heartbeat(folders, done, episodes)

        self._watcher = threading.Thread(target=loop, name="eval-heartbeat", daemon=True)
        self._watcher.start()

    def _heartbeat(self, folders: dict[pathlib.Path, str], done: set, episodes: list[Episode]) -> None:
        assert self.out is not None  # watch() starts the heartbeat only with an out
        running = []
        for folder, label in folders.items():
            seed, category = label.split()[1:3]
            if (int(seed), category) in done:
                continue
            last = _last_line(folder / PROGRESS_LOG)
            if last is not None:
                running.append(f"{label}: {last or 'starting'}")
        if self.tty:
            self._line(episodes)
        else:
            self.out.write(
                f"[{len(episodes)}/{self.total}] {self.summary(episodes)}; running: "
                f"{' | '.join(running) or 'starting'}\n"
            )
        self.out.flush()
        self._said = time.monotonic()

    def start(self, slots: int, note: str, episodes: list[Episode]) -> None:
        self.slots = max(1, slots)
        self.t0 = time.perf_counter()
        if self.out is None:
            return
        if note:
            self.out.write(note + "\n")
        if self.tty:
            self._line(episodes)
        self.out.flush()

    def episode(self, ep: Episode, episodes: list[Episode]) -> None:
        self._walls.append(ep.wall_time)
        self._said = time.monotonic()
        if self.out is None:
            return
        with self.lock:
            if self.tty:
                self._line(episodes)
            else:
                verdict = "success" if ep.success else f"FAILURE at {ep.failed_node or '?'}"
                self.out.write(
                    f"[{len(episodes)}/{self.total}] seed {ep.seed} {ep.category}: {verdict} "
                    f"({ep.sim_time:.0f} s sim, {ep.wall_time:.0f} s wall); {self.summary(episodes)}\n"
                )
            self.out.flush()

    def end(self) -> None:
        self._stop.set()
        if self._watcher is not None:
            self._watcher.join()
        if self.out is not None and self.tty:
            self.out.write("\n")
            self.out.flush()

    def time_left(self, done: int) -> float | None:
        """[s] the episodes still to run, in rounds of ``slots``, times the median wall time
        of the episodes this run finished; None before the first."""
        if not self._walls:
            return None
        left = self.total - done
        return statistics.median(self._walls) * math.ceil(left / self.slots)

    def summary(self, episodes: list[Episode]) -> str:
        n, ok = len(episodes), sum(e.success for e in episodes)
        rate = f" ({100 * ok / n:.0f}%)" if n else ""
        left = self.time_left(n)
        eta = "time left ?" if left is None and n < self.total else f"~{_duration(left or 0)} left"
        return f"{ok} succeeded{rate}, {_duration(time.perf_counter() - self.t0)}, {eta}"

    def _line(self, episodes: list[Episode]) -> None:
        assert self.out is not None  # a tty is an out
        n = len(episodes)
        bar = "#" * int(30 * n / self.total) if self.total else ""
        text = f"\r[{bar:<30}] {n}/{self.total} episodes, {self.summary(episodes)}"
        self.out.write(text.ljust(self._width))  # blanks what a longer line left
        self._width = len(text)


def _last_line(path: pathlib.Path) -> str | None:
    """The last line of a text file ("" when empty), None when there is none."""
    try:
        with open(path, "rb") as f:
            f.seek(0, 2)
            f.seek(max(0, f.tell() - 400))
            lines = f.read().decode("utf-8", "replace").splitlines()
    except OSError:
        return None
    return lines[-1].strip() if lines else ""


def _duration(s: float) -> str:
    if s < 90:
        return f"{s:.0f} s"
    if s < 90 * 60:
        return f"{s / 60:.0f} min"
    return f"{int(s // 3600)} h {int(s % 3600 // 60):02d} min"


#: the settings of the run whose episodes are in out/episodes.csv (what --resume checks)
SETTINGS = "eval.json"


def _resumable(csv_path: pathlib.Path, tree: str, world: str, locations: str | None, mapping: bool) -> list[Episode]:
    """The episodes of ``csv_path`` that a run of ``tree`` in ``world`` may keep: all of them,
    or an :class:`EvalError` if they are another run's (another tree, world, locations or
    mapping), which must not be mixed in."""
    if not csv_path.exists():
        return []
    previous = read_csv(csv_path)
    theirs = sorted({(e.tree, e.world) for e in previous})
    if any(t != (tree, world) for t in theirs):
        runs = ", ".join(f"{t} in {w}" for t, w in theirs)
        raise EvalError(
            f"--resume: {csv_path} holds episodes of {runs}, not of {tree} in {world}; "
            f"resume with the same tree and --world, or give another --out"
        )
    settings = csv_path.with_name(SETTINGS)
    if settings.exists():
        was = json.loads(settings.read_text())
        for key, now in (("locations", locations), ("mapping", mapping)):
            if was.get(key, now) != now:
                flag = "--locations" if key == "locations" else "--no-map"
                raise EvalError(
                    f"--resume: the episodes in {csv_path} ran with {key} {was[key]!r}, "
                    f"this run with {now!r}; resume with the same {flag}, or give another --out"
                )
    return previous


def read_csv(path: str | pathlib.Path) -> list[Episode]:
    """The episodes of an episodes.csv :func:`write_csv` wrote (the columns it has; no
    traces, paths or results)."""

    def num(text: str | None) -> float:
        return float(text) if text not in (None, "") else float("nan")

    def count(text: str | None) -> int | None:
        return int(text) if text not in (None, "", "None") else None

    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        missing = {"tree", "world", "seed", "category", "success"} - set(reader.fieldnames or ())
        if missing:
            raise EvalError(f"{path} is not an episodes.csv of actorbt eval: no {', '.join(sorted(missing))} column")
        rows = list(reader)
    episodes = {}
    for r in rows:
        e = Episode(
            r["tree"],
            r["world"],
            int(r["seed"]),
            r["category"],
            success=r["success"] == "True",
            tree_status=r.get("tree_status", ""),
            failed_node=r.get("failed_node", ""),
            reason=r.get("reason", ""),
            placed_object=r.get("placed_object", ""),
            pose=r.get("pose", ""),
            support=r.get("support", ""),
            sim_time=num(r.get("sim_time")),
            wall_time=num(r.get("wall_time")),
            loc_rmse_m=num(r.get("loc_rmse_m")),
            loc_max_m=num(r.get("loc_max_m")),
            grasp_tilt_deg=num(r.get("grasp_tilt_deg")),
            pushed=(r.get("pushed") or "").split(),
            objects=count(r.get("objects")),
            placed=count(r.get("placed")),
            trace=r.get("trace", ""),
            target=r.get("target", ""),
            end_pose=r.get("end_pose", ""),
            end_support=r.get("end_support", ""),
            tree_failure=r.get("tree_failure", ""),
        )
        episodes[e.tree, e.world, e.seed, e.category] = e  # a row given twice: the last
    return list(episodes.values())


def write_csv(episodes: list[Episode], path: pathlib.Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, CSV_FIELDS)
        w.writeheader()
        for e in episodes:
            row = {k: v for k, v in asdict(e).items() if k in CSV_FIELDS}
            row["sim_time"] = f"{e.sim_time:.2f}"
            row["wall_time"] = f"{e.wall_time:.2f}"
            row["loc_rmse_m"] = f"{e.loc_rmse_m:.4f}"
            row["loc_max_m"] = f"{e.loc_max_m:.4f}"
            row["grasp_tilt_deg"] = f"{e.grasp_tilt_deg:.1f}"
            row["pushed"] = " ".join(e.pushed)
            w.writerow(row)


def print_table(episodes: list[Episode], out: TextIO = sys.stdout) -> None:
    by_cat: dict[str, list[Episode]] = collections.defaultdict(list)
    for e in episodes:
        by_cat[e.category].append(e)
    out.write(
        f"\n{'category':10s} {'episodes':>8s} {'success':>8s} {'rate':>7s} "
        f"{'sim s (median)':>15s} {'wall s (median)':>16s} {'x real time':>12s} "
        f"{'loc rms cm':>11s} {'loc max cm':>11s} {'tilt deg':>9s}\n"
    )
    for cat, eps in sorted(by_cat.items()) + [("all", episodes)]:
        ok = sum(e.success for e in eps)
        rms = [e.loc_rmse_m for e in eps if e.loc_rmse_m == e.loc_rmse_m]
        worst = [e.loc_max_m for e in eps if e.loc_max_m == e.loc_max_m]
        tilts = [e.grasp_tilt_deg for e in eps if e.grasp_tilt_deg == e.grasp_tilt_deg]
        out.write(
            f"{cat:10s} {len(eps):8d} {ok:8d} {100 * ok / len(eps):6.1f}% "
            f"{statistics.median(e.sim_time for e in eps):15.1f} "
            f"{statistics.median(e.wall_time for e in eps):16.1f} "
            f"{statistics.median(e.realtime_factor for e in eps):12.1f} "
            f"{100 * statistics.median(rms) if rms else float('nan'):11.1f} "
            f"{100 * max(worst) if worst else float('nan'):11.1f} "
            f"{statistics.median(tilts) if tilts else float('nan'):9.1f}\n"
        )
    if any(e.pose for e in episodes):
        print_pose_table(episodes, out)
    # (objects, placed) of the tidy-ups; an episode sets both (a hand-edited CSV may not)
    tidy = [(e.objects, e.placed) for e in episodes if e.objects is not None and e.placed is not None]
    if tidy:
        total, placed = sum(o for o, _ in tidy), sum(p for _, p in tidy)
        out.write(
            f"\nobjects where they belong: {placed} of {total} "
            f"({100 * placed / total if total else float('nan'):.1f}%)\n"
        )
    pushed = [e for e in episodes if e.pushed]
    if pushed:
        out.write(
            f"\nepisodes in which the robot pushed objects it did not pick: {len(pushed)} of "
            f"{len(episodes)} ({sum(len(e.pushed) for e in pushed)} objects)\n"
        )
    failures = collections.Counter(e.failed_node or "?" for e in episodes if not e.success)
    if failures:
        out.write("\nfailures by node:\n")
        for node, n in failures.most_common():
            out.write(f"  {n:3d}  {node}\n")
        out.write("\nfailed episodes:\n")
        for e in episodes:
            if not e.success:
                out.write(f"  seed {e.seed:3d} {e.category:7s} {e.failed_node}: {e.reason[:150]}\n")


def print_pose_table(episodes: list[Episode], out: TextIO = sys.stdout) -> None:
    """Successes per category and the pose its object had in the world (the one placed,
    else the one the last pick went for; "none": no pick was tried)."""
    poses = ("upright", "lying", "tilted", "none")
    cells: dict[tuple[str, str], list[bool]] = collections.defaultdict(list)
    for e in episodes:
        cells[e.category, e.pose or "none"].append(e.success)
    out.write(f"\n{'by pose':10s}" + "".join(f"{p:>10s}" for p in poses) + "\n")
    for cat in sorted({e.category for e in episodes}):
        row = [cells.get((cat, p), []) for p in poses]
        out.write(f"{cat:10s}" + "".join(f"{f'{sum(r)}/{len(r)}' if r else '-':>10s}" for r in row) + "\n")


def print_rates(
    rows: list[tuple[str, list[Episode]]],
    label: str,
    target_rate: float,
    target_rtf: float | None = None,
    out: TextIO = sys.stdout,
) -> None:
    """One line per (name, episodes): successes, rate, median real-time factor, wall and
    sim time per episode, and the targets met or MISSED (the benchmarks' summary)."""
    width = max([8, len(label)] + [len(name) for name, _ in rows])
    print(
        f"\n{label:{width}s} {'success':>12s} {'rate':>7s} {'RTF median':>11s} "
        f"{'wall/episode':>13s} {'sim/episode':>12s}",
        file=out,
    )
    for name, eps in rows:
        n, ok = len(eps), sum(e.success for e in eps)
        rtf = statistics.median(e.realtime_factor for e in eps)
        line = (
            f"{name:{width}s} {ok:5d}/{n:<6d} {100 * ok / n:6.1f}% {rtf:10.1f}x "
            f"{statistics.median(e.wall_time for e in eps):11.1f} s "
            f"{statistics.median(e.sim_time for e in eps):10.1f} s   "
            f"target >= {target_rate:.0%}: {'ok' if ok / n >= target_rate else 'MISSED'}"
        )
        if target_rtf is not None:
            line += f"; RTF >= {target_rtf:g}x: {'ok' if rtf >= target_rtf else 'MISSED'}"
        print(line, file=out)
