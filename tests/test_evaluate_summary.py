"""demo.evaluate: the benchmarks' success summary (one line per group) and their CSV."""

import csv
import io

import pytest

import demo.evaluate as evaluation
from demo.episode import Episode
from demo.evaluate import print_pose_table, print_rates


def ep(success: bool, sim: float, wall: float) -> Episode:
    return Episode("bt_pick_place", "house", 0, "can", success=success, sim_time=sim, wall_time=wall)


def test_rates_medians_and_targets():
    out = io.StringIO()
    print_rates(
        [("can", [ep(True, 100, 20), ep(True, 120, 30), ep(False, 90, 10)]), ("bottle", [ep(True, 100, 5)] * 4)],
        "category",
        0.9,
        target_rtf=10.0,
        out=out,
    )
    lines = out.getvalue().strip().splitlines()
    assert lines[0].split()[:3] == ["category", "success", "rate"]
    can, bottle = lines[1], lines[2]
    assert "2/3" in can and "66.7%" in can and "5.0x" in can and "20.0 s" in can and "100.0 s" in can
    assert "target >= 90%: MISSED" in can and "RTF >= 10x: MISSED" in can
    assert "4/4" in bottle and "100.0%" in bottle and "20.0x" in bottle
    assert "target >= 90%: ok" in bottle and "RTF >= 10x: ok" in bottle


def test_successes_per_category_and_pose():
    def posed(cat, success, pose):
        return Episode("bt_pick_place", "house_hard", 0, cat, success=success, pose=pose)

    out = io.StringIO()
    print_pose_table(
        [
            posed("can", True, "upright"),
            posed("can", False, "upright"),
            posed("can", True, "lying"),
            posed("carton", False, ""),
        ],
        out,
    )
    head, *rows = out.getvalue().strip().splitlines()
    assert head.split() == ["by", "pose", "upright", "lying", "tilted", "none"]
    assert rows[0].split() == ["can", "1/2", "1/1", "-", "-"]
    assert rows[1].split() == ["carton", "-", "-", "-", "0/1"]  # no pick was tried


def test_a_run_cut_off_keeps_the_episodes_it_finished_in_its_csv(tmp_path, monkeypatch):
    def one(seed):
        if seed == 3:
            raise KeyboardInterrupt  # the run is stopped during its third episode
        return Episode("bt_pick_place", "house", seed, "can", success=seed == 1, sim_time=10.0)

    monkeypatch.setattr(evaluation, "_jobs", lambda tree, world, seeds, first, *rest: list(range(first, first + seeds)))
    monkeypatch.setattr(evaluation, "_one", one)
    with pytest.raises(KeyboardInterrupt):
        evaluation.evaluate(
            "bt_pick_place", 4, "house", "can", jobs=1, out_dir=tmp_path, first_seed=1, progress=None, config=object()
        )
    rows = list(csv.DictReader(open(tmp_path / "episodes.csv")))
    assert [(r["seed"], r["success"]) for r in rows] == [("1", "True"), ("2", "False")]
