"""The ``check:`` language: a small, safe comparison language over the blackboard.

Grammar (lowest precedence first)::

    expr       := or_expr
    or_expr    := and_expr ("or" and_expr)*
    and_expr   := not_expr ("and" not_expr)*
    not_expr   := "not" not_expr | comparison
    comparison := operand [ ("==" | "!=" | "<" | "<=" | ">" | ">=" | "in" | "not" "in") operand ]
    operand    := "-" operand | NUMBER | STRING | "true" | "false" | "null"
                | "[" [expr ("," expr)* [","]] "]" | "(" expr ")" | KEY
    KEY        := NAME ("." NAME)*        # blackboard key, then dict fields / attributes

Comparisons do not chain (``a < b < c`` is an error: write ``a < b and b < c``).
``and``/``or`` short-circuit and give booleans. The expression is parsed once, at load
time, into a small AST; evaluation walks that AST. Nothing is ever handed to ``eval``.

The parser, :func:`keys_of` and :func:`evaluate` recurse over the expression, so its
depth is limited: each ``(``, ``[``, ``not``, unary ``-`` and each ``and``/``or`` of a
chain is one level, at most :data:`MAX_EXPR_DEPTH`. Numbers have at most
:data:`MAX_NUMBER_DIGITS` digits.
"""

from __future__ import annotations

import operator
import re
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Union

from ._errors import CheckEvaluationError, shorten

__all__ = [
    "MAX_EXPR_DEPTH",
    "MAX_NUMBER_DIGITS",
    "And",
    "Compare",
    "Expr",
    "ExprSyntaxError",
    "Key",
    "ListExpr",
    "Literal",
    "Neg",
    "Not",
    "Or",
    "evaluate",
    "keys_of",
    "parse_expression",
]


class ExprSyntaxError(ValueError):
    """A check expression does not parse; ``offset`` is the 0-based character index.

    The mission parser turns it into a :class:`CheckExpressionError` at the file position.
    """

    def __init__(self, message: str, offset: int) -> None:
        super().__init__(message)
        self.message = message
        self.offset = offset


#: Deepest nesting of a check expression (see the module docstring for what counts).
#: The parser recurses about five frames per level; 64 keeps it and the evaluator far
#: below Python's recursion limit, and no sensible check comes near it.
MAX_EXPR_DEPTH = 64

#: Most digits in a number literal (Python refuses int <-> str past 4,300 digits).
MAX_NUMBER_DIGITS = 100

# ---------------------------------------------------------------- tokens

# ASCII digits with single '_' between them, as in Python; a fraction; an exponent.
_NUMBER = re.compile(
    r"[0-9](?:_?[0-9])*(?:\.[0-9](?:_?[0-9])*)?(?:[eE][+-]?[0-9](?:_?[0-9])*)?"
    r"|\.[0-9](?:_?[0-9])*(?:[eE][+-]?[0-9](?:_?[0-9])*)?"
)

_KEYWORDS = {"and", "or", "not", "in", "true", "false", "null"}
_OPERATORS = ("==", "!=", "<=", ">=", "<", ">", "(", ")", "[", "]", ",", ".", "-")


@dataclass(frozen=True)
class _Token:
    kind: str  # "num" "str" "name" "op" "kw" "end"
    text: str
    value: Any
    offset: int


def _tokenize(source: str) -> list[_Token]:
    tokens: list[_Token] = []
    i, n = 0, len(source)
    while i < n:
        c = source[i]
        if c in " \t\r\n":
            i += 1
            continue
        number = _NUMBER.match(source, i)
        if number is not None:
            tokens.append(_number_token(source, number))
            i = number.end()
            continue
        if c.isalpha() or c == "_":
            j = i
            while j < n and (source[j].isalnum() or source[j] == "_"):
                j += 1
            word = source[i:j]
            tokens.append(_Token("kw" if word in _KEYWORDS else "name", word, None, i))
            i = j
            continue
        if c in "\"'":
            value, j = _read_string(source, i)
            tokens.append(_Token("str", source[i:j], value, i))
            i = j
            continue
        for op in _OPERATORS:
            if source.startswith(op, i):
                tokens.append(_Token("op", op, None, i))
                i += len(op)
                break
        else:
            if c == "=":
                raise ExprSyntaxError("'=' is not an operator, expected '==' to compare", i)
            if source.startswith("&&", i) or source.startswith("||", i) or c == "!":
                word = {"&": "and", "|": "or", "!": "not"}[c]
                raise ExprSyntaxError(f"unexpected {source[i : i + 2].rstrip()!r}, expected {word!r}", i)
            raise ExprSyntaxError(f"unexpected character {c!r}", i)
    tokens.append(_Token("end", "", None, n))
    return tokens


