"""The category files and their registry (categories/)."""

from __future__ import annotations

import math
import textwrap

import pytest

import categories
from categories import Box, Category, Cylinder, Grasp, Revolution


JUICE = textwrap.dedent("""
    from categories import Box, Category, Grasp, register

    CATEGORY = register(Category(
        name="juice_test", shape=Box(0.06, 0.04, 0.10), mass=0.05, rgba=(0.9, 0.4, 0.05, 1.0),
        grasp=Grasp(height=0.05, closed_min=0.03, closed_max=0.05)))
""")


@pytest.fixture
def juice_file(tmp_path):
    path = tmp_path / "juice.py"
    path.write_text(JUICE)
    yield path
    categories.unregister("juice_test")


def test_built_ins():
    assert {"can", "bottle", "carton"} <= set(categories.names())
    carton = categories.get("carton")
    assert isinstance(carton.shape, Box) and carton.height == pytest.approx(0.12)
    assert categories.get("bottle").shape.body_radius == pytest.approx(0.035)


def test_unknown_names_list_close_matches():
    with pytest.raises(categories.UnknownCategoryError, match="did you mean carton"):
        categories.get("craton")


def test_a_file_in_any_folder_adds_a_category(juice_file):
    added = categories.load(juice_file)
    assert [c.name for c in added] == ["juice_test"]
    assert categories.get("juice_test").strategy.sides == (0.0, math.pi / 2)
    assert categories.load(juice_file) == []  # loading it again changes nothing


def test_a_relative_path_is_read_from_the_base_folder(juice_file):
    assert [c.name for c in categories.load("juice.py", base=juice_file.parent)] == ["juice_test"]


def test_a_missing_file_says_where_it_looked(tmp_path):
    with pytest.raises(categories.CategoryError, match="not found"):
        categories.load(tmp_path / "nope.py")


def test_a_taken_name_is_not_silently_replaced():
    other = Category("can", Cylinder(0.03, 0.1), 0.04, (1, 0, 0, 1), Grasp(height=0.05))
    with pytest.raises(categories.CategoryError, match="registered already"):
        categories.register(other)
    categories.register(categories.get("can"))  # the same declaration again is fine


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(shape=Box(0.10, 0.09, 0.1)), "fits the gripper"),  # too wide on every side
        (dict(grasp=Grasp(height=0.2)), "not on the object"),
        (dict(mass=0), "mass"),
        (dict(rgba=(2, 0, 0)), "rgba"),
        (dict(name="my can"), "letters"),
    ],
)
def test_bad_declarations_say_what_is_wrong(kwargs, message):
    base = dict(name="x_test", shape=Box(0.07, 0.045, 0.12), mass=0.05, rgba=(1, 1, 0, 1), grasp=Grasp(height=0.06))
    with pytest.raises((ValueError, TypeError), match=message):
        Category(**{**base, **kwargs})


def test_shapes_give_the_simulator_its_parts():
    bottle = Revolution(((0.2, 0.035), (0.23, 0.024), (0.305, 0.0135)))
    parts = bottle.parts()
    assert [p[2] for p in parts] == pytest.approx([0.2, 0.03, 0.075])
    assert parts[0][3] == pytest.approx(-0.305 / 2 + 0.1)  # the body's centre
    assert Box(0.07, 0.045, 0.12).width_across(0.0) == pytest.approx(0.045)
    assert Box(0.07, 0.045, 0.12).width_across(math.pi / 2) == pytest.approx(0.07)
    with pytest.raises(ValueError):
        Revolution(((0.1, 0.03), (0.05, 0.02)))  # sections must rise


def test_the_simulator_builds_every_registered_category(juice_file):
    from sim.objects import CATEGORIES

    categories.load(juice_file)
    assert CATEGORIES["juice_test"].parts == (("box", (0.06, 0.04, 0.10), 0.0),)
    assert "box" in CATEGORIES and "carton" in CATEGORIES  # distractors too
