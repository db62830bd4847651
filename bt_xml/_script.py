"""BehaviorTree.CPP scripts, translated into what actorbt missions say: assignments of
literals and keys become ``set:`` values, boolean expressions become ``check:``
expressions (the check: language of :mod:`bt_engine.trees`). Everything else (arithmetic, string
concatenation, bitwise operators, the ternary, compound assignment) is refused with a
located error: the check language deliberately has no arithmetic. Nothing is evaluated
here, and nothing ever reaches ``eval``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

from bt_engine.trees import ExprSyntaxError, Ref, keys_of, parse_expression
from ._errors import Pos, UnsupportedXmlError

__all__ = ["Assignment", "ScriptError", "condition", "statements"]

#: where character ``offset`` of the script text is in the file
Locate = Callable[[int], Pos]


class ScriptError(UnsupportedXmlError):
    """A script that cannot be translated."""


@dataclass(frozen=True)
class _Tok:
    kind: str  # num str name op kw end
    text: str
    value: Any
    offset: int


_TOKEN = re.compile(
    r"""
    (?P<ws>\s+)
  | (?P<num>0[xX][0-9a-fA-F]+
          | [0-9]+\.[0-9]*(?:[eE][+-]?[0-9]+)? | \.[0-9]+(?:[eE][+-]?[0-9]+)? | [0-9]+(?:[eE][+-]?[0-9]+)?)
  | (?P<str>'[^']*'|"[^"]*")
  | (?P<name>@?[A-Za-z_][A-Za-z0-9_]*)
  | (?P<op>:=|\+=|-=|\*=|/=|==|!=|<=|>=|&&|\|\||\.\.|[-+*/<>!()=;&|^~?:])