def _number_token(source: str, number: re.Match[str]) -> _Token:
    i, j, text = number.start(), number.end(), number.group()
    if j < len(source) and (source[j].isalnum() or source[j] == "_"):
        raise ExprSyntaxError(f"malformed number {shorten(source[i : j + 1])}", i)
    if sum(c.isdigit() for c in text) > MAX_NUMBER_DIGITS:
        raise ExprSyntaxError(f"number longer than {MAX_NUMBER_DIGITS} digits, expected a shorter number", i)
    is_float = any(c in ".eE" for c in text)
    return _Token("num", text, float(text) if is_float else int(text), i)


_ESCAPES = {"n": "\n", "t": "\t", "r": "\r", "\\": "\\", "'": "'", '"': '"', "0": "\0"}


def _read_string(source: str, start: int) -> tuple[str, int]:
    quote = source[start]
    out: list[str] = []
    i = start + 1
    while i < len(source):
        c = source[i]
        if c == quote:
            return "".join(out), i + 1
        if c == "\\":
            if i + 1 >= len(source):
                break
            esc = source[i + 1]
            if esc not in _ESCAPES:
                raise ExprSyntaxError(f"unknown escape '\\{esc}' in string", i)
            out.append(_ESCAPES[esc])
            i += 2
            continue
        out.append(c)
        i += 1
    raise ExprSyntaxError(f"unterminated string, expected a closing {quote}", start)


# ---------------------------------------------------------------- AST


@dataclass(frozen=True)
class Literal:
    """A constant: number, string, boolean or null."""

    value: Any
    offset: int


@dataclass(frozen=True)
class Key:
    """A blackboard key, then dict fields or attributes: ``found.category``."""

    name: str
    fields: tuple[str, ...]
    offset: int

    @property
    def dotted(self) -> str:
        return ".".join((self.name, *self.fields))


@dataclass(frozen=True)
class ListExpr:
    """A list display ``[a, b, 3]``."""

    items: tuple[Expr, ...]
    offset: int


@dataclass(frozen=True)
class Neg:
    """Unary minus."""

    operand: Expr
    offset: int


@dataclass(frozen=True)
class Not:
    """Boolean negation."""

    operand: Expr
    offset: int


@dataclass(frozen=True)
class And:
    """Short-circuit conjunction."""

    left: Expr
    right: Expr
    offset: int


@dataclass(frozen=True)
class Or:
    """Short-circuit disjunction."""

    left: Expr
    right: Expr
    offset: int


@dataclass(frozen=True)
class Compare:
    """One comparison: ``op`` is one of == != < <= > >= in, not in."""

    op: str
    left: Expr
    right: Expr
    offset: int


Expr = Union[Literal, Key, ListExpr, Neg, Not, And, Or, Compare]

_COMPARE_OPS = {"==", "!=", "<", "<=", ">", ">="}


