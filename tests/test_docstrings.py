"""The Args: convention (bt_engine.docstrings): parsing docstrings, units, explicit docs."""

from __future__ import annotations

import pytest

from bt_engine.docstrings import attach, explicit, param_docs, parse, unit_of

GOTO = """Drive to (x, y) [m] in the map frame.

    Fails when no path exists.

    Args:
        x: goal x in the map frame [m]
        y (float): goal y in the map frame [m]
        timeout: give up after this long [s]; None: from
            the path length

    Returns:
        the pose reached: x [m], y [m], yaw [rad]

    Raises:
        NavigationError: no path.
    """


def test_args_entries_with_types_and_continuations():
    d = parse(GOTO)
    assert d.params == {
        "x": "goal x in the map frame [m]",
        "y": "goal y in the map frame [m]",
        "timeout": "give up after this long [s]; None: from the path length",
    }
    assert d.returns == "the pose reached: x [m], y [m], yaw [rad]"


def test_summary_details_and_text_leave_the_sections_out():
    d = parse(GOTO)
    assert d.summary == "Drive to (x, y) [m] in the map frame."
    assert d.details == "Fails when no path exists.\nRaises: NavigationError: no path."
    assert d.text == (
        "Drive to (x, y) [m] in the map frame.\n\nFails when no path exists.\n\nRaises:\n    NavigationError: no path."
    )


def test_variadic_grouped_and_section_synonyms():
    d = parse("""Move.

        Parameters:
            *q: joint positions [rad]
            x, y: a point in the map frame [m]
            **extra: ignored
        """)
    assert d.params == {
        "q": "joint positions [rad]",
        "x": "a point in the map frame [m]",
        "y": "a point in the map frame [m]",
        "extra": "ignored",
    }


def test_args_right_after_the_summary_and_an_entry_text_on_the_next_line():
    d = parse("""Wait.
        Args:
            seconds:
                how long [s]
        """)
    assert d.summary == "Wait."
    assert d.params == {"seconds": "how long [s]"}


def test_a_docstring_without_sections():
    d = parse("One line.\n\nAnother paragraph\n    wrapped.")
    assert (d.summary, d.details, d.params, d.returns) == ("One line.", "Another paragraph wrapped.", {}, "")
    assert parse(None) == parse("")
    assert parse("").summary == ""


def test_prose_that_looks_like_an_entry_is_no_section():
    d = parse("Note: this is prose.\nExample: x: 1")
    assert d.params == {}
    assert d.summary == "Note: this is prose. Example: x: 1"


@pytest.mark.parametrize(
    "text, unit",
    [
        ("goal x [m]", "m"),
        ("seconds to wait [s]", "s"),
        ("top speed [m/s]", "m/s"),
        ("acceleration [m/s^2]", "m/s^2"),
        ("the turn [deg], left positive", "deg"),
        ("x [m] and y [m]", "m"),  # the same unit twice
        ("search locations [x, y] in the map frame [m]", "m"),  # a list is no unit
        ("where to return: x, y [m], yaw [rad]", None),  # several units: none
        ("how many looks", None),
        ("an index [0]", None),
        ("the watchdog [s, wall]", None),
        ("", None),
        (None, None),
    ],
)
def test_unit_of(text, unit):
    assert unit_of(text) == unit


def test_param_docs_and_attach_put_docs_on_the_function():
    @param_docs({"x": "goal x [m]"}, y="goal y [m]", returns="the pose")
    def goto(x, y):
        pass

    assert explicit(goto) == ({"x": "goal x [m]", "y": "goal y [m]"}, "the pose")
    attach(goto, {"y": "another y [m]"})
    assert explicit(goto) == ({"x": "goal x [m]", "y": "another y [m]"}, "the pose")
    assert explicit(lambda: None) == ({}, None)

    class Holder:
        @param_docs(n="how many")
        def count(self, n):
            pass

    assert explicit(Holder().count) == ({"n": "how many"}, None)  # bound methods read their function's
