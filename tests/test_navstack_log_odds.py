"""navstack.log_odds: the log-odds update from a laser scan, growth, clamping, to_map()."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

from navstack.log_odds import LogOddsGrid, LogOddsParams, logit
from navstack.synthetic import Boxes, cast, world_boxes

FIXTURES = Path(__file__).parent / "fixtures"


def beam_grid(ranges, angle=0.0, pose=(0.0, 0.0, 0.0), **kw):
    g = LogOddsGrid(LogOddsParams(**kw))
    g.integrate(pose, np.atleast_1d(np.asarray(ranges, float)), np.full(np.size(ranges), angle), 3.5)
    return g


def value(g, x, y):
    c, r = g.cell_of(x, y)
    return float(g.logodds[r, c])


def test_one_beam_frees_the_cells_it_crosses_and_marks_its_end():
    p = LogOddsParams()
    g = beam_grid([1.02])
    # the hit cell (1.00 .. 1.05) gets l_occ, every cell before it l_free, nothing beyond
    assert value(g, 1.02, 0.01) == pytest.approx(p.l_occ)
    for x in np.arange(0.025, 1.0, 0.05):
        assert value(g, x, 0.01) == pytest.approx(p.l_free), x
    assert value(g, 1.07, 0.01) == 0.0
    assert value(g, 0.5, 0.06) == 0.0  # the neighbouring row is untouched
    # once per scan: the 10 beams sharing the cells count once
    g2 = LogOddsGrid()
    g2.integrate((0, 0, 0), np.full(10, 1.02), np.zeros(10), 3.5)
    assert np.array_equal(g2.logodds, g.logodds)


def test_no_return_clears_to_max_range_and_marks_nothing():
    p = LogOddsParams()
    for r in (np.inf, 3.5, 9.0):  # inf, at range_max, beyond: all "no return"
        g = beam_grid([r], angle=math.pi / 2)
        assert value(g, 0.01, 3.45) == pytest.approx(p.l_miss)
        assert value(g, 0.01, 3.55) == 0.0
        assert g.logodds.max() == 0.0
    g = beam_grid([np.nan])
    assert not g.logodds.any()
    # a returned beam's crossing wins over a drop-out's in the same scan
    g = LogOddsGrid()
    g.integrate((0, 0, 0), [np.inf, 2.02], [0.0, 0.0], 3.5)
    assert value(g, 1.02, 0.01) == pytest.approx(p.l_free) and value(g, 3.0, 0.01) == pytest.approx(p.l_miss)
    g = LogOddsGrid()
    g.integrate((0, 0, 0), [np.inf], [0.0], 3.5, clear_range=1.0)
    assert value(g, 0.95, 0.01) < 0 and value(g, 1.05, 0.01) == 0.0


def test_log_odds_accumulate_and_clamp_and_convert_to_trinary():
    p = LogOddsParams()
    g = LogOddsGrid(p)
    for _ in range(20):
        g.integrate((0.0, 0.0, 0.0), [1.02], [0.0], 3.5)
    assert value(g, 1.02, 0.01) == pytest.approx(p.l_max)
    assert value(g, 0.5, 0.01) == pytest.approx(p.l_min)
    # a wall that moved away is cleared again by beams through it: the clamp bounds how
    # many passes that takes ((l_max - logit(0.65)) / -l_free: 8)
    for k in range(8):
        assert value(g, 1.02, 0.01) >= logit(0.65), k
        g.integrate((0.0, 0.0, 0.0), [2.02], [0.0], 3.5)
    assert value(g, 1.02, 0.01) < logit(0.65)
    one = beam_grid([1.02])
    m = one.to_map()
    assert m.resolution == 0.05 and set(np.unique(m.data)) <= {-1, 0, 100}
    assert m.value_at(1.02, 0.01) == 100  # one hit: p 0.7 >= 0.65
    assert m.value_at(0.5, 0.01) == -1  # one pass: p 0.4, not yet <= 0.25
    thrice = LogOddsGrid()
    for _ in range(3):
        thrice.integrate((0, 0, 0), [1.02], [0.0], 3.5)
    assert thrice.to_map().value_at(0.5, 0.01) == 0
    assert m.value_at(-1.0, 0.01) == -1


def test_the_grid_grows_and_keeps_what_it_knew():
    g = beam_grid([1.02])
    before = value(g, 1.02, 0.01)
    g.integrate((20.0, -6.99, 0.0), [1.02], [math.pi], 3.5)
    x0, y0, x1, y1 = g.extent()
    assert x0 < 0 and y0 < -7 and x1 > 20 and y1 > 0
    assert value(g, 1.02, 0.01) == before
    assert value(g, 18.99, -6.99) == pytest.approx(g.params.l_occ)
    # the origin stays on the lattice through (0, 0): cells never shift by a fraction
    assert g.origin[0] / 0.05 == pytest.approx(round(g.origin[0] / 0.05))


def test_a_square_room_is_mapped_where_its_walls_are():
    room = Boxes.from_list([(2, 0, 4.1, 0.1, 0), (2, 3, 4.1, 0.1, 0), (0, 1.5, 0.1, 3.1, 0), (4, 1.5, 0.1, 3.1, 0)])
    angles = np.arange(360) * 2 * math.pi / 360
    g = LogOddsGrid()
    rng = np.random.default_rng(0)
    for x, y in [(1, 1), (2, 1.5), (3, 2)]:
        r = cast(room, (x, y), angles, 3.5)
        r = r + rng.normal(0, 0.01, r.shape)
        g.integrate((x, y, 0.0), r, angles, 3.5)
    m = g.to_map()
    xs, ys = m.cell_centres(m.occupied())
    assert len(xs) > 150
    assert room.contains(xs, ys, margin=0.1).mean() > 0.97
    fx, fy = m.cell_centres(m.free())
    assert not room.contains(fx, fy).any()


def test_a_360_beam_scan_takes_a_few_milliseconds():
    boxes = world_boxes(FIXTURES / "house_world.yaml")
    angles = np.arange(360) * 2 * math.pi / 360
    r = cast(boxes, (1.0, 1.0), angles, 3.5)
    g = LogOddsGrid()
    g.integrate((1.0, 1.0, 0.0), r, angles, 3.5)
    times = []
    for k in range(30):
        t0 = time.perf_counter()
        g.integrate((1.0 + 0.01 * k, 1.0, 0.0), r, angles, 3.5)
        times.append(time.perf_counter() - t0)
    assert np.median(times) < 0.010
