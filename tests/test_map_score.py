"""Scoring a built map (sim/map_score.py, `actorbt map score`): alignment over x, y, yaw,
then precision and recall of occupied cells within 10 cm."""

from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pytest

from sim.gridmap import GridMap, write_pgm_yaml
from sim.map_score import Alignment, score_maps, truth_grid

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def truth() -> GridMap:
    return truth_grid("house", 0)  # the lidar's slice of the house


def resample(truth: GridMap, pose, shape=(440, 440), origin=(-11.0, -11.0)) -> GridMap:
    """``truth`` seen from a frame at ``pose`` (x, y, yaw) in it, as a map built from a
    robot starting there would be: each new cell takes the value of the truth cell under it."""
    a = Alignment(*pose, 0.0)
    r, c = np.indices(shape)
    q = np.column_stack(
        [origin[0] + (c.ravel() + 0.5) * truth.resolution, origin[1] + (r.ravel() + 0.5) * truth.resolution]
    )
    p = a.apply(q)
    rr = np.floor((p[:, 1] - truth.origin[1]) / truth.resolution).astype(int)
    cc = np.floor((p[:, 0] - truth.origin[0]) / truth.resolution).astype(int)
    ok = (rr >= 0) & (rr < truth.height) & (cc >= 0) & (cc < truth.width)
    out = np.full(len(q), -1, np.int8)
    out[ok] = truth.data[rr[ok], cc[ok]]
    return GridMap(out.reshape(shape), truth.resolution, origin)


def test_identical_maps_score_one(truth):
    s = score_maps(truth, truth)
    assert (s.precision, s.recall) == (1.0, 1.0)
    assert (s.alignment.x, s.alignment.y, s.alignment.yaw) == pytest.approx((0, 0, 0), abs=1e-6)
    assert 0 < s.true_faces < s.built_occupied  # faces only, not the walls' insides


@pytest.mark.parametrize("pose", [(1.0, 1.0, 0.0), (2.3, 5.1, math.radians(37)), (8.0, 6.0, math.radians(-150))])
def test_shifted_rotated_copy_is_realigned(truth, pose):
    built = resample(truth, pose)
    s = score_maps(built, truth)
    a = s.alignment
    assert math.hypot(a.x - pose[0], a.y - pose[1]) < 0.05, a
    assert abs((a.yaw - pose[2] + math.pi) % (2 * math.pi) - math.pi) < math.radians(1.0), a
    assert s.precision > 0.97 and s.recall > 0.97, s


def test_noise_lowers_precision_not_recall(truth):
    rng = np.random.default_rng(1)
    noisy = truth.data.copy()
    free = np.flatnonzero(noisy.ravel() == 0)
    noisy.ravel()[rng.choice(free, 600, replace=False)] = 100  # speckles in the open
    s = score_maps(GridMap(noisy, truth.resolution, truth.origin), truth)
    assert s.recall == 1.0
    # a few speckles fall within 10 cm of a wall and count as right
    assert truth_occ(truth) / (truth_occ(truth) + 600) <= s.precision < 0.93


def truth_occ(truth: GridMap) -> int:
    return int((truth.data == 100).sum())


def test_missing_walls_lower_recall(truth):
    cut = truth.data.copy()
    cut[:, : truth.width // 2][cut[:, : truth.width // 2] == 100] = -1  # the west half unseen
    s = score_maps(GridMap(cut, truth.resolution, truth.origin), truth, alignment=Alignment(0, 0, 0, 1))
    assert s.precision == 1.0 and 0.3 < s.recall < 0.7


def test_cli_map_score_json(truth, tmp_path, capsys):
    from bt_cli.main import main

    _, yml = write_pgm_yaml(resample(truth, (1.0, 1.0, math.radians(90))), tmp_path / "built.pgm")
    assert main(["--config", str(ROOT / "actorbt.yaml"), "map", "score", str(yml), "--world", "house", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["precision"] > 0.97 and out["recall"] > 0.97
    assert out["alignment"]["yaw_deg"] == pytest.approx(90, abs=1)
    assert main(["--config", str(ROOT / "actorbt.yaml"), "map", "score", str(yml)]) == 0
    text = capsys.readouterr().out
    assert "precision" in text and "recall" in text and "yaw 90" in text


def test_overlay_colours_matched_stray_and_missed_cells(truth):
    from sim.map_score import overlay_image

    built = truth.data.copy()
    built[:, : truth.width // 2][built[:, : truth.width // 2] == 100] = -1  # the west half unseen
    r, c = np.argwhere(truth.data == 0)[len(np.argwhere(truth.data == 0)) // 2]
    built[r, c] = 100  # a speckle in the open
    s = score_maps(GridMap(built, truth.resolution, truth.origin), truth, alignment=Alignment(0, 0, 0, 1))
    img = overlay_image(GridMap(built, truth.resolution, truth.origin), truth, s, scale=2)
    assert img.shape == (2 * truth.height, 2 * truth.width, 3) and img.dtype == np.uint8
    colours = {tuple(v) for v in img.reshape(-1, 3)}
    assert {(30, 160, 60), (220, 40, 40), (40, 90, 230)} <= colours
    # north up: the speckle's row counts from the top
    assert tuple(img[2 * (truth.height - 1 - r), 2 * c]) == (220, 40, 40)
    # the missed faces are in the west half, the matched ones in the east
    blue = np.argwhere((img == (40, 90, 230)).all(axis=2))[:, 1]
    green = np.argwhere((img == (30, 160, 60)).all(axis=2))[:, 1]
    assert np.median(blue) < truth.width < np.median(green)