""",
    re.X,
)

_UNSUPPORTED = {
    "+": "arithmetic ('+')",
    "*": "arithmetic ('*')",
    "/": "arithmetic ('/')",
    "..": "string concatenation ('..')",
    "&": "bitwise '&'",
    "|": "bitwise '|'",
    "^": "bitwise '^'",
    "~": "bitwise '~'",
    "?": "the ternary '? :'",
    ":": "the ternary '? :'",
    "+=": "compound assignment ('+=')",
    "-=": "compound assignment ('-=')",
    "*=": "compound assignment ('*=')",
    "/=": "compound assignment ('/=')",
}
_WHY = "actorbt's check language has no arithmetic (docs/btxml.md); compute it in an actor"


def _tokens(text: str, locate: Locate) -> list[_Tok]:
    out: list[_Tok] = []
    i = 0
    while i < len(text):
        m = _TOKEN.match(text, i)
        if m is None:
            raise ScriptError(
                locate(i),
                f"unexpected character {text[i]!r} in script {text!r}, expected a BehaviorTree.CPP script expression",
            )
        kind = m.lastgroup
        tok = m.group()
        if kind == "num":
            value: Any = (
                int(tok, 16) if tok[:2] in ("0x", "0X") else (float(tok) if any(c in tok for c in ".eE") else int(tok))
            )
            out.append(_Tok("num", tok, value, i))
        elif kind == "str":
            out.append(_Tok("str", tok, tok[1:-1], i))
        elif kind == "name":
            if tok.startswith("@"):
                raise ScriptError(
                    locate(i),
                    f"{tok}: the root blackboard ('@' keys) is not supported, expected a "
                    "key of this tree (pass values between trees through SubTree ports)",
                )
            out.append(_Tok("kw" if tok in ("true", "false") else "name", tok, None, i))
        elif kind == "op":
            out.append(_Tok("op", tok, None, i))
        i = m.end()
    out.append(_Tok("end", "", None, len(text)))
    return out


def _split(tokens: list[_Tok]) -> list[list[_Tok]]:
    parts: list[list[_Tok]] = [[]]
    for tok in tokens[:-1]:
        if tok.kind == "op" and tok.text == ";":
            parts.append([])
        else:
            parts[-1].append(tok)
    return [p for p in parts if p]


@dataclass(frozen=True)
class Assignment:
    """``key := value``: a literal, or a :class:`Ref` to another key."""

    key: str
    value: Any


def _value(tokens: list[_Tok], text: str, locate: Locate) -> Any:
    """A literal or a key; anything else is refused."""
    if len(tokens) == 2 and tokens[0].text == "-" and tokens[1].kind == "num":
        return -tokens[1].value
    if len(tokens) == 1:
        tok = tokens[0]
        if tok.kind in ("num", "str"):
            return tok.value
        if tok.kind == "kw":
            return tok.text == "true"
        if tok.kind == "name":
            return Ref(tok.text, (), locate(tok.offset))
    bad = next((t for t in tokens if t.text in _UNSUPPORTED), tokens[0] if tokens else None)
    what = _UNSUPPORTED.get(bad.text, "an expression") if bad is not None else "nothing"
    raise ScriptError(
        locate(bad.offset if bad is not None else len(text)),
        f"cannot assign {what} in script {text!r}: only a literal or a key can be assigned, since {_WHY}",
    )


def statements(text: str, locate: Locate) -> list[Assignment | str]:
    """The statements of a Script: assignments, and conditions translated to the check
    language (as text).

    Raises:
        ScriptError: with the position of the part that cannot be translated.
    """
    result: list[Assignment | str] = []
    for part in _split(_tokens(text, locate)):
        if len(part) >= 2 and part[0].kind == "name" and part[1].kind == "op" and part[1].text in (":=", "="):
            result.append(Assignment(part[0].text, _value(part[2:], text, locate)))
        elif len(part) >= 2 and part[1].kind == "op" and part[1].text in _UNSUPPORTED:
            raise ScriptError(
                locate(part[1].offset),
                f"{_UNSUPPORTED[part[1].text]} in script {text!r} is not supported, since {_WHY}",
            )
        else:
            result.append(_translate(part, text, locate))
    return result


def condition(text: str, locate: Locate) -> str:
    """A BehaviorTree.CPP boolean expression as a check expression.

    Raises:
        ScriptError: assignments, several statements, or unsupported operators.
    """
    parts = statements(text, locate)
    if len(parts) != 1 or not isinstance(parts[0], str):
        raise ScriptError(locate(0), f"expected one condition (such as 'battery > 0.2 && ready'), got {text!r}")
    return parts[0]


_MAP = {"&&": "and", "||": "or", "!": "not"}


def _translate(tokens: list[_Tok], text: str, locate: Locate) -> str:
    out: list[str] = []
    origin: list[tuple[int, int]] = []  # (offset in output, offset in source)
    for tok in tokens:
        if tok.kind == "op" and tok.text in _UNSUPPORTED:
            raise ScriptError(
                locate(tok.offset), f"{_UNSUPPORTED[tok.text]} in {text!r} is not supported, since {_WHY}"
            )
        if tok.kind == "op" and tok.text in (":=", "="):
            raise ScriptError(
                locate(tok.offset),
                f"assignment inside an expression in {text!r}, expected "
                "'key := value' as a statement of its own, or '==' to compare",
            )
        if tok.kind == "str":
            piece = '"' + tok.value.replace("\\", "\\\\").replace('"', '\\"') + '"'
        elif tok.kind == "num":
            piece = repr(tok.value)
        else:
            piece = _MAP.get(tok.text, tok.text)
        origin.append((sum(len(p) + 1 for p in out), tok.offset))
        out.append(piece)
    result = " ".join(out)
    try:
        expr = parse_expression(result)
    except ExprSyntaxError as exc:
        source_offset = max((s for o, s in origin if o <= exc.offset), default=0)
        raise ScriptError(
            locate(source_offset), f"cannot translate {text!r} to a check expression: {exc.message}"
        ) from None
    for key in keys_of(expr):
        if key.name.startswith("_"):
            raise ScriptError(locate(0), f"key {key.name!r} in {text!r}: keys starting with '_' are not supported")
    return result
