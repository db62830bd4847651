"""The check: language: parse, evaluate, and fail with an offset. Never eval."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from bt_engine.trees import CheckEvaluationError, evaluate, parse_expression
from bt_engine.trees._expr import ExprSyntaxError, keys_of

BOARD = {
    "battery": 0.5,
    "count": 3,
    "name": "can",
    "found": {"category": "bottle", "pose": {"x": 1.0}},
    "robot": SimpleNamespace(mode="auto", _secret=1),
    "items": ["a", "b"],
    "flag": True,
    "nothing": None,
}


def lookup(key: str) -> object:
    return BOARD[key]


@pytest.mark.parametrize("source,expected", [
    ("battery > 0.2", True),
    ("battery >= 0.5 and count == 3", True),
    ("battery < 0.2 or count != 3", False),
    ("not flag", False),
    ("not not flag", True),
    ("found.category == 'bottle'", True),
    ('found.category in ["can", "bottle"]', True),
    ("name not in items", True),
    ("'a' in items", True),
    ("found.pose.x <= 1", True),
    ("robot.mode == \"auto\"", True),
    ("nothing == null", True),
    ("(count > 5 or flag) and battery > 0", True),
    ("count > -1", True),
    ("-count == -3", True),
    ("1e-3 < 0.01", True),
    ("count == 3.0", True),
    ("[1, 2,] == [1, 2]", True),
    ("flag", True),
    ("nothing", None),
    ("'it\\'s' == \"it's\"", True),
    ("true and false", False),
])
def test_evaluates(source: str, expected: object) -> None:
    assert evaluate(parse_expression(source), lookup) == expected


@pytest.mark.parametrize("source,offset,fragment", [
    ("", 0, "empty check expression"),
    ("battery >", 9, "expected a value"),
    ("(battery > 1", 12, "expected ')'"),
    ("a = 1", 2, "expected '=='"),
    ("a && b", 2, "expected 'and'"),
    ("a || b", 2, "expected 'or'"),
    ("!a", 0, "expected 'not'"),
    ("0 < a < 2", 6, "comparisons do not chain"),
    ("a b", 2, "expected an operator or the end"),
    ("'open", 0, "unterminated string"),
    ("a.", 2, "expected a field name"),
    ("robot._secret", 6, "private field"),
    ("__import__('os')", 0, "invalid key"),
    ("len(items)", 3, "expected an operator or the end"),
    ("items[0]", 5, "expected an operator or the end"),
    ("3x > 1", 0, "malformed number"),
    ("a ; b", 2, "unexpected character ';'"),
    ("[1, 2", 5, "expected ',' or ']'"),
    ("'\\q'", 1, "unknown escape"),
    ("a and", 5, "expected a value"),
    ("in", 0, "unexpected keyword 'in'"),
])
def test_syntax_errors_point_at_the_offending_character(source: str, offset: int, fragment: str) -> None:
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression(source)
    assert info.value.offset == offset
    assert fragment in info.value.message


@pytest.mark.parametrize("source,fragment", [
    ("missing > 1", "blackboard key 'missing' is not set"),
    ("found.colour == 1", "found has no field 'colour'"),
    ("robot.speed > 1", "robot has no field 'speed'"),
    ("name < 3", "cannot evaluate 'can' < 3 (str vs int)"),
    ("-name == 1", "cannot negate 'can'"),
])
def test_evaluation_errors(source: str, fragment: str) -> None:
    with pytest.raises(CheckEvaluationError, match=fragment.replace("(", r"\(").replace(")", r"\)")):
        evaluate(parse_expression(source), lookup)


def test_short_circuit_skips_unset_keys() -> None:
    assert evaluate(parse_expression("flag or missing"), lookup) is True
    assert evaluate(parse_expression("not flag and missing"), lookup) is False


def test_keys_are_reported_with_offsets() -> None:
    expr = parse_expression("battery > 0.2 and found.category in [name, 'x']")
    assert [(k.dotted, k.offset) for k in keys_of(expr)] == [
        ("battery", 0), ("found.category", 18), ("name", 37)]


def test_python_is_not_evaluated() -> None:
    # Things that would do something in Python are just syntax errors or plain keys here.
    for source in ("__import__('os').system('true')", "().__class__", "exec('1')", "lambda: 1"):
        with pytest.raises(ExprSyntaxError):
            parse_expression(source)
