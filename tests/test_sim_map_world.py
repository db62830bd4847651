"""Worlds built from map_server maps (sim/map_world.py): a small hand-made PGM with a narrow
door, the cleanup a SLAM map needs, locations files and their errors, the PGM/YAML round
trip, a SimWorld on the house's own exported map, and worlds from maps made to look like
real SLAM maps (sim/map_degrade.py): the house's, and two rooms joined by 1-cell gaps only."""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np
import pytest

from planning import OccupancyGrid
from planning.base_planner import plan_base_path
from sim import write_map
from sim.description import load_world
from sim.gridmap import GridMap, build_grid, read_map, read_pgm_yaml, write_pgm_yaml
from sim.map_world import merge_rectangles
from sim.world_spec import WorldError

RES = 0.05
ORIGIN = (-1.25, -0.55)  # non-zero: cell (0, 0)'s corner in the map frame


def room_map(door_cells: int = 6, speckle=True) -> np.ndarray:
    """OccupancyGrid values (row 0 = lowest y), 100 x 60 cells (5 m x 3 m): two rooms joined
    by a door ``door_cells`` wide in a 1-cell wall, unknown outside, a noise speckle and a
    small unknown hole in the left room, an unknown bay (not seen by the lidar) in the right."""
    g = np.full((60, 100), -1, np.int8)
    g[5:55, 5:95] = 0
    g[5, 5:95] = g[54, 5:95] = 100
    g[5:55, 5] = g[5:55, 94] = 100
    g[5:55, 50] = 100  # the dividing wall...
    d0 = 30 - door_cells // 2
    g[d0 : d0 + door_cells, 50] = 0  # ... and its door
    if speckle:
        g[40, 20] = 100  # lidar noise in the open
        g[15:17, 35:37] = -1  # a 2 x 2 gap in the floor's coverage
    g[30:45, 80:94] = -1  # a bay the lidar never saw
    return g


def write_room(tmp_path, data=None, name="room", **kw) -> str:
    gm = GridMap(room_map(**kw) if data is None else data, RES, ORIGIN)
    _, yml = write_pgm_yaml(gm, tmp_path / f"{name}.pgm")
    return str(yml)


def cells_xy(r, c):
    return ORIGIN[0] + (c + 0.5) * RES, ORIGIN[1] + (r + 0.5) * RES


LEFT, RIGHT = cells_xy(30, 25), cells_xy(20, 70)  # room centres (x, y)


def plannable(grid: GridMap, a, b) -> bool:
    """Whether navstack's planner (robot radius 0.20 m) finds a way from a to b."""
    path = plan_base_path(OccupancyGrid(grid.data, grid.resolution, grid.origin), a, b, robot_radius=0.20)
    assert path.failure is None or "start" not in path.failure.value, path.message
    return path.failure is None


def test_round_trip_pgm_yaml_is_identical(tmp_path):
    data = room_map()
    back = read_pgm_yaml(write_room(tmp_path, data))
    assert np.array_equal(back.data, data)
    assert back.origin == pytest.approx(ORIGIN) and back.resolution == RES


def test_map_modes_negate_p2_and_16_bit(tmp_path):
    # a 3 x 2 image: black, white, grey / mid-greys; rows top (max y) first
    (tmp_path / "a.pgm").write_text("P2\n# ascii\n3 2\n255\n0 255 205\n100 128 50\n")
    base = "image: a.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    (tmp_path / "t.yaml").write_text(base + "negate: 0\n")
    t = read_map(tmp_path / "t.yaml").grid.data
    assert t[1].tolist() == [100, 0, -1] and t[0].tolist() == [-1, -1, 100]  # 100/255 -> p .61
    (tmp_path / "n.yaml").write_text(base + "negate: 1\n")
    assert read_map(tmp_path / "n.yaml").grid.data[1].tolist() == [0, 100, 100]
    (tmp_path / "s.yaml").write_text(base + "negate: 0\nmode: scale\n")
    s = read_map(tmp_path / "s.yaml").grid.data
    assert s[1, 0] == 100 and s[1, 1] == 0 and 0 < s[0, 0] < 100
    (tmp_path / "r.pgm").write_bytes(b"P5 2 1 255\n" + bytes([0, 100]))
    (tmp_path / "r.yaml").write_text(base.replace("a.pgm", "r.pgm") + "mode: raw\n")
    assert read_map(tmp_path / "r.yaml").grid.data.tolist() == [[0, 100]]
    (tmp_path / "w.pgm").write_bytes(b"P5\n2 1\n65535\n" + bytes([0, 0, 255, 255]))
    (tmp_path / "w.yaml").write_text(base.replace("a.pgm", "w.pgm"))
    assert read_map(tmp_path / "w.yaml").grid.data.tolist() == [[100, 0]]


