"""`actorbt eval --ray`: the same episodes as Ray tasks give the same rows as --jobs; without
Ray installed, --ray says how to install it."""

from __future__ import annotations

import csv
import sys
import time

import pytest

import demo.evaluate as evaluation
from bt_engine.errors import ActorbtError

#: what an episode's row must agree on, whoever ran it (not its times or trace path)
SAME = ("tree", "world", "seed", "category", "success", "tree_status", "failed_node", "reason")


def rows(path) -> list[tuple]:
    return [tuple(r[k] for k in SAME) for r in csv.DictReader(open(path))]


def test_ray_runs_the_same_episodes_as_jobs(tmp_path):
    ray = pytest.importorskip(
        "ray", reason="Ray is not installed: pip install 'actorbt[cluster]' (or the test extra) to run the --ray test"
    )
    # reset (open the gripper, fold the arm, drive home) in open_floor: about a second
    # each; "mixed" asks a different category per seed
    t0 = time.perf_counter()
    by_jobs = evaluation.evaluate("reset", 2, "open_floor", "mixed", jobs=2, out_dir=tmp_path / "jobs", progress=None)
    t_jobs = time.perf_counter() - t0
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        t0 = time.perf_counter()
        by_ray = evaluation.evaluate(
            "reset", 2, "open_floor", "mixed", jobs=1, out_dir=tmp_path / "ray", progress=None, ray=True
        )
        t_ray = time.perf_counter() - t0
        assert ray.is_initialized()  # a Ray the caller started is left to the caller
    finally:
        ray.shutdown()
    print(f"--jobs 2: {t_jobs:.1f} s, --ray (2 CPUs): {t_ray:.1f} s")
    assert len(by_jobs) == 2 and all(e.success for e in by_jobs), [e.reason for e in by_jobs]
    assert rows(tmp_path / "ray" / "episodes.csv") == rows(tmp_path / "jobs" / "episodes.csv")
    assert [(e.seed, e.category, e.success, e.tree_status, e.failed_node) for e in by_ray] == [
        (e.seed, e.category, e.success, e.tree_status, e.failed_node) for e in by_jobs
    ]
    assert [e.seed for e in by_ray] == [0, 1] and len({e.category for e in by_ray}) == 2
    for e in by_ray:  # each wrote its trace where the driver said
        assert e.trace.startswith(str((tmp_path / "ray").absolute())), e.trace
        assert (tmp_path / "ray" / f"{e.category}_seed{e.seed}" / "trace.jsonl").exists()
    assert evaluation._app is None  # the episodes ran in Ray's workers, not here


def test_without_ray_installed_ray_says_how_to_install_it(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    ran = []
    monkeypatch.setattr(evaluation, "_one", ran.append)
    with pytest.raises(ActorbtError, match=r"pip install 'actorbt\[cluster\]'"):
        evaluation.evaluate("reset", 2, "open_floor", "can", out_dir=tmp_path, progress=None, config=object(), ray=True)
    assert ran == [] and not (tmp_path / "episodes.csv").exists()
