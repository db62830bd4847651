"""`actorbt eval --resume` runs only the episodes its CSV lacks and never mixes in another
run's; the progress shows successes so far and the time left, on one line on a terminal and
a line per episode in a log."""

from __future__ import annotations

import csv
import io
import json

import pytest

import demo.evaluate as evaluation
from demo.episode import Episode
from demo.evaluate import EvalError, read_csv, write_csv


@pytest.fixture
def runner(monkeypatch):
    """Episodes are not run: each job is recorded and succeeds, with a wall time from
    ``walls`` (seed -> s)."""

    class Runner:
        ran: list[tuple] = []
        walls: dict[int, float] = {}

        def __call__(self, job):
            tree, world, seed, category, out = job[:5]
            self.ran.append((tree, world, seed, category))
            return Episode(
                tree,
                world,
                seed,
                category,
                success=seed % 2 == 0,
                tree_status="SUCCESS",
                sim_time=30.0,
                wall_time=self.walls.get(seed, 1.0),
                trace=str(out / "trace.jsonl"),
            )

    r = Runner()
    r.ran, r.walls = [], {}
    monkeypatch.setattr(evaluation, "_one", r)
    return r


def finished(seed, category, **kw) -> Episode:
    return Episode(
        "reset", "open_floor", seed, category, success=True, tree_status="SUCCESS", sim_time=12.5, wall_time=4.0, **kw
    )


def test_resume_runs_only_the_episodes_the_csv_lacks(tmp_path, runner):
    write_csv(
        [finished(1, "can", grasp_tilt_deg=3.2, pushed=["box_1"], objects=3, placed=2)], tmp_path / "episodes.csv"
    )
    out = io.StringIO()
    eps = evaluation.evaluate(
        "reset", 3, "open_floor", "can", out_dir=tmp_path, progress=out, config=object(), resume=True
    )
    assert runner.ran == [("reset", "open_floor", 0, "can"), ("reset", "open_floor", 2, "can")]
    assert "resuming: 1 of 3 episodes kept" in out.getvalue() and "2 to run" in out.getvalue()
    assert [e.seed for e in eps] == [0, 1, 2]
    rows = list(csv.DictReader(open(tmp_path / "episodes.csv")))
    assert [(r["seed"], r["sim_time"]) for r in rows] == [("0", "30.00"), ("1", "12.50"), ("2", "30.00")]
    kept = eps[1]  # the kept row as it was
    assert (kept.sim_time, kept.grasp_tilt_deg, kept.pushed, kept.objects, kept.placed) == (12.5, 3.2, ["box_1"], 3, 2)

    runner.ran.clear()  # all there: nothing to run
    again = evaluation.evaluate(
        "reset", 3, "open_floor", "can", out_dir=tmp_path, progress=None, config=object(), resume=True
    )
    assert runner.ran == [] and [e.seed for e in again] == [0, 1, 2]


def test_resume_keeps_other_seeds_rows_in_the_csv_but_not_in_the_result(tmp_path, runner):
    write_csv([finished(0, "can"), finished(7, "can"), finished(0, "bottle")], tmp_path / "episodes.csv")
    eps = evaluation.evaluate(
        "reset", 2, "open_floor", "can", out_dir=tmp_path, progress=None, config=object(), resume=True
    )
    assert runner.ran == [("reset", "open_floor", 1, "can")]
    assert [(e.seed, e.category) for e in eps] == [(0, "can"), (1, "can")]
    assert [(e.seed, e.category) for e in read_csv(tmp_path / "episodes.csv")] == [
        (0, "bottle"),
        (0, "can"),
        (1, "can"),
        (7, "can"),
    ]


@pytest.mark.parametrize("tree, world", [("bt_pick_place", "open_floor"), ("reset", "house")])
def test_resume_refuses_another_runs_csv(tmp_path, runner, tree, world):
    write_csv([finished(0, "can")], tmp_path / "episodes.csv")
    with pytest.raises(EvalError, match=f"holds episodes of reset in open_floor, not of {tree} in {world}"):
        evaluation.evaluate(tree, 2, world, "can", out_dir=tmp_path, progress=None, config=object(), resume=True)
    assert runner.ran == []
    assert len(read_csv(tmp_path / "episodes.csv")) == 1  # left as it was


def test_resume_refuses_episodes_run_with_other_map_settings(tmp_path, runner):
    evaluation.evaluate("reset", 1, "open_floor", "can", out_dir=tmp_path, progress=None, config=object())
    assert json.loads((tmp_path / "eval.json").read_text())["mapping"] is False
    with pytest.raises(EvalError, match="resume with the same --no-map"):
        evaluation.evaluate(
            "reset", 2, "open_floor", "can", out_dir=tmp_path, progress=None, config=object(), resume=True, mapping=True
        )
    assert runner.ran == [("reset", "open_floor", 0, "can")]