def test_merged_boxes_and_cleanup(tmp_path):
    data = room_map()
    spec = load_world(write_room(tmp_path, data))
    occupied = int((data == 100).sum())
    assert len(spec.walls) < occupied / 10, (len(spec.walls), occupied)
    grid = build_grid(spec, RES)
    sx, sy = cells_xy(40, 20)
    assert grid.value_at(sx, sy) == 0  # the speckle is floor
    assert grid.value_at(*cells_xy(15, 35)) == 0  # the small hole is floor
    assert grid.value_at(*cells_xy(38, 88)) == -1  # the unseen bay stays outside


def test_unknown_is_outside_walled_off(tmp_path):
    spec = load_world(write_room(tmp_path, door_cells=12))
    g = build_grid(spec, RES).data
    free, unknown = g == 0, g == -1
    # no free cell touches an unknown one: walls stand on every free/unknown boundary
    touch = np.zeros_like(free)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            touch |= np.roll(np.roll(unknown, dr, 0), dc, 1)
    assert not (free & touch).any()
    assert free.sum() > 1000


def test_narrow_door_stops_the_robot(tmp_path):
    locs = _locs(tmp_path, start=LEFT, place=cells_xy(12, 12))
    narrow = load_world(write_room(tmp_path, door_cells=6, name="narrow"), locations=locs)  # 0.30 m door
    wide = load_world(write_room(tmp_path, door_cells=14, name="wide"), locations=locs)  # 0.70 m door
    assert not plannable(build_grid(narrow, RES), LEFT, RIGHT)
    assert plannable(build_grid(wide, RES), LEFT, RIGHT)
    # objects and search spots only where the robot can go: the left room
    for o in narrow.objects:
        assert o.x < cells_xy(0, 50)[0] - 0.3, o
    for x, y in narrow.search_locations:
        assert x < cells_xy(0, 50)[0]


def _locs(tmp_path, name="locs", **named) -> str:
    f = tmp_path / f"{name}.yaml"
    f.write_text("".join(f"{k}: [{', '.join(f'{v:.3f}' for v in xy)}]\n" for k, xy in named.items()))
    return str(f)


def test_locations_file(tmp_path):
    world = write_room(tmp_path, door_cells=14)
    start = (LEFT[0] - 0.6, LEFT[1], 0.5)
    place = (RIGHT[0], RIGHT[1], 1.0)
    spots = {"desk": cells_xy(45, 40), "shelf": cells_xy(15, 60)}
    spec = load_world(world, seed=3, locations=_locs(tmp_path, home=start, pallet=place, **spots))
    assert spec.robot_start == pytest.approx(start)
    assert (spec.place.x, spec.place.y, spec.place.yaw) == pytest.approx(place)
    assert np.allclose(spec.search_locations, list(spots.values()))
    assert sorted(o.category for o in spec.objects) == ["bottle", "box", "can", "carton"]
    grid = build_grid(spec, RES)
    for o in spec.objects:
        near = min(math.hypot(o.x - x, o.y - y) for x, y in spots.values())
        assert near <= 1.5 + 1e-9
        assert grid.value_at(o.x, o.y) == 0
    again = load_world(world, seed=3, locations=_locs(tmp_path, home=start, pallet=place, **spots))
    assert again.objects == spec.objects  # seeded
    other = load_world(world, seed=4, locations=_locs(tmp_path, home=start, **spots))
    assert other.objects != spec.objects
    assert other.place is not None and math.hypot(other.place.x - start[0], other.place.y - start[1]) < 3


def test_without_locations_picks_its_own(tmp_path):
    spec = load_world(write_room(tmp_path, door_cells=14))
    grid = build_grid(spec, RES)
    assert grid.value_at(*spec.robot_start[:2]) == 0
    assert len(spec.search_locations) >= 2
    assert spec.place is not None and len(spec.objects) == 4
    assert max(x for x, _ in spec.search_locations) > cells_xy(0, 50)[0]  # both rooms


