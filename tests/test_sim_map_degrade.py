"""sim/map_degrade.py: the house's own map made to look like a real SLAM map (turned, seen
only by a lidar along a drive, thin ragged walls with gaps, speckles, unknown patches),
the same from the same seed. The worlds built from such maps: tests/test_sim_map_world.py."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from sim import write_map
from sim.description import load_world
from sim.gridmap import lidar_height, read_map, write_pgm_yaml
from sim.map_degrade import slam_like, write_slam_like


def house_drive():
    """The house's start, search locations and place location: where the mapping drove."""
    spec = load_world("house", 0)
    return [spec.robot_start[:2]] + list(spec.search_locations) + [(spec.place.x, spec.place.y)]


@pytest.fixture(scope="module")
def house_src(tmp_path_factory):
    out = tmp_path_factory.mktemp("house_lidar")
    return read_map(write_map("house", 0, out / "house.pgm", height=lidar_height())[1]).grid


@pytest.fixture(scope="module")
def slam(house_src):
    return slam_like(house_src, house_drive(), seed=1)


def occupied_near(m, x, y, cells=1) -> bool:
    """Whether the map has an occupied cell within ``cells`` of the house point (x, y)."""
    r, c = m.grid.cell(*m.frame.to_map(x, y)[:2])
    return bool((m.grid.data[r - cells : r + cells + 1, c - cells : c + cells + 1] == 100).any())


def test_same_seed_same_map_trinary_and_map_saver_round_trip(house_src, slam, tmp_path):
    again = slam_like(house_src, house_drive(), seed=1)
    assert np.array_equal(again.grid.data, slam.grid.data) and again.grid.origin == slam.grid.origin
    assert not np.array_equal(slam_like(house_src, house_drive(), seed=2).grid.data, slam.grid.data)
    assert set(np.unique(slam.grid.data).tolist()) == {-1, 0, 100}
    assert slam.grid.resolution == house_src.resolution == 0.05
    # the origin is not the source's, nor on its cell lattice
    ox, oy = slam.grid.origin
    assert abs(ox) > 0.5 and abs(oy) > 0.5
    assert (
        min(
            abs((ox - house_src.origin[0]) / 0.05 - round((ox - house_src.origin[0]) / 0.05)),
            abs((oy - house_src.origin[1]) / 0.05 - round((oy - house_src.origin[1]) / 0.05)),
        )
        > 1e-3
    )
    _, yml = write_pgm_yaml(slam.grid, tmp_path / "slam.pgm")
    back = read_map(yml)
    assert back.mode == "trinary" and np.array_equal(back.grid.data, slam.grid.data)


def test_the_map_is_turned_as_its_frame_says(slam):
    f = slam.frame
    start = house_drive()[0]
    assert f.to_map(*start) == pytest.approx((0.0, 0.0, math.radians(3.0)))  # SLAM began there
    assert f.to_source(*f.to_map(7.0, 6.2)[:2]) == pytest.approx((7.0, 6.2))
    # the walls' faces lie where the frame puts them, far from the pivot too (a turn the
    # wrong way would be 0.5 m off at the far end of the south wall)
    south = [(x, 0.05) for x in np.arange(0.5, 5.5, 0.1)]
    west = [(0.05, y) for y in np.arange(0.5, 4.0, 0.1)]
    for face in (south, west):
        assert np.mean([occupied_near(slam, x, y) for x, y in face]) > 0.9
    assert np.mean([occupied_near(slam, x, 0.3) for x, _ in south]) < 0.1  # the floor in front
    # a straight wall is a staircase: along the south face, the wall's row changes
    rows = [slam.grid.cell(*slam.frame.to_map(x, 0.05)[:2])[0] for x, _ in south]
    assert max(rows) - min(rows) >= 4


def test_walls_between_rooms_are_one_cell_thin(slam):
    # the wall at x = 6 between living room and kitchen (its doorway y 1.5..2.5), across
    # each of the map's rows
    widths = []
    for y in list(np.arange(0.2, 1.3, 0.05)) + list(np.arange(2.7, 4.3, 0.05)):
        r, c = slam.grid.cell(*slam.frame.to_map(6.0, y)[:2])
        widths.append(int((slam.grid.data[r, c - 4 : c + 5] == 100).sum()))
    widths = np.array(widths)
    assert (widths == 1).mean() > 0.8 and widths.max() <= 3, widths


def test_only_what_the_lidar_saw_is_known(slam):
    g = slam.grid
    for x, y in ((3.5, 4.0), (1.05, 6.9), (9.65, 2.5)):  # inside sofa, bed, kitchen counter
        assert g.value_at(*slam.frame.to_map(x, y)[:2]) == -1
    assert g.value_at(*slam.frame.to_map(5.0, -0.3)[:2]) == -1  # outside the house
    # unknown islands in the floor: patches and what furniture hid
    unknown = (g.data == -1).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(unknown, connectivity=4)
    h, w = unknown.shape
    inner = [
        i
        for i in range(1, n)
        if stats[i, 0] > 0 and stats[i, 1] > 0 and stats[i, 0] + stats[i, 2] < w and stats[i, 1] + stats[i, 3] < h
    ]
    assert len(inner) >= 5
    assert len(slam.patches) >= 2


def test_flaws_gaps_speckles_streaks(slam):
    g = slam.grid.data
    assert len(slam.gaps) >= 8 and len(slam.speckles) >= 30
    for r, c in slam.gaps:  # a gap is one free cell of a wall, on its own
        assert g[r, c] == 0 and (g[r - 1 : r + 2, c - 1 : c + 2] == 100).any()
        assert min(max(abs(r - r2), abs(c - c2)) for r2, c2 in slam.gaps if (r2, c2) != (r, c)) > 4
    for r, c in slam.speckles:  # noise: one or two cells, mostly in the open
        assert g[r, c] == 100
    lone = sum((g[r - 1 : r + 2, c - 1 : c + 3] == 100).sum() <= 2 for r, c in slam.speckles)
    assert lone > 0.7 * len(slam.speckles)
    # rays leaked out through a gap: free cells with unknown on both sides, outside the house
    free = g == 0
    thin = free & (np.roll(g, 1, 0) == -1) & (np.roll(g, -1, 0) == -1) | free & (np.roll(g, 1, 1) == -1) & (
        np.roll(g, -1, 1) == -1
    )
    assert thin.sum() >= 3


def test_write_slam_like_moves_the_places_into_its_frame(house_src, tmp_path):
    src = tmp_path / "src.pgm"
    _, src_yaml = write_pgm_yaml(house_src, src)
    places = {"start": (1.0, 1.0, 0.0), "desk": (4.8, 1.6), "place": (7.0, 6.2, 0.5)}
    yml, locs, m = write_slam_like(src_yaml, tmp_path / "slam.pgm", places, seed=3)
    assert np.array_equal(read_map(yml).grid.data, m.grid.data)
    text = locs.read_text().splitlines()
    assert [ln.split(":")[0] for ln in text] == ["start", "desk", "place"]
    assert text[0] == "start: [0.0000, 0.0000, 0.0524]"
    x, y, theta = m.frame.to_map(7.0, 6.2, 0.5)
    assert text[2] == f"place: [{x:.4f}, {y:.4f}, {theta:.4f}]"
    assert len(text[1].split(",")) == 2