def test_a_run_without_resume_says_it_rewrites_the_csv(tmp_path, runner):
    write_csv([finished(0, "can")], tmp_path / "episodes.csv")
    out = io.StringIO()
    evaluation.evaluate("reset", 1, "open_floor", "can", out_dir=tmp_path, progress=out, config=object())
    assert "is rewritten (--resume keeps its episodes)" in out.getvalue()
    assert runner.ran == [("reset", "open_floor", 0, "can")]


def test_a_log_gets_a_line_per_episode_with_successes_and_time_left(tmp_path, runner):
    runner.walls = {0: 10.0, 1: 20.0, 2: 90.0}
    out = io.StringIO()  # not a terminal
    evaluation.evaluate("reset", 4, "open_floor", "can", out_dir=tmp_path, progress=out, config=object())
    lines = out.getvalue().splitlines()
    assert len(lines) == 4 and "\r" not in out.getvalue()
    assert lines[0].startswith("[1/4] seed 0 can: success (30 s sim, 10 s wall); 1 succeeded (100%)")
    assert lines[0].endswith("~30 s left")  # median 10 s x 3 to go, one at a time
    assert lines[1].startswith("[2/4] seed 1 can: FAILURE at ?") and "1 succeeded (50%)" in lines[1]
    assert lines[1].endswith("~30 s left")  # median 15 s x 2
    assert lines[2].endswith("~20 s left")  # median 20 s x 1
    assert lines[3].endswith("~0 s left") and "2 succeeded (50%)" in lines[3]


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_gets_one_line_that_updates(tmp_path, runner):
    out = Terminal()
    evaluation.evaluate("reset", 3, "open_floor", "can", out_dir=tmp_path, progress=out, config=object())
    text = out.getvalue()
    assert text.count("\n") == 1 and text.endswith("\n")
    updates = text.rstrip("\n").split("\r")[1:]
    assert len(updates) == 4  # before the first episode, then after each
    assert "0/3 episodes, 0 succeeded, 0 s, time left ?" in updates[0]
    assert "[" + "#" * 20 + " " * 10 + "] 2/3 episodes, 1 succeeded (50%)" in updates[2]
    assert "3/3 episodes, 2 succeeded (67%)" in updates[3]


def test_the_time_left_counts_the_episodes_running_at_once():
    bar = evaluation.Progress(None, total=10)
    bar.start(4, "", [])
    for wall in (60.0, 100.0, 80.0):
        bar.episode(Episode("t", "w", 0, "can", wall_time=wall), [])
    assert bar.time_left(3) == 80.0 * 2  # 7 to go, 4 at once: 2 rounds of the median
    assert bar.time_left(10) == 0.0
    assert evaluation._duration(80 * 60) == "80 min" and evaluation._duration(2 * 3600 + 300) == "2 h 05 min"


def test_the_csv_reads_back_as_it_was_written(tmp_path):
    eps = [
        finished(
            3,
            "bottle",
            failed_node="pick",
            reason='said "no", twice',
            pose="lying",
            grasp_tilt_deg=float("nan"),
            pushed=["a", "b"],
            objects=None,
        ),
        Episode("reset", "open_floor", 4, "can"),
    ]
    write_csv(eps, tmp_path / "a.csv")
    write_csv(read_csv(tmp_path / "a.csv"), tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_a_csv_that_is_not_an_episodes_csv_is_refused(tmp_path):
    (tmp_path / "episodes.csv").write_text("a,b\n1,2\n")
    with pytest.raises(EvalError, match="not an episodes.csv of actorbt eval"):
        read_csv(tmp_path / "episodes.csv")


def test_an_episode_error_that_cannot_be_pickled_comes_back_as_its_message(monkeypatch):
    """A worker's error goes back to the pool pickled: one whose class takes other
    arguments than its message would not unpickle, and the pool would wait forever."""
    from bt_engine.errors import UnknownActorError

    def one(job):
        raise UnknownActorError("nosuchtree", ["survey"])

    monkeypatch.setattr(evaluation, "_one", one)
    with pytest.raises(EvalError, match="seed 3 \\(can\\): UnknownActorError: unknown actor 'nosuchtree'"):
        evaluation._run_job(("nosuchtree", "open_floor", 3, "can"))

    def two(job):
        raise ValueError("plain")  # one that pickles is raised as it is

    monkeypatch.setattr(evaluation, "_one", two)
    with pytest.raises(ValueError, match="plain"):
        evaluation._run_job(("t", "w", 0, "can"))