class _Parser:
    def __init__(self, source: str) -> None:
        self.source = source
        self.tokens = _tokenize(source)
        self.i = 0
        self.depth = 0  # levels open on the way to the current token

    def deeper(self, tok: _Token) -> None:
        """Open one more level at ``tok``; the caller closes it by restoring ``depth``."""
        self.depth += 1
        if self.depth > MAX_EXPR_DEPTH:
            raise ExprSyntaxError(
                f"expression nested deeper than {MAX_EXPR_DEPTH} levels, expected a flatter expression "
                "(split it into several check: nodes)",
                tok.offset,
            )

    @property
    def tok(self) -> _Token:
        return self.tokens[self.i]

    def advance(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def at(self, kind: str, text: str | None = None) -> bool:
        tok = self.tok
        return tok.kind == kind and (text is None or tok.text == text)

    def describe(self, tok: _Token) -> str:
        return "end of expression" if tok.kind == "end" else shorten(tok.text)

    def expect(self, kind: str, text: str, what: str) -> _Token:
        if not self.at(kind, text):
            raise ExprSyntaxError(f"unexpected {self.describe(self.tok)}, expected {what}", self.tok.offset)
        return self.advance()

    def parse(self) -> Expr:
        if self.at("end"):
            raise ExprSyntaxError("empty check expression, expected e.g. 'battery > 0.2'", 0)
        expr = self.or_expr()
        if not self.at("end"):
            tok = self.tok
            if tok.kind == "op" and tok.text in _COMPARE_OPS or tok.kind == "kw" and tok.text in ("in", "not"):
                raise ExprSyntaxError("comparisons do not chain, expected 'and' between two comparisons", tok.offset)
            raise ExprSyntaxError(f"unexpected {self.describe(tok)}, expected an operator or the end", tok.offset)
        return expr

    def or_expr(self) -> Expr:
        depth = self.depth
        left = self.and_expr()
        while self.at("kw", "or"):
            tok = self.advance()
            self.deeper(tok)  # a chain nests to the left: Or(Or(a, b), c)
            left = Or(left, self.and_expr(), tok.offset)
        self.depth = depth
        return left

    def and_expr(self) -> Expr:
        depth = self.depth
        left = self.not_expr()
        while self.at("kw", "and"):
            tok = self.advance()
            self.deeper(tok)
            left = And(left, self.not_expr(), tok.offset)
        self.depth = depth
        return left

    def not_expr(self) -> Expr:
        if self.at("kw", "not"):
            tok = self.advance()
            self.deeper(tok)
            operand = self.not_expr()
            self.depth -= 1
            return Not(operand, tok.offset)
        return self.comparison()

    def comparison(self) -> Expr:
        left = self.operand()
        tok = self.tok
        if tok.kind == "op" and tok.text in _COMPARE_OPS:
            self.advance()
            return Compare(tok.text, left, self.operand(), tok.offset)
        if self.at("kw", "in"):
            self.advance()
            return Compare("in", left, self.operand(), tok.offset)
        if self.at("kw", "not") and self.tokens[self.i + 1].kind == "kw" and self.tokens[self.i + 1].text == "in":
            self.advance()
            self.advance()
            return Compare("not in", left, self.operand(), tok.offset)
        return left

    def operand(self) -> Expr:
        tok = self.tok
        if tok.kind == "op" and tok.text in ("-", "(", "["):
            self.advance()
            self.deeper(tok)
            inner = self.nested(tok)
            self.depth -= 1
            return inner
        if tok.kind in ("num", "str"):
            self.advance()
            return Literal(tok.value, tok.offset)
        if tok.kind == "kw" and tok.text in ("true", "false", "null"):
            self.advance()
            return Literal({"true": True, "false": False, "null": None}[tok.text], tok.offset)
        if tok.kind == "name":
            self.advance()
            fields: list[str] = []
            while self.at("op", "."):
                self.advance()
                field = self.tok
                if field.kind not in ("name", "kw"):
                    raise ExprSyntaxError(
                        f"unexpected {self.describe(field)}, expected a field name after '.'", field.offset
                    )
                if field.text.startswith("_"):
                    raise ExprSyntaxError(
                        f"private field {shorten(field.text)}, expected a public field name", field.offset
                    )
                self.advance()
                fields.append(field.text)
            if tok.text.startswith("__"):
                raise ExprSyntaxError(f"invalid key {shorten(tok.text)}, expected a blackboard key", tok.offset)
            return Key(tok.text, tuple(fields), tok.offset)
        if tok.kind == "kw":
            raise ExprSyntaxError(f"unexpected keyword {tok.text!r}, expected a value", tok.offset)
        raise ExprSyntaxError(
            f"unexpected {self.describe(tok)}, expected a value (number, string, key, list)", tok.offset
        )

    def nested(self, tok: _Token) -> Expr:
        """What follows an opening ``-``, ``(`` or ``[`` (already consumed)."""
        if tok.text == "-":
            return Neg(self.operand(), tok.offset)
        if tok.text == "(":
            inner = self.or_expr()
            self.expect("op", ")", "')' to close the '('")
            return inner
        items: list[Expr] = []
        while not self.at("op", "]"):
            items.append(self.or_expr())
            if not self.at("op", ","):
                break
            self.advance()
        self.expect("op", "]", "',' or ']' to close the list")
        return ListExpr(tuple(items), tok.offset)


def parse_expression(source: str) -> Expr:
    """Parse a check expression.

    Raises:
        ExprSyntaxError: with a message and the offset of the offending character.
    """
    return _Parser(source).parse()


def keys_of(expr: Expr) -> Iterator[Key]:
    """Every blackboard key the expression reads, in source order."""
    if isinstance(expr, Key):
        yield expr
    elif isinstance(expr, ListExpr):
        for item in expr.items:
            yield from keys_of(item)
    elif isinstance(expr, (Neg, Not)):
        yield from keys_of(expr.operand)
    elif isinstance(expr, (And, Or, Compare)):
        yield from keys_of(expr.left)
        yield from keys_of(expr.right)


# ---------------------------------------------------------------- evaluation

_MISSING = object()

_BINARY: dict[str, Callable[[Any, Any], Any]] = {
    "==": operator.eq,
    "!=": operator.ne,
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "in": lambda a, b: a in b,
    "not in": lambda a, b: a not in b,
}


def field_of(value: Any, field: str) -> Any:
    """``value[field]`` for a mapping, else the public attribute ``value.field``.

    Raises:
        KeyError: the field does not exist.
    """
    if isinstance(value, dict):
        if field in value:
            return value[field]
        raise KeyError(field)
    if field.startswith("_"):
        raise KeyError(field)
    result = getattr(value, field, _MISSING)
    if result is _MISSING:
        raise KeyError(field)
    return result


def read_path(lookup: Callable[[str], Any], key: str, fields: tuple[str, ...]) -> Any:
    """The value at ``key.field.field`` on the blackboard; ``lookup`` raises KeyError for
    unset keys.

    Raises:
        KeyError: the key is unset or a field is missing; its message names which.
    """
    try:
        value = lookup(key)
    except KeyError:
        raise KeyError(f"blackboard key {key!r} is not set") from None
    for i, field in enumerate(fields):
        try:
            value = field_of(value, field)
        except KeyError:
            where = ".".join((key, *fields[:i]))
            raise KeyError(f"{where} has no field {field!r} (it is {type(value).__name__})") from None
    return value


def evaluate(expr: Expr, lookup: Callable[[str], Any]) -> Any:
    """Evaluate ``expr``; ``lookup(key)`` reads the blackboard and raises KeyError if unset.

    Raises:
        CheckEvaluationError: an unset key, a missing field, or values that do not compare.
    """
    if isinstance(expr, Literal):
        return expr.value
    if isinstance(expr, Key):
        try:
            return read_path(lookup, expr.name, expr.fields)
        except KeyError as e:
            raise CheckEvaluationError(e.args[0]) from None
    if isinstance(expr, ListExpr):
        return [evaluate(item, lookup) for item in expr.items]
    if isinstance(expr, Neg):
        value = evaluate(expr.operand, lookup)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise CheckEvaluationError(f"cannot negate {value!r}, expected a number")
        return -value
    if isinstance(expr, Not):
        return not evaluate(expr.operand, lookup)
    if isinstance(expr, And):
        return bool(evaluate(expr.left, lookup)) and bool(evaluate(expr.right, lookup))
    if isinstance(expr, Or):
        return bool(evaluate(expr.left, lookup)) or bool(evaluate(expr.right, lookup))
    if isinstance(expr, Compare):
        left = evaluate(expr.left, lookup)
        right = evaluate(expr.right, lookup)
        try:
            return bool(_BINARY[expr.op](left, right))
        except TypeError:
            raise CheckEvaluationError(
                f"cannot evaluate {left!r} {expr.op} {right!r} ({type(left).__name__} vs {type(right).__name__})"
            ) from None
    raise TypeError(f"not an expression: {expr!r}")  # pragma: no cover