@pytest.mark.parametrize(
    "text, line, words",
    [
        ("start: [0.0, 0.0, 0.0]\ndesk: [1, 2, 3, 4]\n", 2, "must be [x, y, theta]"),
        ("start: [0.0, 0.0]\ndesk: [1, oops]\n", 2, "must be a number"),
        ("start: [0.0, 0.0]\n  desk: [1, 2]\n", 2, ""),  # bad YAML
        ("desk: [{wall}, 0.0]\n", 1, "in a wall"),
        ("desk: [9.0, 9.0]\n", 1, "outside the map"),
        ("desk: [{right}]\n", 1, "cannot be reached"),
        ("home: [0, 0]\nstart: [0, 0]\n", 2, "keep one"),
    ],
)
def test_locations_errors(tmp_path, text, line, words):
    world = write_room(tmp_path)  # the 0.3 m door: the right room is out of reach
    wall_x = cells_xy(0, 50)[0]
    text = text.replace("{wall}", f"{wall_x:.3f}").replace("{right}", f"{RIGHT[0]:.3f}, {RIGHT[1]:.3f}")
    f = tmp_path / "bad_locs.yaml"
    f.write_text(text)
    with pytest.raises(WorldError) as e:
        load_world(world, locations=str(f), seed=0)
    assert f"bad_locs.yaml:{line}:" in str(e.value) and words in str(e.value)


