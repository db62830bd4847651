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


@pytest.mark.parametrize(
    "source,expected",
    [
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
        ('robot.mode == "auto"', True),
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
    ],
)
def test_evaluates(source: str, expected: object) -> None:
    assert evaluate(parse_expression(source), lookup) == expected


@pytest.mark.parametrize(
    "source,offset,fragment",
    [
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
    ],
)
def test_syntax_errors_point_at_the_offending_character(source: str, offset: int, fragment: str) -> None:
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression(source)
    assert info.value.offset == offset
    assert fragment in info.value.message


@pytest.mark.parametrize(
    "source,fragment",
    [
        ("missing > 1", "blackboard key 'missing' is not set"),
        ("found.colour == 1", "found has no field 'colour'"),
        ("robot.speed > 1", "robot has no field 'speed'"),
        ("name < 3", "cannot evaluate 'can' < 3 (str vs int)"),
        ("-name == 1", "cannot negate 'can'"),
    ],
)
def test_evaluation_errors(source: str, fragment: str) -> None:
    with pytest.raises(CheckEvaluationError, match=fragment.replace("(", r"\(").replace(")", r"\)")):
        evaluate(parse_expression(source), lookup)


def test_short_circuit_skips_unset_keys() -> None:
    assert evaluate(parse_expression("flag or missing"), lookup) is True
    assert evaluate(parse_expression("not flag and missing"), lookup) is False


def test_keys_are_reported_with_offsets() -> None:
    expr = parse_expression("battery > 0.2 and found.category in [name, 'x']")
    assert [(k.dotted, k.offset) for k in keys_of(expr)] == [("battery", 0), ("found.category", 18), ("name", 37)]


def test_python_is_not_evaluated() -> None:
    # Things that would do something in Python are just syntax errors or plain keys here.
    for source in ("__import__('os').system('true')", "().__class__", "exec('1')", "lambda: 1"):
        with pytest.raises(ExprSyntaxError):
            parse_expression(source)


# ---------------------------------------------------------------- limits (issue core-2)

from bt_engine.trees import CheckExpressionError, parse_mission  # noqa: E402
from bt_engine.trees._expr import MAX_EXPR_DEPTH, MAX_NUMBER_DIGITS  # noqa: E402

# name -> (expression n levels deep, offset of the opener of level n)
NESTINGS = {
    "parentheses": (lambda n: "(" * n + "1" + ")" * n + " > 0", lambda n: n - 1),
    "not": (lambda n: "not " * n + "flag", lambda n: 4 * (n - 1)),
    "unary minus": (lambda n: "-" * n + "count > 0", lambda n: n - 1),
    "lists": (lambda n: "[" * n + "]" * n + " == []", lambda n: n - 1),
    "or chain": (lambda n: "flag or " * n + "flag", lambda n: 8 * n - 3),
    "and chain": (lambda n: "flag and " * n + "flag", lambda n: 9 * n - 4),
}


@pytest.mark.parametrize("shape", NESTINGS)
def test_nesting_up_to_the_limit_parses_and_evaluates(shape: str) -> None:
    build, _ = NESTINGS[shape]
    expr = parse_expression(build(MAX_EXPR_DEPTH))
    evaluate(expr, lookup)
    list(keys_of(expr))


@pytest.mark.parametrize("shape", NESTINGS)
def test_nesting_past_the_limit_names_it_and_points_at_the_level_past_it(shape: str) -> None:
    build, opener = NESTINGS[shape]
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression(build(MAX_EXPR_DEPTH + 1))
    assert f"expression nested deeper than {MAX_EXPR_DEPTH} levels" in info.value.message
    assert info.value.offset == opener(MAX_EXPR_DEPTH + 1)


@pytest.mark.parametrize(
    "source",
    [
        "(" * 5000 + "1" + ")" * 5000 + " > 0",
        "not " * 5000 + "flag",
        "-" * 5000 + "1 > 0",
        "[" * 5000,
        "flag or " * 5000 + "flag",
        "(not -" * 2000 + "1",
    ],
)
def test_thousands_of_levels_are_a_syntax_error_not_a_recursion_error(source: str) -> None:
    with pytest.raises(ExprSyntaxError, match="nested deeper than"):
        parse_expression(source)


def test_numbers_up_to_the_digit_limit_parse() -> None:
    assert evaluate(parse_expression("9" * MAX_NUMBER_DIGITS + " > 1"), lookup) is True


@pytest.mark.parametrize(
    "source,offset",
    [
        ("9" * (MAX_NUMBER_DIGITS + 1) + " > 1", 0),
        ("count > " + "9" * 5000, 8),  # past Python's 4,300-digit int conversion limit
        ("count < 1." + "5" * 5000, 8),
    ],
)
def test_number_literals_past_the_digit_limit_name_it(source: str, offset: int) -> None:
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression(source)
    assert info.value.message == f"number longer than {MAX_NUMBER_DIGITS} digits, expected a shorter number"
    assert info.value.offset == offset


@pytest.mark.parametrize("source,value", [("1_000 == 1000", True), ("0.000_1 < 1", True), ("1e1_0 > 1", True)])
def test_underscores_between_digits_are_fine(source: str, value: bool) -> None:
    assert evaluate(parse_expression(source), lookup) is value


@pytest.mark.parametrize(
    "source,offset,fragment",
    [
        ("1__0 > 1", 0, "malformed number '1_'"),
        ("count > 1_", 8, "malformed number '1_'"),
        ("1_.5 > 0", 0, "malformed number '1_'"),
        ("1.5_ > 0", 0, "malformed number '1.5_'"),
        ("\u00b2 > 1", 0, "unexpected character '\u00b2'"),  # isdigit() but not a number int() reads
        ("\u0663 > 1", 0, "unexpected character '\u0663'"),  # only ASCII digits are numbers
    ],
)
def test_malformed_numbers_are_syntax_errors_not_value_errors(source: str, offset: int, fragment: str) -> None:
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression(source)
    assert (info.value.offset, fragment in info.value.message) == (offset, True), info.value.message


def test_long_tokens_are_shortened_in_messages() -> None:
    with pytest.raises(ExprSyntaxError) as info:
        parse_expression("a " + "b" * 5000)
    assert len(info.value.message) < 120 and "'bbbb" in info.value.message


def test_deep_check_in_a_mission_points_at_the_file_position() -> None:
    depth = MAX_EXPR_DEPTH + 1
    text = "name: deep\nroot:\n  check: '" + "(" * depth + "1" + ")" * depth + " > 0'\n"
    with pytest.raises(CheckExpressionError) as info:
        parse_mission(text, "deep.yaml")
    # line 3; the expression starts at column 11, the 65th '(' is 64 further along
    assert str(info.value).startswith(
        f"deep.yaml:3:{11 + MAX_EXPR_DEPTH}: bad check expression: "
        f"expression nested deeper than {MAX_EXPR_DEPTH} levels"
    )


def test_huge_number_in_a_mission_check_points_at_it() -> None:
    with pytest.raises(CheckExpressionError) as info:
        parse_mission("name: n\nroot: {check: 'flag > " + "9" * 5000 + "'}\n", "n.yaml")
    assert str(info.value).startswith(
        f"n.yaml:2:23: bad check expression: number longer than {MAX_NUMBER_DIGITS} digits"
    )
