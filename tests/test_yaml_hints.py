"""Plain-words advice for YAML syntax errors (bt_engine.yaml_hints)."""

from __future__ import annotations

import pytest
import yaml

from bt_engine.yaml_hints import GENERAL_HINT, syntax_hint, syntax_mark, syntax_message


def error_of(text: str) -> yaml.MarkedYAMLError:
    with pytest.raises(yaml.MarkedYAMLError) as caught:
        yaml.safe_load(text)
    return caught.value


@pytest.mark.parametrize(
    "text, advice",
    [
        # a list item out of line with its list
        ("root:\n  children:\n    - a\n  - b\n", "check the indentation of this line against the line above"),
        ("a:\n  - x\n  - y\n - z\n", "'-' items of one list start in the same column"),
        # a key out of line with its mapping
        ("a:\n    b: 1\n  c: 2\n", "the keys of one mapping start in the same column"),
        ("a:\n  b: 1\n   c: 2\n", "check its indentation"),
        # a second ':' in a value
        ("a: b: c\n", "put the value in quotes"),
        # tabs
        ("a:\n\tb: 1\n", "replace the tab on this line with spaces"),
        # an unclosed quote, bracket or brace
        ('a: "hello\nb: 2\n', "the quoted text opened at line 1 is never closed"),
        ("a: [1, 2\nb: 3\n", "the [list] opened at line 1 is not closed"),
        ("a: {x: 1\nb: 3\n", "the {mapping} opened at line 1 is not closed"),
        # characters that cannot start a plain value
        ("a: @foo\n", "cannot start with '@'"),
        ("a: `foo`\n", "cannot start with '`'"),
        ("a: *x\n", "'*' starts an alias"),
        # the text ends inside a value
        ("a: [", "the text ends inside a value"),
        # text after a quoted value
        ('a: "x" y\n', "quote the whole value"),
    ],
)
def test_the_likely_fix_is_said_in_plain_words(text, advice):
    exc = error_of(text)
    assert advice in syntax_hint(exc)
    message = syntax_message(exc)
    assert message.startswith("YAML syntax error: ")
    assert message.endswith(syntax_hint(exc))
    # the parser's token names are said in words
    assert not any(
        jargon in message
        for jargon in ("'?'", "<block end>", "<stream end>", "<scalar>", "while parsing", "while scanning")
    )


@pytest.mark.parametrize(
    "text, words",
    [
        ("root:\n  - do: sleep\n  with: [1]\n", "a key where the end of the block above was expected"),
        ("a: {x: 1\n", "the end of the text where ',' or '}' was expected"),
        ("a: b: c\n", "a ':' after a value"),
        ("a:\n\tb: 1\n", "a tab character"),
        ('a: "x\n', "the text ends inside a quoted value"),
        ("a: @x\n", "'@' cannot start a value"),
    ],
)
def test_what_the_parser_met_is_said_in_words(text, words):
    assert syntax_message(error_of(text)).startswith(f"YAML syntax error: {words}; ")


def test_every_error_gets_some_advice():
    exc = error_of("a: |\n b\nc\n")
    assert syntax_hint(exc)  # a specific rule or the general one
    assert GENERAL_HINT.startswith("check this line")


def test_an_unclosed_quote_points_where_it_opens():
    exc = error_of("a: 1\nb: 'hello\nc: 2\nd: 3\n")
    mark = syntax_mark(exc)
    assert (mark.line + 1, mark.column + 1) == (2, 4)
    exc = error_of("a:\n  - x\n - y\n")
    assert syntax_mark(exc) is exc.problem_mark
