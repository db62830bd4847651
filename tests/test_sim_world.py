"""Worlds from YAML: validation with file:line, seeded placement, the occupancy map,
the PGM/YAML export and the top-view snapshot."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from sim import WorldError, list_worlds, load_world, snapshot, write_map
from sim.description import world_path
from sim.gridmap import build_grid, read_pgm_yaml
from sim.objects import CATEGORIES
from sim.robot import URDF

SMALL = """\
name: small
bounds: [-0.5, -0.5, 3.5, 3.5]
walls:
  - [0, 0, 3, 0]
  - [3, 0, 3, 3]
  - [3, 3, 0, 3]
  - [0, 3, 0, 0]
rooms:
  corner: [2.0, 2.0, 3.0, 3.0]
robot: {start: [0.5, 0.5, 0]}
objects:
  - {category: can, count: COUNT, room: corner}
"""


def test_shipped_worlds_load():
    assert {"house", "open_floor"} <= set(list_worlds())
    house = load_world("house", seed=0)
    assert len(house.rooms) >= 4 and house.place is not None
    cats = {o.category for o in house.objects}
    assert {"can", "bottle"} <= cats and cats - {"can", "bottle"}, "needs a distractor"
    for o in house.objects:
        assert o.name and house.room_of(o.x, o.y) is not None


def test_categories_match_the_brief():
    can = CATEGORIES["can"]
    assert can.radius * 2 == pytest.approx(0.066) and can.height == pytest.approx(0.122)
    assert can.mass == pytest.approx(0.040) and can.rgba[0] > 0.7 > max(can.rgba[1:3])
    bottle = CATEGORIES["bottle"]
    assert len(bottle.parts) >= 2 and bottle.mass <= 0.3  # body + neck, light for the arm


def test_others_places_one_of_every_category_not_listed(tmp_path):
    import categories

    w = load_world("house", seed=2)
    assert sorted(o.category for o in w.objects) == ["bottle", "box", "box", "can", "can", "carton"]
    juice = tmp_path / "juice.py"
    juice.write_text(
        "from categories import Box, Category, Grasp, register\n"
        "register(Category('juice_world_test', Box(0.06, 0.04, 0.1), 0.05, (1, .5, 0, 1),"
        " Grasp(height=0.05)))\n"
    )
    categories.load(juice)
    try:
        again = load_world("house", seed=2)
        assert again.objects[:6] == w.objects  # the layout so far stays
        (extra,) = again.objects[6:]
        assert extra.category == "juice_world_test" and again.room_of(extra.x, extra.y)
    finally:
        categories.unregister("juice_world_test")


def test_same_seed_same_world_other_seed_other_world():
    a, b, c = (load_world("house", seed=s) for s in (5, 5, 6))
    assert a.objects == b.objects
    assert a.objects != c.objects


def test_placement_keeps_clear_of_walls_furniture_and_each_other():
    for seed in range(10):
        w = load_world("house", seed)
        for o in w.objects:
            r = CATEGORIES[o.category].radius
            assert all(ob.distance(o.x, o.y) >= r + 0.3 - 1e-9 for ob in w.obstacles), (seed, o)
        for i, a in enumerate(w.objects):
            for b in w.objects[i + 1 :]:
                assert math.hypot(a.x - b.x, a.y - b.y) > 0.3


def test_bad_yaml_names_file_and_line(tmp_path):
    f = tmp_path / "bad.yaml"
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nobjects:\n  - {category: can\n  - {category: box}\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:5:5: YAML syntax error: .*; .*not closed"):
        load_world(f)
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nobjects:\n  - {category: can}\n  - {category: teapot}\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:5:16: .*unknown category 'teapot'"):
        load_world(f)
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nwalls:\n  - [0, 0, 5]\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:4:5: walls\[0\] must have 4 numbers"):
        load_world(f)
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nplace_location: {center: [1, 1], size: [1, x, 1]}\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:3:44: place_location.size must be a number, got 'x'"):
        load_world(f)
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nrobots: {start: [1, 1, 0]}\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:3:1: world: unknown key 'robots'"):
        load_world(f)
    f.write_text("name: bad\nbounds: [0, 0, 5, 5]\nsearch_locations: [[1, 1], [7, 1]]\n")
    with pytest.raises(WorldError, match=r"bad\.yaml:3:28: search_locations\[1\]: \(7, 1\) is outside the bounds"):
        load_world(f)


def test_search_locations_are_optional():
    assert load_world("open_floor", 0).search_locations == []
    house = load_world("house", 0).search_locations
    assert len(house) == 9 and house[0] == (1.8, 2.0)


def test_unplaceable_object_is_a_clear_error(tmp_path):
    f = tmp_path / "crowded.yaml"
    f.write_text(SMALL.replace("COUNT", "1"))
    assert len(load_world(f).objects) == 1
    f.write_text(SMALL.replace("COUNT", "40"))
    with pytest.raises(WorldError) as e:
        load_world(f)
    msg = str(e.value)
    assert msg.startswith(f"{f}:12:5: cannot place object 'can_")
    assert "room 'corner'" in msg and "no free floor space" in msg


def test_unknown_world_lists_the_known_ones():
    with pytest.raises(WorldError, match="unknown world 'mars'.*house.*open_floor"):
        world_path("mars")


def test_occupancy_grid_from_geometry():
    w = load_world("house", 0)
    g = build_grid(w)
    assert g.resolution == 0.05
    assert g.value_at(5.0, 0.0) == 100  # outer wall
    assert g.value_at(*w.robot_start[:2]) == 0  # start is free
    assert g.value_at(-0.3, -0.3) == -1  # outside the house: unknown
    assert g.value_at(2.0, 4.5) == 0  # a doorway is open
    assert g.value_at(w.place.x, w.place.y) == 100
    for f in w.furniture:
        assert g.value_at(f.x, f.y) == 100
    # every room is reachable through its doorways
    for name, (x0, y0, x1, y1) in w.rooms.items():
        assert (
            g.data[g.cell(x0 + 0.3, y0 + 0.3)[0] : g.cell(x1, y1)[0], g.cell(x0 + 0.3, y0 + 0.3)[1] : g.cell(x1, y1)[1]]
            == 0
        ).any(), name


def test_map_export_round_trips(tmp_path):
    pgm, yml = write_map("house", 0, tmp_path / "house.pgm")
    assert pgm.read_bytes().startswith(b"P5")
    text = yml.read_text()
    assert "image: house.pgm" in text and "resolution: 0.05" in text and "origin: [-0.5, -0.5, 0.0]" in text
    back = read_pgm_yaml(yml)
    assert np.array_equal(back.data, build_grid(load_world("house", 0)).data)


def test_urdf_has_the_contracted_names_and_physics():
    root = ET.parse(URDF).getroot()
    links = {link.get("name"): link for link in root.findall("link")}
    joints = {j.get("name"): j for j in root.findall("joint")}
    for n in (
        "base_footprint",
        "base_link",
        "end_effector_link",
        "camera_link",
        "camera_optical_frame",
        "base_scan",
        "imu_link",
    ):
        assert n in links
    for n in ("wheel_left_joint", "wheel_right_joint"):
        assert joints[n].get("type") == "continuous"
    for n in ("joint1", "joint2", "joint3", "joint4"):
        assert joints[n].get("type") == "revolute"
    for n in ("gripper_left_joint", "gripper_right_joint"):
        assert joints[n].get("type") == "prismatic"
        assert 2 * float(joints[n].find("limit").get("upper")) > 0.066 + 0.01
    frames = {"base_footprint", "end_effector_link", "camera_optical_frame", "base_scan", "imu_link"}
    for name, link in links.items():
        assert link.find("inertial") is not None, name
        if name not in frames:
            assert link.find("collision") is not None, name


def test_snapshot_writes_top_view_and_camera(tmp_path):
    out = snapshot("open_floor", 1, tmp_path / "w.png", camera=True, camera_size=(160, 120))
    assert [p.name for p in out] == ["w.png", "w_camera.png"]
    import cv2

    top, cam = cv2.imread(str(out[0])), cv2.imread(str(out[1]))
    assert top.shape[0] > 400 and top.shape[1] > 400
    assert cam.shape == (120, 320, 3)


def test_urdf_is_what_its_generator_writes():
    from sim.models import build_urdf

    assert build_urdf.build() == URDF.read_text(), "run `python -m sim.models.build_urdf`"
