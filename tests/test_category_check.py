"""A category is checked against the robot (categories/check.py's rules, the arm's reach
from actors/category_check.py): the gripper's rules when it registers, the arm's when the
robot starts, and all by hand with `actorbt category check FILE`; each problem says where
and what to change."""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap

import pytest

import categories
from categories import Box, Category, Grasp, Revolution, TopGrasp
from actors.category_check import check_registered, problems_of, reachable
from categories.check import reach_band

#: the cone of a plastic cup, 50 mm at the foot and 72 mm at the rim, 95 mm tall, as
#: stacked sections (a user's category of a shape the built-ins do not have)
CUP = Revolution(((0.02, 0.0265), (0.04, 0.0285), (0.06, 0.0305), (0.08, 0.0325), (0.095, 0.0355)))


def _cup(**grasp) -> Category:
    return Category(
        name="cup_test", shape=CUP, mass=0.012, rgba=(0.1, 0.3, 0.9, 1.0), grasp=Grasp(**{"height": 0.05, **grasp})
    )


def test_the_built_ins_can_work():
    for cat in categories.all_categories():
        assert problems_of(cat) == [], cat.name
    check_registered()


def test_the_arm_reaches_the_floor_band_the_docs_name():
    low, high = reach_band(reachable, 0.27, 0.0)
    assert low == pytest.approx(0.045, abs=0.002) and high > 0.3


def test_the_stall_window_is_derived_from_the_width_at_the_grasp_height():
    cup = _cup(height=0.05)  # the pads (30 mm tall) reach up to the section 65 mm across
    assert cup.held_width() == pytest.approx(0.065)
    assert (cup.grasp.closed_min, cup.grasp.closed_max) == pytest.approx((0.055, 0.073))
    assert problems_of(cup) == []
    wide = _cup(height=0.085, open_width=0.080)  # near the rim, 71 mm: short of the opening
    assert wide.grasp.closed_max == pytest.approx(0.078)
    box = Category(
        name="box_test", shape=Box(0.07, 0.045, 0.12), mass=0.05, rgba=(1, 1, 0, 1), grasp=Grasp(height=0.06)
    )
    assert (box.grasp.closed_min, box.grasp.closed_max) == pytest.approx((0.035, 0.053))


@pytest.mark.parametrize(
    "grasp, top, expected",
    [
        (
            dict(height=0.035),
            None,
            "grasp.height 0.035 m is out of the arm's reach: at reach 0.270 m and pitch 0 deg "
            "the hand reaches 0.045..0.369 m above the floor; "
            "change grasp.height or approach.reach",
        ),
        (dict(lift=0.40), None, "the lift (grasp.height + grasp.lift) 0.450 m is out of the arm's reach"),
        (
            dict(closed_min=0.050, closed_max=0.058),
            None,
            "at grasp.height 0.050 m the fingers close on 65 mm, outside closed_min..closed_max 50..58 mm; "
            "leave both out to have them derived from the shape",
        ),
        (dict(open_width=0.095), None, "grasp.open_width 95 mm is wider than the gripper opens (90 mm)"),
        (dict(closed_min=0.05, closed_max=0.085), None, "grasp.closed_max 85 mm reaches the opening (85 mm)"),
        (
            {},
            TopGrasp(reach=0.30),
            "lying, the grasp at 0.041 m is out of the arm's reach: at reach 0.300 m and "
            "pitch 90 deg the hand reaches no height; change top_grasp",
        ),
    ],
)
def test_each_rule_names_what_to_change(grasp, top, expected):
    extra = {} if top is None else {"top_grasp": top}
    cup = Category(
        name="cup_test",
        shape=CUP,
        mass=0.012,
        rgba=(0.1, 0.3, 0.9, 1.0),
        grasp=Grasp(**{"height": 0.05, **grasp}),
        **extra,
    )
    problems = problems_of(cup)
    assert any(p.startswith(expected) for p in problems), problems


