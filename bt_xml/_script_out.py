"""Missions' ``check:`` and ``set:`` written as BehaviorTree.CPP scripts, when a script
says exactly the same: the text is read back with the importer's own translation
(:mod:`._script`) and kept only if it gives the same expression (and, for a node
without a name, the same text, which is its label) or the same assignments. Otherwise
the exporter uses actorbt's own nodes (:mod:`._extensions`)."""

from __future__ import annotations

import re

from bt_engine.trees import (
    And,
    Check,
    Compare,
    Expr,
    ExprSyntaxError,
    Key,
    Literal,
    Neg,
    Not,
    Or,
    Ref,
    SetValues,
    parse_expression,
)
from ._compare import expr_shape
from ._errors import Pos
from ._script import Assignment, ScriptError, condition, statements
from ._values import _plain_text, same_value

__all__ = ["check_script", "set_script"]

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_KEYWORDS = ("true", "false")
_HERE = Pos("<export>", 1, 1)
# binding strength in BehaviorTree.CPP scripts: || < && < comparisons < unary ! and -
_OR, _AND, _CMP, _ATOM = 1, 2, 3, 4


def _string(text: str) -> str | None:
    if any(c in text for c in "\n\r\t"):
        return None
    if "'" not in text:
        return f"'{text}'"
    if '"' not in text:
        return f'"{text}"'
    return None


def _literal(value: object) -> str | None:
    """A value as a script literal: a string quoted, anything else as in an attribute."""
    if isinstance(value, str):
        return _string(value)
    return _plain_text(value)


def _print(expr: Expr, need: int) -> str | None:
    """The expression as script text, parenthesised when it binds weaker than ``need``."""
    if isinstance(expr, Literal):
        return _literal(expr.value)
    if isinstance(expr, Key):
        return expr.name if not expr.fields and expr.name not in _KEYWORDS else None
    if isinstance(expr, Neg):
        inner = _print(expr.operand, _ATOM)
        return None if inner is None else "-" + inner
    if isinstance(expr, Not):
        inner = _print(expr.operand, _ATOM)
        return None if inner is None else "!" + inner
    if isinstance(expr, (And, Or)):
        strength = _AND if isinstance(expr, And) else _OR
        left = _print(expr.left, strength)
        right = _print(expr.right, strength + 1)
        if left is None or right is None:
            return None
        text = f"{left} {'&&' if strength == _AND else '||'} {right}"
    elif isinstance(expr, Compare) and expr.op not in ("in", "not in"):
        left, right = _print(expr.left, _ATOM), _print(expr.right, _ATOM)
        if left is None or right is None:
            return None
        text, strength = f"{left} {expr.op} {right}", _CMP
    else:
        return None  # lists, `in`, null
    return text if strength >= need else f"({text})"


def check_script(node: Check) -> str | None:
    """A ScriptCondition ``code`` for the check, or None when no script says it exactly."""
    script = _print(node.expr, _OR)
    if script is None:
        return None
    try:
        back = condition(script, lambda _offset: _HERE)
        same = expr_shape(parse_expression(back)) == expr_shape(node.expr)
    except (ScriptError, ExprSyntaxError):
        return None
    if not same or node.name is None and back != node.source:
        return None
    return script


def set_script(node: SetValues) -> str | None:
    """A Script ``code`` that assigns the same values, or None: a script assigns literals
    and plain keys only, and must not read a key the same node writes."""
    parts = []
    for key, value in node.values.items():
        if not _NAME.match(key) or key in _KEYWORDS:
            return None
        if isinstance(value, Ref):
            if value.fields or value.key in node.values or value.key in _KEYWORDS:
                return None
            text = value.key
        else:
            literal = _literal(value)
            if literal is None:
                return None
            text = literal
        parts.append(f"{key} := {text}")
    script = "; ".join(parts)
    try:
        back = statements(script, lambda _offset: _HERE)
    except ScriptError:
        return None
    if len(back) != len(node.values) or not all(
        isinstance(s, Assignment) and s.key == key and same_value(s.value, value)
        for s, (key, value) in zip(back, node.values.items())
    ):
        return None
    return script