def test_map_errors(tmp_path):
    (tmp_path / "empty.pgm").write_bytes(b"P5\n4 4\n255\n" + bytes([205] * 16))
    (tmp_path / "empty.yaml").write_text(
        "image: empty.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    with pytest.raises(WorldError, match="no free space"):
        load_world(tmp_path / "empty.yaml")
    (tmp_path / "yaw.yaml").write_text("image: empty.pgm\nresolution: 0.05\norigin: [0, 0, 0.3]\n")
    with pytest.raises(WorldError, match=r"yaw.yaml:3:9: origin: yaw 0.3"):
        load_world(tmp_path / "yaw.yaml")
    (tmp_path / "mode.yaml").write_text("image: empty.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: fancy\n")
    with pytest.raises(WorldError, match=r"mode.yaml:4:7: mode: unknown 'fancy'"):
        load_world(tmp_path / "mode.yaml")
    (tmp_path / "gone.yaml").write_text("image: nope.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(WorldError, match=r"gone.yaml:1:8: cannot read the image"):
        load_world(tmp_path / "gone.yaml")
    with pytest.raises(WorldError, match="locations file goes with a world built from a map"):
        load_world("house", locations=tmp_path / "mode.yaml")


def test_merge_rectangles_covers_exactly():
    rng = np.random.default_rng(0)
    mask = rng.random((40, 50)) < 0.3
    mask[10, :] = True
    mask[:, 7] = True
    rects = merge_rectangles(mask)
    cover = np.zeros((40, 50), int)
    for r, c, h, w in rects:
        cover[r : r + h, c : c + w] += 1
    assert np.array_equal(cover, mask.astype(int))  # every cell once, nothing else
    assert len(merge_rectangles(np.ones((30, 3), bool))) == 1


@pytest.fixture(scope="module")
def house_map(tmp_path_factory):
    out = tmp_path_factory.mktemp("house_map")
    return write_map("house", 0, out / "house.pgm")[1]


def test_house_map_rebuilds_the_same_grid(house_map):
    spec = load_world(house_map)
    old = read_pgm_yaml(house_map)
    new = build_grid(dataclasses.replace(spec, place=None), RES)  # the pallet is new
    # the built world is cropped to the known cells: compare cell by cell in the map frame
    dr, dc = (round((new.origin[i] - old.origin[i]) / RES) for i in (1, 0))
    same = np.full(old.data.shape, -1, np.int8)
    same[dr : dr + new.height, dc : dc + new.width] = new.data
    assert np.array_equal(same, old.data)
    assert len(spec.walls) < 60


def test_simworld_on_the_house_map_sees_walls(house_map):
    from sim import SimWorld

    sim = SimWorld(None, str(house_map), seed=1, camera=False)
    try:
        sim.advance(0.3)
        x, y, _ = sim.robot_pose()
        assert math.hypot(x - sim.spec.robot_start[0], y - sim.spec.robot_start[1]) < 0.05
        ranges = np.asarray(sim.scan_now())
        hits = np.isfinite(ranges) & (ranges > 0)
        assert hits.mean() > 0.5  # walls within 3.5 m on most sides
        assert ranges[hits].min() < 1.0  # the start is near the house's corner
        assert sorted(sim.object_names()) == ["bottle_1", "box_1", "can_1", "carton_1"]
    finally:
        sim.close()


# ---------------------------------------------------------------------------------------
# worlds from maps that look like real SLAM maps (sim/map_degrade.py): turned 3°, thin
# ragged walls with 1-cell gaps, speckles, unknown patches and shadows


@pytest.fixture(scope="module")
def slam_house(tmp_path_factory):
    """The house's lidar-height export made SLAM-like, with the house's places in its frame."""
    from sim.gridmap import lidar_height
    from sim.map_degrade import write_slam_like

    out = tmp_path_factory.mktemp("slam_house")
    src = write_map("house", 0, out / "house.pgm", height=lidar_height())[1]
    house = load_world("house", 0)
    places = {"start": house.robot_start}
    places.update({f"spot_{i}": xy for i, xy in enumerate(house.search_locations)})
    places["place"] = (house.place.x, house.place.y, house.place.yaw)
    return write_slam_like(src, out / "slam.pgm", places, seed=5)


def free_grid(grid: GridMap) -> GridMap:
    """``grid`` with every cell that is not occupied free: what stops a robot is the walls
    alone, not build_grid's flood fill from the start."""
    return GridMap(np.where(grid.data == 100, 100, 0).astype(np.int8), grid.resolution, grid.origin)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_world_from_a_slam_like_map(slam_house, seed):
    yml, locs, m = slam_house
    spec = load_world(yml, seed=seed, locations=locs)
    # walls merged into boxes: long runs of the staircase walls are one box each
    cells = sum(round(w.sx / RES) * round(w.sy / RES) for w in spec.walls)
    assert cells >= (m.grid.data == 100).sum() * 0.8
    assert len(spec.walls) < cells / 3, (len(spec.walls), cells)
    assert sum(max(w.sx, w.sy) >= 0.5 for w in spec.walls) >= 20
    # everything the mission needs is reachable from the start, in the walls the map made
    grid = build_grid(spec, RES)
    start = spec.robot_start[:2]
    assert len(spec.search_locations) == 9
    for p in spec.search_locations + [(o.x, o.y) for o in spec.objects]:
        assert plannable(grid, start, p), p
    clear = cv2.distanceTransform((grid.data == 0).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * RES
    for o in spec.objects:
        assert clear[grid.cell(o.x, o.y)] >= 0.3, o  # not against a ragged wall
        assert min(math.dist((o.x, o.y), s) for s in spec.search_locations) <= 1.5 + 1e-9


def test_one_cell_gaps_in_a_thin_wall_do_not_let_the_robot_through(tmp_path):
    from sim.map_degrade import slam_like
    from sim.map_world import write_locations

    data = room_map(door_cells=0, speckle=False)  # no door: the wall has only gaps
    for r in range(9, 52, 7):
        data[r, 50] = 0  # 1-cell (5 cm) gaps, 7 of them
    place = cells_xy(44, 16)
    drive = [LEFT, cells_xy(12, 12), place, RIGHT, cells_xy(48, 70)]
    m = slam_like(GridMap(data, RES, ORIGIN), drive, seed=0)
    _, yml = write_pgm_yaml(m.grid, tmp_path / "gappy.pgm")
    left, right = m.frame.to_map(*LEFT)[:2], m.frame.to_map(*RIGHT)[:2]
    named = {"start": left, "place": m.frame.to_map(*place)}
    spec = load_world(yml, seed=0, locations=write_locations(tmp_path / "start.yaml", named))
    grid = free_grid(build_grid(spec, RES))
    # the built wall has the gaps (and the turned map's own 1-cell holes): the rooms touch...
    _, labels = cv2.connectedComponents((grid.data == 0).astype(np.uint8), connectivity=8)
    assert labels[grid.cell(*left)] == labels[grid.cell(*right)]
    # ... but neither the planner (radius 0.20 m) nor the robot's base itself (0.281 m across
    # at its narrowest: a disc of 0.14 m) passes any of them
    assert not plannable(grid, left, right)
    path = plan_base_path(OccupancyGrid(grid.data, RES, grid.origin), left, right, robot_radius=0.14)
    assert path.failure is not None
    # so the world keeps to the left room: its search spots, its objects, its place location
    wall_x = cells_xy(0, 50)[0]
    for x, y in spec.search_locations + [(o.x, o.y) for o in spec.objects] + [(spec.place.x, spec.place.y)]:
        assert m.frame.to_source(x, y)[0] < wall_x - 0.1, (x, y)
    with pytest.raises(WorldError, match="cannot be reached"):
        load_world(yml, seed=0, locations=write_locations(tmp_path / "far.yaml", {**named, "shelf": right}))