def test_a_category_the_gripper_cannot_hold_fails_where_it_registers(tmp_path):
    path = tmp_path / "cup.py"
    path.write_text(
        textwrap.dedent('''\
        """A cup whose stall window misses it."""
        from categories import Category, Grasp, Revolution, register

        CATEGORY = register(Category(
            name="cup_window_test",
            shape=Revolution(((0.095, 0.03),)), mass=0.012, rgba=(0.1, 0.3, 0.9, 1.0),
            grasp=Grasp(height=0.05, closed_min=0.040, closed_max=0.050)))
    ''')
    )
    with pytest.raises(categories.CategoryError) as e:
        categories.load(path)
    assert str(e.value).startswith(
        f"{path}:4: category 'cup_window_test' cannot work: at grasp.height 0.050 m "
        "the fingers close on 60 mm, outside closed_min..closed_max 40..50 mm"
    )
    assert "cup_window_test" not in categories.names()


def test_a_category_out_of_the_arms_reach_fails_when_the_robot_starts(tmp_path):
    path = tmp_path / "cup.py"
    path.write_text(
        textwrap.dedent('''\
        """A cup held too low."""
        from categories import Category, Grasp, Revolution, register

        CATEGORY = register(Category(
            name="cup_low_test",
            shape=Revolution(((0.095, 0.03),)), mass=0.012, rgba=(0.1, 0.3, 0.9, 1.0),
            grasp=Grasp(height=0.035)))
    ''')
    )
    categories.load(path)
    with pytest.raises(categories.CategoryError) as e:
        check_registered()
    assert str(e.value).startswith(
        f"{path}:4: category 'cup_low_test' cannot work on this robot: grasp.height 0.035 m is out of the arm's reach"
    )
    from bt_engine import Runtime
    from actors.catch import Catcher

    rt = Runtime(clock="virtual")
    try:
        with pytest.raises(categories.CategoryError, match="cup_low_test"):
            rt.add_subsystem("catch", Catcher)
    finally:
        rt.close()


def test_a_declaration_error_names_its_line(tmp_path):
    path = tmp_path / "tall.py"
    path.write_text(
        "from categories import Category, Cylinder, Grasp, register\n\n"
        "CATEGORY = register(Category(name='tall_test', shape=Cylinder(0.03, 0.1), mass=0.01,\n"
        "                             rgba=(1, 0, 0), grasp=Grasp(height=0.2)))\n"
    )
    with pytest.raises(
        categories.CategoryError, match=rf"^{path}:3: tall_test: grasp height 0.2 m is not on the object"
    ):
        categories.load(path)


def test_category_check_by_hand(tmp_path):
    good, bad = tmp_path / "cup.py", tmp_path / "low.py"
    good.write_text(
        "from categories import Category, Grasp, Revolution, register\n"
        f"CATEGORY = register(Category(name='cup_cli_test', shape=Revolution({CUP.sections!r}),\n"
        "    mass=0.012, rgba=(0.1, 0.3, 0.9, 1.0), grasp=Grasp(height=0.05, lift=0.10)))\n"
    )
    bad.write_text(good.read_text().replace("cup_cli_test", "low_cli_test").replace("height=0.05", "height=0.035"))
    run = subprocess.run(
        [sys.executable, "-m", "bt_cli.main", "category", "check", str(good), str(bad)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 1, run.stderr
    assert f"{good}: category 'cup_cli_test' can work on this robot" in run.stdout
    assert "upright: reach 0.270 m, height 0.050 m, pitch 0 deg, held at 55..73 mm, lift 0.100 m" in run.stdout
    assert f"error: {bad}:2: category 'low_cli_test' cannot work on this robot: grasp.height 0.035 m" in run.stderr


@pytest.fixture(autouse=True)
def _forget_test_categories():
    yield
    for name in categories.names():
        if name.endswith("_test"):
            categories.unregister(name)


def test_reach_band_is_empty_where_the_arm_cannot_point():
    assert reach_band(reachable, 0.5, math.pi / 2) is None
